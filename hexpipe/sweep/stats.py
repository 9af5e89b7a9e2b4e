"""Statistics across episodes and training seeds: pure functions on arrays, intervals from scipy.stats.

Conventions (as in rliable, Agarwal et al. 2021, "Deep RL at the edge of the statistical precipice"):
- Wilson score interval for a success rate pooled over every episode of every seed (the episode is the unit);
- percentile bootstrap over training seeds (the seed is the unit). Pooled over terrains, a resample draws whole
  seeds, each with its values on every terrain: one policy is evaluated on all of them, so its terrains rise and
  fall together. (rliable's stratified bootstrap resamples each task's runs on its own, which suits tasks trained
  separately; here it gave intervals too narrow: two 3-seed halves of one comparison excluded each other.)
  Every resample keeps every terrain;
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


def _aligned(strata: Sequence[ArrayLike]) -> np.ndarray | None:
    """(terrains, seeds) matrix of per-seed values; None when empty. Column i must be seed i on every terrain."""
    samples = [np.asarray(s, dtype=float) for s in strata]
    if not samples or any(len(s) == 0 for s in samples):
        return None
    if len({len(s) for s in samples}) != 1:
        raise ValueError(f"every terrain needs the same seeds, got {[len(s) for s in samples]} seeds per terrain")
    return np.stack(samples)


def _bootstrap(
    groups: list[np.ndarray], statistic: Callable[..., np.ndarray], confidence: float, resamples: int, seed: int
) -> tuple[float, float]:
    """Percentile interval of `statistic(*groups)` over resampled seeds.

    Each group is a (terrains, seeds) matrix. A resample draws whole seeds (columns) of each group, the same columns
    on every terrain, because one policy is evaluated on every terrain and its terrains rise and fall together;
    resampling each terrain's seeds on its own would treat them as independent and give too narrow an interval.
    Groups (the two conditions of a comparison) are resampled independently of each other."""
    if any(g.shape[-1] < 2 for g in groups):
        return math.nan, math.nan
    if all(np.all(g == g[:, :1]) for g in groups):  # every resample is the same: a zero-width interval
        point = float(statistic(*groups))
        return point, point

    def on_seed_indices(*indices: np.ndarray, axis: int = -1) -> np.ndarray:
        # indices[k]: (..., seeds) columns of groups[k]; g[:, idx] is (terrains, ..., seeds) -> (..., terrains, seeds)
        return statistic(*(np.moveaxis(g[:, idx], 0, -2) for g, idx in zip(groups, indices, strict=True)))

    res = stats.bootstrap(tuple(np.arange(g.shape[-1]) for g in groups), on_seed_indices, n_resamples=resamples,
                          vectorized=True, paired=False, confidence_level=confidence, method="percentile",
                          rng=np.random.default_rng(seed))
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def _mean_of_means(values: np.ndarray) -> np.ndarray:
    """(..., terrains, seeds) -> (...): the mean over terrains of the mean over seeds."""
    return values.mean(axis=-1).mean(axis=-1)


def _iqm_of_pooled(values: np.ndarray) -> np.ndarray:
    """(..., terrains, seeds) -> (...): the IQM of every (terrain, seed) value pooled."""
    return stats.trim_mean(values.reshape(*values.shape[:-2], -1), 0.25, axis=-1)


def _improvement(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(..., terrains, seeds_x), (..., terrains, seeds_y) -> (...): P(X > Y) over (x, y) seed pairs, ties counted
    half, averaged over terrains (the Mann-Whitney U statistic over the number of pairs)."""
    a, b = x[..., :, None], y[..., None, :]
    per_terrain = (a > b).mean(axis=(-1, -2)) + 0.5 * (a == b).mean(axis=(-1, -2))
    return per_terrain.mean(axis=-1)


def bootstrap_mean(
    strata: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """Mean over strata (terrains) of the per-stratum mean of per-seed values, with a bootstrap interval over whole
    seeds: strata[t][i] is seed i's value on terrain t. One stratum: the plain percentile bootstrap over seeds."""
    values = _aligned(strata)
    if values is None:
        return Estimate(math.nan)
    return Estimate(float(_mean_of_means(values)), *_bootstrap([values], _mean_of_means, confidence, resamples, seed))


def bootstrap_iqm(
    strata: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """IQM of the per-seed values of every stratum pooled, with a bootstrap interval over whole seeds."""
    values = _aligned(strata)
    if values is None:
        return Estimate(math.nan)
    return Estimate(float(_iqm_of_pooled(values)), *_bootstrap([values], _iqm_of_pooled, confidence, resamples, seed))


def probability_of_improvement(x: ArrayLike, y: ArrayLike) -> float:
    """P(X > Y) for one terrain: the share of (x, y) pairs where x wins, ties counted half."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if not len(x) or not len(y):
        return math.nan
    return float(_improvement(x[None], y[None]))


def bootstrap_improvement(
    xs: Sequence[ArrayLike], ys: Sequence[ArrayLike], confidence: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> Estimate:
    """P(X > Y) averaged over terrains (xs[t][i], ys[t][i]: seed i's value on terrain t), with a bootstrap interval
    that resamples whole seeds of X and of Y, independently of each other."""
    if len(xs) != len(ys) or not xs:
        raise ValueError(f"need the same terrains for both conditions, got {len(xs)} and {len(ys)}")
    x, y = _aligned(xs), _aligned(ys)
    if x is None or y is None:
        return Estimate(math.nan)
    return Estimate(float(_improvement(x, y)), *_bootstrap([x, y], _improvement, confidence, resamples, seed))
