"""Call every device of a configuration once, so ``simmer check`` finds faulty device code.

Validation checks a configuration's settings; it cannot see that a device class calls a helper
that does not exist. :func:`probe_devices` builds a throwaway simulation and calls each device
as a run would (``update``, a plain read, ``shapes``), turning every exception into a
:class:`~simmer.errors.ConfigIssue` that names the file and line of the student's own code.
"""

from __future__ import annotations

from contextlib import suppress
from pathlib import Path

import numpy as np

from simmer.config.models import DeviceSpec, SimConfig
from simmer.errors import CommandError, ConfigIssue, describe_exception
from simmer.world.simulation import Simulation

DEVICE_FAULTS = (Exception, SystemExit)
"""What a device's code may raise that ``check`` reports rather than stopping on: any error,
and ``sys.exit()``."""


def _hint(exc: BaseException) -> str:
    """What to do about an exception raised by a device's code."""
    if isinstance(exc, AttributeError | NameError):
        what = "a name used on that line does not exist: check its spelling and that it is "
        what += "defined (or imported) in your device file"
    else:
        what = "fix the code on that line"
    return f"{what}; run unfixed, the device is switched off and its commands answer NaN"


def _issue(spec: DeviceSpec, action: str, exc: BaseException, base: Path | None) -> ConfigIssue:
    return ConfigIssue(
        f"{spec.group}.{spec.id}",
        f"{action} raised {describe_exception(exc, base)}; {_hint(exc)}",
    )


def probe_devices(config: SimConfig) -> list[ConfigIssue]:
    """Build a throwaway simulation of a validated ``config`` and call each device once.

    Every device gets ``update`` once; every device except drives (a command would start motion)
    gets ``simulate(0.0)``, a plain read, then ``shapes``. The first exception of each device
    becomes one issue on its key (``sensors.t0``). A :class:`~simmer.errors.CommandError` from
    ``simulate`` is the device refusing a value, which is allowed, so it is not reported.
    """
    source = Path(config.source)
    base = source.parent if source.is_file() else None
    try:
        sim = Simulation(config)
    except DEVICE_FAULTS as exc:
        return _construction_issues(config, base) or [
            ConfigIssue("", f"building the simulation raised {describe_exception(exc, base)}")
        ]
    issues = []
    for spec in config.devices:
        device = sim.robot.devices[spec.id]
        action = "update()"
        try:
            device.update(sim)
            if device.category != "drive":
                action = "simulate(0.0)"
                with suppress(CommandError):  # refusing a value is the device's right
                    device.simulate(0.0, sim)
                action = "shapes()"
                device.shapes(sim)
        except DEVICE_FAULTS as exc:
            issues.append(_issue(spec, action, exc, base))
    return issues


def _construction_issues(config: SimConfig, base: Path | None) -> list[ConfigIssue]:
    """Build each device on its own, to say which one's constructor raises."""
    issues = []
    for spec in config.devices:
        kind = config.kinds.get(spec.kind)
        if kind is None:
            continue  # the simulation's own error says so
        try:
            kind(spec.id, spec.params, np.random.default_rng(0))
        except DEVICE_FAULTS as exc:
            issues.append(_issue(spec, "building the device", exc, base))
    return issues
