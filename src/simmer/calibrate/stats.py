"""The few distribution quantiles an interval needs, without SciPy (not a dependency).

Normal quantiles are exact (:class:`statistics.NormalDist`); Student's t by its Cornish-Fisher
expansion and chi-square by Wilson and Hilferty's cube-root approximation, both within 1% of
the exact quantile from 5 degrees of freedom up, which is what a calibration's counts give
(docs/calibration.md)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

LEVEL = 0.99
"""The confidence of every interval a calibration states: 99%, so that a check of each
setting over twenty robots (docs/calibration.md) is not failed by chance alone (with 95%, a
setting outside its interval in 3 of 20 happens in 1 check in 13, and one of nine settings
so in 1 in 2)."""


def normal_quantile(p: float) -> float:
    """The standard normal's ``p`` quantile."""
    return NormalDist().inv_cdf(p)


def t_quantile(p: float, df: float) -> float:
    """Student's t's ``p`` quantile with ``df`` degrees of freedom (Cornish-Fisher)."""
    z = normal_quantile(p)
    return (
        z
        + (z**3 + z) / (4 * df)
        + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * df**2)
        + (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / (384 * df**3)
    )


def chi2_quantile(p: float, df: float) -> float:
    """The chi-square distribution's ``p`` quantile (Wilson-Hilferty)."""
    z = normal_quantile(p)
    a = 2.0 / (9.0 * df)
    return df * max(1.0 - a + z * math.sqrt(a), 0.0) ** 3


def mean_interval(values: list[float], level: float = LEVEL) -> tuple[float, float, float]:
    """The mean of ``values`` and its two-sided t interval."""
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, -math.inf, math.inf
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    half = t_quantile(0.5 + level / 2, n - 1) * sd / math.sqrt(n)
    return mean, mean - half, mean + half


def variance_interval(ss: float, df: float, level: float = LEVEL) -> tuple[float, float, float]:
    """A variance estimated from a sum of squared deviations ``ss`` with ``df`` degrees of
    freedom: the estimate and its two-sided chi-square interval."""
    if df <= 0:
        return math.nan, 0.0, math.inf
    tail = (1 - level) / 2
    return ss / df, ss / chi2_quantile(1 - tail, df), ss / chi2_quantile(tail, df)


@dataclass(frozen=True)
class Interval:
    """What a fit knows of one setting: its value and the interval at ``level`` holding it."""

    value: float
    low: float
    high: float
    level: float = LEVEL

    def draw(self, rng: np.random.Generator) -> float:
        """One value the setting may have, given the fit: a split normal about the value with
        the interval's ends as its ``level`` quantiles (a normal when the interval is
        symmetric, as a t interval of a bias is; skewed as a chi-square interval of an error
        is). Not uniform in the interval: that would make its ends as likely as the value
        the run points to, and widen a band past what the run supports."""
        z = normal_quantile(0.5 + self.level / 2)
        u = float(rng.standard_normal())
        side = self.high - self.value if u > 0 else self.value - self.low
        return self.value + u * max(side, 0.0) / z
