"""Which of SimMeR's modules are its public API, as data: the one place that says so.

The public modules are the ones users import: each lists exactly its public names in
``__all__``, and docs/api.md is generated from them (``python scripts/api_docs.py``). Every
other module is internal and may change in any release, as may the modules inside a public
package (``simmer.devices.base``, ``simmer.sweep.runs``): import from the package.
``tests/repository/test_api.py`` pins the names and keeps this list whole.
"""

from __future__ import annotations

PUBLIC = (
    "simmer",
    "simmer.client",
    "simmer.devices",
    "simmer.ending",
    "simmer.errors",
    "simmer.pose",
    "simmer.record",
    "simmer.sweep",
    "simmer.batch",
    "simmer.gym",
)
"""The modules users import, in the order docs/api.md shows them."""

INTERNAL = (
    "simmer.__main__",
    "simmer._api",
    "simmer.calibrate",
    "simmer.cli",
    "simmer.clock",
    "simmer.colors",
    "simmer.compat",
    "simmer.config",
    "simmer.console",
    "simmer.geometry",
    "simmer.grade",
    "simmer.lazy",
    "simmer.localize",
    "simmer.lockstep",
    "simmer.newfolder",
    "simmer.options",
    "simmer.ports",
    "simmer.proctree",
    "simmer.protocol",
    "simmer.runner",
    "simmer.scene",
    "simmer.serve",
    "simmer.tap",
    "simmer.transport",
    "simmer.ui",
    "simmer.untrusted",
    "simmer.view",
    "simmer.warmup",
    "simmer.world",
)
"""The modules and packages (with everything in them) that are internal: they may change."""

FROM_INTERNAL = {
    "simmer": ("SimConfig", "Simulation", "load_config", "replay", "with_overrides"),
    "simmer.devices": ("heading_vector",),
    "simmer.sweep": ("apply_overrides",),
}
"""Public names a public module takes from an internal one on purpose (by module): what a
user needs from there, given where users look for it."""
