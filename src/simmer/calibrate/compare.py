"""``simmer compare``: does my simulator match my robot? The real readings of a tap's run
against the band the simulator predicts for them, over many seeds.

The simulator is driven through the run's command sequence once per seed: each message at the
time the tap saw it (wall seconds since the tap started, as simulated seconds), except that a
drive the robot accepted while the simulated one still moves first waits for it (the real
robot had finished: its reply says so). Every sensor reading the robot replied is set beside
the simulator's readings of the same command: the band is the middle :data:`LEVEL` of them
(from the 0.5th to the 99.5th percentile), and a real reading outside it is an outlier, named
by its time, message and device. A gyroscope is compared as its change since the run's first
read of it: it counts from when it was switched on, which a tap cannot know; and its band is
widened by what it drifts in :data:`TIMING_STEPS` steps, as the tap's time of a read is that
close to the robot's.

With the fit's intervals (``simmer calibrate`` writes them beside its fragment), each seed's
simulator also draws its fitted settings from them (:meth:`~simmer.calibrate.stats.Interval.
draw`), from a stream of its own per seed: the band is then what the simulator predicts given
what the run could tell of the robot (the posterior predictive), not given the fitted values
alone, which a run of eight legs knows to a few tenths of a percent at best.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simmer.calibrate.fit import setting
from simmer.calibrate.stats import Interval
from simmer.config.models import SimConfig
from simmer.config.overrides import with_overrides
from simmer.protocol import parse_message
from simmer.tap.folder import TapRun

LEVEL = 0.99
"""The share of the simulator's readings the band holds."""
SEEDS = 100
"""Seeds simulated unless ``--seeds`` says otherwise."""
MAX_NAMED = 20
"""Outliers named one by one (then how many more)."""
RELATIVE = frozenset({"gyroscope"})
"""Device kinds compared as their change since the run's first read."""
TIMING_STEPS = 2
"""Steps between the tap's time of a read and the robot's, which a gyroscope's band allows."""
DRAWS = 3301
"""The stream (with the seed) each seed's settings are drawn from, apart from the simulator's."""
NAMES = ("value", "low", "high", "level")
"""The numbers each interval's table in an intervals file holds."""


@dataclass(frozen=True)
class Reading:
    """One real reading and the simulator's band for it."""

    time: float
    device: str
    message: str
    number: int
    """Which exchange of the run (from 1)."""
    real: float
    low: float
    median: float
    high: float

    @property
    def inside(self) -> bool:
        """Whether the real reading lies in the band."""
        return self.low <= self.real <= self.high

    def describe(self, unit: str) -> str:
        """The outlier in one line."""
        return (
            f"{self.device} at {self.time:.2f} s (exchange {self.number}, {self.message!r}): "
            f"{self.real:.3f}{unit}, the simulator's band {self.low:.3f} to {self.high:.3f}"
        )


@dataclass(frozen=True)
class Comparison:
    """Every real reading against its band."""

    readings: list[Reading]
    seeds: int
    units: dict[str, str]
    relative: frozenset[str] = frozenset()
    """Devices compared as their change since the run's first read."""
    drawn: tuple[str, ...] = ()
    """The settings each seed drew from the fit's intervals (none: the values as given)."""

    @property
    def inside_fraction(self) -> float:
        """The share of real readings inside their band (NaN: none)."""
        if not self.readings:
            return math.nan
        return sum(r.inside for r in self.readings) / len(self.readings)

    def outliers(self) -> list[Reading]:
        """The real readings outside their band, in time order."""
        return [r for r in self.readings if not r.inside]

    def summary(self) -> list[str]:
        """The figures and the outliers named, in lines."""
        total = len(self.readings)
        outside = self.outliers()
        lines = [
            f"{total - len(outside)} of {total} real readings ({self.inside_fraction:.1%}) are "
            f"inside the band holding {LEVEL:.0%} of the simulator's, over {self.seeds} seeds"
            + (
                f", each drawing {len(self.drawn)} fitted settings from their intervals"
                if self.drawn
                else ""
            )
        ]
        for reading in outside[:MAX_NAMED]:
            lines.append("  outside: " + reading.describe(self.units.get(reading.device, "")))
        if len(outside) > MAX_NAMED:
            lines.append(f"  and {len(outside) - MAX_NAMED} more outside")
        return lines


def _unit(kind: str) -> str:
    return {"ultrasonic": " in", "gyroscope": " deg", "compass": " deg"}.get(kind, "")


def compare(
    run: TapRun,
    config: SimConfig,
    *,
    seeds: int = SEEDS,
    intervals: Mapping[str, Interval] | None = None,
) -> Comparison:
    """The run's real readings against the band ``config`` predicts over ``seeds`` seeds;
    with ``intervals`` (dotted key: the fit's interval), each seed draws those settings."""
    from simmer.world.simulation import Simulation

    kinds = {spec.id: (spec.group, spec.kind) for spec in config.devices}
    lenient = config.settings.lenient_commands
    rate = config.settings.frame_rate
    plan: list[tuple[int, list[int], bool]] = []
    """Per exchange: its index, which of its replies are compared, whether it starts a drive."""
    places: list[tuple[int, int, str]] = []
    """Per compared reading: exchange index, reply index, device."""
    for index, event in enumerate(run.exchanges):
        commands = parse_message(event.message, lenient=lenient)
        compared, starts = [], False
        for k, (command, reply) in enumerate(zip(commands, event.replies, strict=False)):
            group, _ = kinds.get(command.device, ("", ""))
            if group == "sensors" and math.isfinite(reply):
                compared.append(k)
                places.append((index, k, command.device))
            elif group == "drives" and command.value != 0.0 and math.isinf(reply):
                starts = True
        plan.append((index, compared, starts))
    simulated = np.empty((seeds, len(places)))
    for seed in range(seeds):
        drawn = config
        if intervals:
            rng = np.random.default_rng([DRAWS, seed])
            draws = {key: setting(key, iv.draw(rng)) for key, iv in intervals.items()}
            drawn = with_overrides(config, draws)
        sim = Simulation(drawn, seed=seed)
        column = 0
        for index, compared, starts in plan:
            event = run.exchanges[index]
            target = round(event.time * rate)
            if target > sim.steps:
                sim.step(target - sim.steps)
            if starts and sim.robot.any_drive_moving:
                sim.run_until_idle()
            if not compared and not starts:
                continue  # a poll, or a command refused: nothing the simulator must do
            values = sim.command(event.message)
            for k in compared:
                simulated[seed, column] = values[k]
                column += 1
    real = np.array([run.exchanges[i].replies[k] for i, k, _ in places], dtype=float)
    for device in {d for _, _, d in places if kinds[d][1] in RELATIVE}:
        columns = [c for c, (_, _, d) in enumerate(places) if d == device]
        first = columns[0]
        real[columns] = (real[columns] - real[first] + 180.0) % 360.0 - 180.0
        simulated[:, columns] = (
            simulated[:, columns] - simulated[:, [first]] + 180.0
        ) % 360.0 - 180.0
    tail = (1.0 - LEVEL) / 2 * 100
    low, median, high = np.percentile(simulated, [tail, 50.0, 100.0 - tail], axis=0)
    params = {spec.id: spec.params for spec in config.devices}
    for c, (_, _, device) in enumerate(places):
        if kinds[device][1] in RELATIVE:
            slack = abs(float(getattr(params[device], "bias", 0.0))) * TIMING_STEPS / rate
            low[c] -= slack
            high[c] += slack
    readings = [
        Reading(
            run.exchanges[i].time,
            device,
            run.exchanges[i].message,
            i + 1,
            float(real[c]),
            float(low[c]),
            float(median[c]),
            float(high[c]),
        )
        for c, (i, _, device) in enumerate(places)
    ]
    units = {d: _unit(kinds[d][1]) for _, _, d in places}
    relative = frozenset(d for _, _, d in places if kinds[d][1] in RELATIVE)
    return Comparison(readings, seeds, units, relative, tuple(intervals or ()))


def load_intervals(path: Path) -> dict[str, Interval]:
    """The intervals file ``simmer calibrate`` writes beside its fragment
    (:func:`simmer.calibrate.fit.intervals_document`); ValueError naming the file and key."""
    import tomllib

    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (UnicodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(
            f"{path}: not TOML ({exc}); write it again with simmer calibrate"
        ) from None
    found: dict[str, Interval] = {}
    for key, table in data.items():
        ends = [table.get(name) if isinstance(table, dict) else None for name in NAMES]
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in ends
        ):
            raise ValueError(
                f'{path}: ["{key}"] needs finite numbers value, low, high and level; write '
                "it again with simmer calibrate"
            )
        value, low, high, level = (float(v) for v in ends if v is not None)
        if not (low <= value <= high and 0.0 < level < 1.0):
            raise ValueError(
                f'{path}: ["{key}"] needs low <= value <= high and 0 < level < 1; write it '
                "again with simmer calibrate"
            )
        found[key] = Interval(value, low, high, level)
    return found


def draw_comparison(comparison: Comparison, target: Path, title: str) -> None:
    """The picture: a panel per device, its band against time, the real readings over it,
    those outside in red and numbered as :meth:`Comparison.summary` names them."""
    from matplotlib import style
    from matplotlib.figure import Figure

    from simmer.record.plots import save_png

    devices = list(dict.fromkeys(r.device for r in comparison.readings))
    with style.context("default"):
        height = 1.6 + 2.2 * max(len(devices), 1)
        fig = Figure(figsize=(12.0, height), dpi=100, layout="constrained")
        axes = fig.subplots(max(len(devices), 1), 1, sharex=True, squeeze=False)[:, 0]
        for ax, device in zip(axes, devices, strict=False):
            rows = [r for r in comparison.readings if r.device == device]
            t = np.array([r.time for r in rows])
            ax.fill_between(
                t,
                [r.low for r in rows],
                [r.high for r in rows],
                step="mid",
                color="#9ecae1",
                alpha=0.8,
                label=f"simulator's {LEVEL:.0%} band",
            )
            ax.plot(t, [r.median for r in rows], color="#3182bd", lw=0.8, label="its median")
            inside = [r for r in rows if r.inside]
            outside = [r for r in rows if not r.inside]
            ax.plot(
                [r.time for r in inside], [r.real for r in inside], ".", color="black", ms=3,
                label="real reading",
            )  # fmt: skip
            if outside:
                ax.plot(
                    [r.time for r in outside], [r.real for r in outside], "o", color="#d62728",
                    ms=5, label="real, outside the band",
                )  # fmt: skip
            unit = comparison.units.get(device, "").strip()
            relative = " change" if device in comparison.relative else ""
            ax.set_ylabel(f"{device}{relative}" + (f" ({unit})" if unit else ""))
            share = sum(r.inside for r in rows) / len(rows)
            ax.set_title(f"{device}: {share:.0%} of {len(rows)} inside", loc="left", fontsize=9)
            ax.grid(alpha=0.3)
        axes[0].legend(loc="upper right", fontsize=8, ncols=4)
        axes[-1].set_xlabel("time since the tap started (s)")
        fig.suptitle(f"{title}\n{comparison.summary()[0]}", fontsize=10)
        save_png(fig, target)
