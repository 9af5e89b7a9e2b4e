"""Statistics across episodes and training seeds: pure functions on arrays, intervals from scipy.stats.

Conventions (as in rliable, Agarwal et al. 2021, "Deep RL at the edge of the statistical precipice"):
- Wilson score interval for a success rate pooled over every episode of every seed (the episode is the unit);
- percentile bootstrap over training seeds (the seed is the unit), stratified by terrain when terrains are pooled:
  each terrain's seeds are resampled separately, so every resample keeps every terrain;
- IQM: the mean of the middle 50% of per-seed values (scipy's trim_mean at 25%; with fewer than 4 seeds it trims
  nothing and equals the mean);
- probability of improvement P(X > Y): the Mann-Whitney U statistic over (seed of X, seed of Y) pairs divided by
  their number (ties count half), averaged over terrains.

An interval that cannot be computed (fewer than 2 seeds) has low = high = NaN: the report shows "-", never a
made-up width.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

ArrayLike = Sequence[float] | np.ndarray


@dataclass(frozen=True)
class Estimate:
    """A point estimate with its interval (NaN where undefined)."""

    value: float
    low: float = math.nan
    high: float = math.nan

    def as_dict(self, prefix: str) -> dict[str, float]:
        """{prefix: value, prefix_low: low, prefix_high: high}, NaNs left out (metrics files hold numbers only)."""
        out = {prefix: self.value, f"{prefix}_low": self.low, f"{prefix}_high": self.high}
        return {k: float(v) for k, v in out.items() if not math.isnan(v)}


def wilson(successes: int, episodes: int, confidence: float = 0.95) -> Estimate:
    """Success rate with its Wilson score interval (defined for 0 and n successes too)."""
    if episodes <= 0:
        return Estimate(math.nan)
    ci = stats.binomtest(int(successes), int(episodes)).proportion_ci(confidence, method="wilson")
    return Estimate(successes / episodes, float(ci.low), float(ci.high))


def iqm(values: ArrayLike) -> float:
    """Interquartile mean: the mean of the middle 50% (25% trimmed from each end)."""
    values = np.asarray(values, dtype=float)
    return float(stats.trim_mean(values, 0.25)) if len(values) else math.nan


def _bootstrap(
    samples: list[np.ndarray], statistic: Callable[..., np.ndarray], confidence: float, resamples: int, seed: int
) -> tuple[float, float]:
    """Percentile interval of `statistic(*samples, axis=-1)`, each sample resampled on its own (stratified)."""
    if any(len(s) < 2 for s in samples):
        return math.nan, math.nan
    if all(np.all(s == s[0]) for s in samples):  # every resample is the same: a zero-width interval
        point = float(statistic(*samples, axis=-1))
        return point, point
    res = stats.bootstrap(tuple(samples), statistic, n_resamples=resamples, vectorized=True, paired=False,
                          confidence_level=confidence, method="percentile", rng=np.random.default_rng(seed))
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def _mean_of_means(*samples: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean([np.mean(s, axis=axis) for s in samples], axis=0)


def _iqm_of_pooled(*samples: np.ndarray, axis: int = -1) -> np.ndarray:
    return stats.trim_mean(np.concatenate(samples, axis=axis), 0.25, axis=axis)


def bootstrap_mean(
    strata: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """Mean over strata of the per-stratum mean of per-seed values, with a stratified bootstrap interval.

    One stratum (one terrain): the plain percentile bootstrap over seeds."""
    samples = [np.asarray(s, dtype=float) for s in strata]
    if not samples or any(len(s) == 0 for s in samples):
        return Estimate(math.nan)
    value = float(_mean_of_means(*samples))
    return Estimate(value, *_bootstrap(samples, _mean_of_means, confidence, resamples, seed))


def bootstrap_iqm(
    strata: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """IQM of the per-seed values of every stratum pooled, with a stratified bootstrap interval."""
    samples = [np.asarray(s, dtype=float) for s in strata]
    if not samples or any(len(s) == 0 for s in samples):
        return Estimate(math.nan)
    value = float(_iqm_of_pooled(*samples))
    return Estimate(value, *_bootstrap(samples, _iqm_of_pooled, confidence, resamples, seed))


def probability_of_improvement(x: ArrayLike, y: ArrayLike) -> float:
    """P(X > Y) for one terrain: the share of (x, y) pairs where x wins, ties counted half."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if not len(x) or not len(y):
        return math.nan
    return float(stats.mannwhitneyu(x, y).statistic) / (len(x) * len(y))


def bootstrap_improvement(
    xs: Sequence[ArrayLike], ys: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """P(X > Y) averaged over terrains (xs[t], ys[t]: per-seed values on terrain t), stratified bootstrap interval."""
    if len(xs) != len(ys) or not xs:
        raise ValueError(f"need the same terrains for both conditions, got {len(xs)} and {len(ys)}")
    samples = [np.asarray(s, dtype=float) for s in (*xs, *ys)]
    if any(len(s) == 0 for s in samples):
        return Estimate(math.nan)
    k = len(xs)

    def statistic(*parts: np.ndarray, axis: int = -1) -> np.ndarray:
        per_terrain = [stats.mannwhitneyu(a, b, axis=axis, method="asymptotic").statistic
                       / (a.shape[axis] * b.shape[axis]) for a, b in zip(parts[:k], parts[k:], strict=True)]
        return np.mean(per_terrain, axis=0)

    value = float(np.mean([probability_of_improvement(a, b) for a, b in zip(samples[:k], samples[k:], strict=True)]))
    return Estimate(value, *_bootstrap(samples, statistic, confidence, resamples, seed))
