"""Compile every Numba kernel SimMeR runs, or load it from Numba's cache: the simulation's
step and sensors, the expected readings, a LiDAR's scans and table, the batch simulator and
the particle filter's model (with noise on and off).

``scripts/setup.py`` runs it once after installing (``python -m simmer.warmup``), so neither a
student's first run or first ``simmer.batch`` call nor each of the test suite's workers pays
the compile (about 15 s of CPU in all on a fresh install; a second of loading afterwards)."""

from __future__ import annotations

import numpy as np

__all__ = ["compile_kernels"]


def compile_kernels() -> None:
    """Run each kernel once on the built-in default rover (with a LiDAR and the lab's noise
    added where a kernel has a path of its own for them)."""
    from simmer.batch import Batch, Model
    from simmer.config import load_config, with_overrides
    from simmer.runner import LocalLink
    from simmer.world import Simulation

    default = load_config(None)
    link = LocalLink(Simulation(default))
    link.exchange("u0,u1,u2,u3")
    link.exchange("w0-1")
    link.clock("!idle")
    poses = np.array([[12.0, 12.0, 0.0], [14.0, 12.0, 90.0]])
    Simulation(default).expected(poses[:1])
    lidar = {"sensors.l0": {"type": "lidar", "position": [0, -1, 7]}}
    scanning = Simulation(with_overrides(default, lidar))
    scanning.expected(poses[:1], ["l0"])
    scanning.step()  # a scan with the A1M8's noise: its normals' kernel
    Batch(None, [0]).command(["w0-1"])
    model = Model(None)
    model.read(model.move(poses, "w0", 1.0), np.random.default_rng(0))
    noise = {
        "sensors.*.error": 0.05,
        "drives.w0.error": {"x": 0.02, "y": 0.05, "rotation": 1},
        "drives.w0.bias": {"rotation": 0.2},
    }
    noisy = Model(with_overrides(default, noise))
    noisy.expected(noisy.move(poses, "w0", 1.0))
    rng = np.random.default_rng(0)
    noisy.read(noisy.move(poses, "w0", 1.0, rng), rng)


if __name__ == "__main__":
    compile_kernels()
