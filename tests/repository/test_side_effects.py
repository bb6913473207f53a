"""Importing SimMeR and checking a configuration change nothing process-wide: no finder on
``sys.meta_path``, no plug-in module left in ``sys.modules``, no kind added to the registry
(issue 29: validation without side effects). Checked in a fresh interpreter, so nothing
another test imported counts."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

CHECK = """\
import json, sys
from pathlib import Path

finders = [repr(finder) for finder in sys.meta_path]
import simmer.devices
from simmer.devices import registry
after_import = [repr(finder) for finder in sys.meta_path]
modules = set(sys.modules)
kinds = dict(registry._KINDS)

from simmer.config.loader import load_config
config = load_config(Path(sys.argv[1]))
print(json.dumps({
    "meta_path": [finders, after_import, [repr(finder) for finder in sys.meta_path]],
    "new_modules": sorted(
        name for name in set(sys.modules) - modules
        if name.startswith("simmer_plugin_") or name == "bumper"
    ),
    "registry_changed": dict(registry._KINDS) != kinds,
    "kind": config.device("b0").kind,
}))
"""

BUMPER = """\
from simmer.devices import Device, World, register_device_kind


class Bumper(Device):
    def simulate(self, value: float, world: World) -> float:
        return 0.0


register_device_kind("test_bumper", Bumper)
"""


@pytest.mark.slow  # a fresh interpreter imports SimMeR
def test_importing_devices_and_validating_a_plugin_leave_the_process_as_it_was(
    tmp_path: Path,
) -> None:
    (tmp_path / "bumper.py").write_text(BUMPER, encoding="utf-8")
    config = tmp_path / "robot.toml"
    config.write_text('plugins = ["bumper.py"]\n\n[sensors.b0]\ntype = "test_bumper"\n')
    done = subprocess.run(
        [sys.executable, "-c", CHECK, str(config)],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    assert seen["kind"] == "test_bumper"
    before, after_import, after_check = seen["meta_path"]
    assert after_import == before
    assert after_check == before
    assert seen["new_modules"] == []
    assert seen["registry_changed"] is False
