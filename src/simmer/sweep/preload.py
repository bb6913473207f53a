"""Imported once by a Linux sweep's fork server (:func:`simmer.sweep.engine.local_pool`): what
a worker runs, with Numba's compiled functions loaded by a short run of the default robot, so
that each worker forked from the server starts with all of it instead of importing and loading
it again (about a second of CPU a worker). Importing it has that effect and no other."""

import simmer.sweep.runs  # noqa: F401  (what a worker runs)
from simmer.world import Simulation

_warm = Simulation.from_config()
_warm.command("w0-1,u0,u1,u2,u3")
_warm.step()
del _warm
