"""The calibration's output folder: the fitted fragment, the report and its plots.

``simmer calibrate RUN --out DIR`` writes into DIR:

- ``fitted.toml``: the fitted values as dotted keys, each with its interval
  (:func:`simmer.calibrate.fit.fragment`);
- ``fitted.intervals.toml``: the intervals as data (:func:`simmer.calibrate.fit.
  intervals_document`), which ``simmer compare --fitted fitted.toml`` reads beside it;
- ``readings.png``: the run's readings against the band the fitted simulator predicts, each
  seed drawing the fitted settings from their intervals
  (:func:`simmer.calibrate.compare.draw_comparison`), what ``simmer compare`` draws;
- ``drives.png``: each leg's and turn's measured amount over the amount commanded, with the
  fitted scale (1 + bias) and the band the fitted error gives it;
- ``calibration.md``: each value, its interval and how it was measured, the figures of the
  comparison, and the pictures.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from simmer.calibrate.compare import LEVEL as BAND_LEVEL
from simmer.calibrate.compare import compare, draw_comparison
from simmer.calibrate.fit import (
    Calibration,
    fitted_overrides,
    fragment,
    intervals,
    intervals_document,
    intervals_path,
)
from simmer.calibrate.stats import LEVEL
from simmer.config.models import SimConfig
from simmer.config.overrides import with_overrides
from simmer.record.safefile import check_target, write_text
from simmer.tap.folder import TapRun

FITTED = "fitted.toml"
READINGS = "readings.png"
DRIVES = "drives.png"
REPORT = "calibration.md"


def write_report(
    calibration: Calibration,
    run: TapRun,
    config: SimConfig,
    out: Path,
    *,
    seeds: int,
    say: Callable[[str], None] = print,
) -> list[Path]:
    """Write the calibration's folder ``out`` (see the module doc); the files written."""
    out.mkdir(parents=True, exist_ok=True)
    side = intervals_path(out / FITTED)
    for target in (out / FITTED, side, out / READINGS, out / DRIVES, out / REPORT):
        check_target(target, run_folder=False)
    write_text(out / FITTED, fragment(calibration, str(run.folder)), run_folder=False)
    write_text(side, intervals_document(calibration, str(run.folder)), run_folder=False)
    fitted = with_overrides(config, fitted_overrides(calibration))
    comparison = compare(run, fitted, seeds=seeds, intervals=intervals(calibration))
    draw_comparison(
        comparison, out / READINGS, f"{run.folder.name}: the readings against the fitted simulator"
    )
    _draw_drives(calibration, out / DRIVES)
    lines = [
        f"# Calibration of {run.folder.name}",
        "",
        f"Fitted by `simmer calibrate` from the tap's run in `{run.folder}` with the "
        f"configuration `{config.source}`. Each value has its {LEVEL:.0%} interval: the range "
        "that holds the robot's true setting unless this run was a 1-in-100 unlucky one.",
        "",
        "| setting | fitted | interval | from | how |",
        "| --- | --- | --- | --- | --- |",
    ]
    for e in calibration.estimates:
        kept = "" if e.configurable else " (no setting: reported only)"
        lines.append(
            f"| `{e.key}`{kept} | {e.value:.4g} | {e.low:.4g} to {e.high:.4g} | {e.count} | "
            f"{e.how} |"
        )
    lines += ["", *(f"- {note}" for note in calibration.notes), ""]
    lines += [
        "## The readings against the fitted simulator",
        "",
        comparison.summary()[0] + f" (the band: the middle {BAND_LEVEL:.0%}; each seed "
        f"draws the fitted settings from their {LEVEL:.0%} intervals, so the band carries "
        "what this run could not tell of the robot).",
        "",
        *(f"    {line.strip()}" for line in comparison.summary()[1:]),
        "",
        f"![The readings against the fitted simulator's band]({READINGS})",
        "",
        "## Each motion measured",
        "",
        f"![Each leg's and turn's measured amount over the amount commanded]({DRIVES})",
        "",
        f"`{FITTED}` holds the fitted values: paste it into the robot's configuration, or try "
        f"it first: `simmer compare {run.folder} --config {config.source} --fitted "
        f"{out / FITTED}`.",
        "",
    ]
    write_text(out / REPORT, "\n".join(lines), run_folder=False)
    written = [out / FITTED, side, out / READINGS, out / DRIVES, out / REPORT]
    for path in written:
        say(f"wrote {path}")
    return written


def _draw_drives(calibration: Calibration, target: Path) -> None:
    """A panel per drive: each motion's measured over commanded, the fitted scale and band."""
    from matplotlib import style
    from matplotlib.figure import Figure

    from simmer.record.plots import save_png

    drives = list(calibration.ratios)
    with style.context("default"):
        height = 1.4 + 2.6 * max(len(drives), 1)
        fig = Figure(figsize=(10.0, height), dpi=100, layout="constrained")
        axes = fig.subplots(max(len(drives), 1), 1, squeeze=False)[:, 0]
        for ax, drive in zip(axes, drives, strict=False):
            samples = calibration.ratios[drive]
            keys = [e for e in calibration.estimates if e.key.startswith(f"drives.{drive}.")]
            bias = next(e for e in keys if ".bias." in e.key)
            error = next(e for e in keys if ".error." in e.key)
            scale = sum(r for _, r in samples) / len(samples)  # 1 + bias along the motion
            numbers = list(range(1, len(samples) + 1))
            ax.axhspan(
                scale * (1 - 2 * 2.576 * error.value),
                scale * (1 + 2 * 2.576 * error.value),
                color="#9ecae1",
                alpha=0.6,
                label="the fitted error's 99% band",
            )
            ax.axhline(scale, color="#3182bd", label=f"fitted scale 1 + bias = {scale:.4f}")
            ax.axhline(1.0, color="grey", ls="--", lw=0.8, label="as commanded")
            ax.plot(
                numbers,
                [r for _, r in samples],
                "o",
                color="black",
                label="each motion: measured / commanded",
            )
            unit = "deg" if bias.key.endswith("rotation") else "in"
            amounts = sorted({abs(a) for a, _ in samples})
            ax.set_title(
                f"{drive}: {len(samples)} motions of "
                f"{', '.join(f'{a:g}' for a in amounts)} {unit} each way",
                loc="left",
                fontsize=9,
            )
            ax.set_xlabel("motion")
            ax.set_ylabel("measured / commanded")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        save_png(fig, target)
