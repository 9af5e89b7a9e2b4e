"""The sweep's statistics on synthetic data with known answers, and its tables and report without Ray."""

import json
import math

import numpy as np
import pandas as pd
import pytest

from hexpipe.sweep import stats, tables
from hexpipe.sweep.report import SweepReport, write_report


def test_wilson_matches_the_textbook_values():
    # Newcombe (1998), Statistics in Medicine 17:857, method 3 (score interval without continuity correction)
    est = stats.wilson(81, 263)
    assert est.value == pytest.approx(81 / 263)
    assert (est.low, est.high) == pytest.approx((0.2553, 0.3662), abs=5e-5)
    none = stats.wilson(0, 10)  # defined at 0 successes, unlike the normal approximation
    assert none.low == 0.0 and none.high == pytest.approx(0.2775, abs=5e-5)
    assert stats.wilson(10, 10).low == pytest.approx(1 - 0.2775, abs=5e-5)
    assert math.isnan(stats.wilson(0, 0).value)


def test_iqm_is_the_mean_of_the_middle_half():
    assert stats.iqm([1, 2, 3, 4, 5, 6, 7, 8]) == pytest.approx(4.5)  # mean of 3, 4, 5, 6
    assert stats.iqm([0, 0.5, 0.5, 100]) == pytest.approx(0.5)  # the outlier is trimmed
    assert stats.iqm([0.2, 0.4, 0.9]) == pytest.approx(0.5)  # below 4 values nothing is trimmed


def test_bootstrap_interval_brackets_the_mean_and_narrows_with_more_seeds():
    rng = np.random.default_rng(1)
    few, many = rng.normal(0.6, 0.1, 5), rng.normal(0.6, 0.1, 200)
    a, b = stats.bootstrap_mean([few], resamples=2000), stats.bootstrap_mean([many], resamples=2000)
    assert a.low < a.value < a.high and b.low < b.value < b.high
    assert b.high - b.low < (a.high - a.low) / 3
    assert 0.57 < b.value < 0.63 and b.low < 0.6 < b.high
    assert stats.bootstrap_mean([few], resamples=2000) == a  # seeded: reproducible
    same = stats.bootstrap_mean([[1.0, 1.0, 1.0]])
    assert (same.value, same.low, same.high) == (1.0, 1.0, 1.0)
    one = stats.bootstrap_mean([[0.7]])  # one seed: no interval, not a zero-width one
    assert one.value == 0.7 and math.isnan(one.low) and one.as_dict("x") == {"x": 0.7}


def test_pooled_bootstrap_keeps_every_terrain():
    # terrain A is always solved, terrain B never: every resample keeps both, so the pooled mean is exactly 0.5
    # with a zero-width interval, where a bootstrap over the pooled values would spread from 0 to 1
    est = stats.bootstrap_mean([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    assert (est.value, est.low, est.high) == (0.5, 0.5, 0.5)
    est = stats.bootstrap_mean([[1.0, 0.8, 0.9], [0.0, 0.1, 0.0]], resamples=2000)
    assert 0.4 < est.low < est.value < est.high < 0.6


def test_pooled_bootstrap_resamples_whole_seeds():
    # seeds that fail on both terrains together: the seed means are 1, 0, 1, 0, so four seeds leave the pooled mean
    # anywhere in [0, 1]; resampling each terrain on its own would average two independent draws and narrow it
    together = stats.bootstrap_mean([[1.0, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0]], resamples=4000)
    assert (together.value, together.low, together.high) == (0.5, 0.0, 1.0)
    # seeds that trade terrains: every seed's mean is 0.5, so every resample of whole seeds is too
    trade = stats.bootstrap_mean([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]], resamples=4000)
    assert (trade.value, trade.low, trade.high) == (0.5, 0.5, 0.5)
    iqm = stats.bootstrap_iqm([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]], resamples=4000)
    assert iqm.low <= 0.5 <= iqm.high
    with pytest.raises(ValueError, match="same seeds"):
        stats.bootstrap_mean([[1.0, 0.0, 1.0], [1.0, 0.0]])


def test_improvement_interval_resamples_whole_seeds_of_each_side():
    # X's first seed wins on both terrains and its second loses on both; Y sits in between. Whole-seed resamples
    # include all-winning and all-losing draws, so the interval spans [0, 1]
    est = stats.bootstrap_improvement([[1.0, 0.0], [1.0, 0.0]], [[0.5, 0.5], [0.5, 0.5]], resamples=4000)
    assert (est.value, est.low, est.high) == (0.5, 0.0, 1.0)
    # when X's seeds trade terrains, every resample of X scores the same against a constant Y
    est = stats.bootstrap_improvement([[1.0, 0.0], [0.0, 1.0]], [[0.5, 0.5], [0.5, 0.5]], resamples=4000)
    assert (est.value, est.low, est.high) == (0.5, 0.5, 0.5)


def test_by_seed_aligns_terrains_on_the_training_seed():
    a = pd.DataFrame({"train_seed": [2, 0, 1], "success": [0.2, 0.0, 0.1]})
    b = pd.DataFrame({"train_seed": [0, 1, 2, 3], "success": [1.0, 1.1, 1.2, 1.3]})  # seed 3 lacks terrain a
    xa, xb = tables.by_seed([a, b])
    assert xa.tolist() == [0.0, 0.1, 0.2] and xb.tolist() == [1.0, 1.1, 1.2]


def test_probability_of_improvement():
    assert stats.probability_of_improvement([0.9, 0.8], [0.1, 0.2]) == 1.0
    assert stats.probability_of_improvement([0.1, 0.2], [0.9, 0.8]) == 0.0
    assert stats.probability_of_improvement([0.5, 0.5], [0.5, 0.5]) == 0.5  # ties count half
    assert stats.probability_of_improvement([1.0, 0.0], [0.5]) == 0.5
    est = stats.bootstrap_improvement([[0.9, 0.8, 1.0], [0.5, 0.6, 0.7]], [[0.1, 0.2, 0.0], [0.5, 0.6, 0.7]],
                                      resamples=2000)
    assert est.value == pytest.approx((1.0 + 0.5) / 2)  # wins on the first terrain, even on the second
    assert est.low <= est.value <= est.high <= 1.0 and est.low > 0.5


def _records():
    """Two conditions x 3 seeds x 2 terrains x 4 episodes with known successes."""
    rates = {"good": {"flat": [1.0, 1.0, 0.75], "block": [0.75, 0.5, 0.5]},
             "bad": {"flat": [0.5, 0.25, 0.5], "block": [0.0, 0.0, 0.25]}}
    records = []
    for condition, per_terrain in rates.items():
        for seed in range(3):
            episodes = []
            for terrain, rate in per_terrain.items():
                for i in range(4):
                    ok = i < round(rate[seed] * 4)
                    episodes.append({"terrain": terrain, "controller": "policy", "episode": i, "seed": 1000 + i,
                                     "success": ok, "time": 10.0 + seed if ok else 40.0,
                                     "termination": "goal" if ok else "stuck",
                                     "stall_legs": None if ok else "hind" if condition == "good" else "front",
                                     "cost_of_transport": (1.0 if condition == "good" else 2.0) if ok else None})
                episodes.append({"terrain": terrain, "controller": "open_loop", "episode": 0, "seed": 1000,
                                 "success": False, "time": 5.0, "cost_of_transport": None})
            records.append({"trial": f"{condition}-seed{seed}", "condition": condition, "seed": seed,
                            "episodes": episodes, "seconds": {"total": 1.0}})
    return records


def test_tables_from_records():
    episodes = tables.episodes_frame(_records())
    policy = episodes[episodes["controller"] == "policy"]
    seeds = tables.per_seed(policy)
    assert len(seeds) == 2 * 2 * 3
    good_flat = seeds[(seeds["condition"] == "good") & (seeds["terrain"] == "flat")]
    assert good_flat["success"].tolist() == [1.0, 1.0, 0.75] and good_flat["time_to_goal"].tolist() == [10, 11, 12]
    table = tables.summarise(seeds, ["good", "bad"], ["flat", "block"], resamples=1000)
    cell = table["good"]["flat"]
    assert cell["success_rate"] == pytest.approx(11 / 12) and cell["episodes"] == 12 and cell["seeds"] == 3
    assert cell["success_seed_mean"] == pytest.approx(2.75 / 3)
    assert cell["success_rate_low"] < cell["success_rate"] < cell["success_rate_high"] <= 1
    assert cell["time_to_goal"] == pytest.approx(11.0) and cell["cost_of_transport"] == pytest.approx(1.0)
    pooled = table["good"]["all"]
    assert pooled["success_seed_mean"] == pytest.approx((2.75 / 3 + 1.75 / 3) / 2)
    assert "time_to_goal" not in pooled  # not averaged across terrains
    pairs = tables.default_pairs(["good", "bad"], [])
    assert pairs == [("bad", "good")]
    better = tables.improvements(seeds, [("good", "bad")], ["flat", "block"], resamples=1000)["good_vs_bad"]
    assert better["flat"]["probability"] == 1.0 and better["all"]["probability"] == 1.0
    assert tables.pareto_front({"a": (0.9, 1.0), "b": (0.8, 2.0), "c": (0.5, 0.5), "d": (np.nan, 1.0)}) == ["a", "c"]


def test_report_files_are_complete_and_metrics_hold_numbers_only(tmp_path):
    records = _records()
    episodes = tables.episodes_frame(records)
    seeds = tables.per_seed(episodes[episodes["controller"] == "policy"])
    table = tables.summarise(seeds, ["good", "bad"], ["flat", "block"], resamples=500)
    trials = pd.DataFrame([{"trial": r["trial"], "condition": r["condition"], "seed": r["seed"], "status": "ok",
                            "seconds": 1.0, "host": "h", "error": None} for r in records])
    report = SweepReport(
        name="t", command="hexpipe sweep", conditions={"good": (), "bad": ("ppo.blind=true",)}, seeds=[0, 1, 2],
        terrains=["flat", "block"], table=table, improvement=tables.improvements(seeds, [("good", "bad")],
                                                                                   ["flat", "block"], resamples=500),
        per_seed=seeds, episodes=episodes, trials=trials, flat_terrain="flat", confidence=0.95)
    write_report(tmp_path, report)
    metrics = json.loads((tmp_path / "metrics.json").read_text())

    def numbers(tree):
        return all(numbers(v) for v in tree.values()) if isinstance(tree, dict) else isinstance(tree, int | float)

    assert numbers(metrics) and metrics["trials"] == {"complete": 6, "failed": 0, "total": 6}
    assert metrics["conditions"]["good"]["flat"]["success_rate"] == pytest.approx(11 / 12)
    results = pd.read_csv(tmp_path / "results.csv")
    assert set(results["terrain"]) == {"flat", "block", "all"} and "success_iqm_low" in results
    text = (tmp_path / "report.md").read_text()
    assert "good > bad" in text and "pareto_flat.png" in text and "Wilson" in text
    assert "| block | bad | 0.08 [0.01, 0.35] |" in text  # Wilson for 1 of 12
    assert "| 12.0 (1 seed) |" in text  # one seed of `bad` reached the goal on the block: no interval
    stalls = text.split("## Where the policies' failed episodes stopped")[1].split("##")[0]
    assert [line for line in stalls.splitlines() if line.startswith("| `")] == [
        "| `flat` | `good` | 1 | hind 1 |", "| `flat` | `bad` | 7 | front 7 |", "| `block` | `good` | 5 | hind 5 |",
        "| `block` | `bad` | 11 | front 11 |"]
    for name in ("success.png", "pareto_flat.png", "episodes.csv", "per_seed.csv", "trials.csv"):
        assert (tmp_path / name).stat().st_size > 0
    assert not list(tmp_path.glob(".*tmp*"))

    # Pareto: success over the suite (the `all` row) against flat cost; both conditions cross flat ground, so only
    # the suite's success can tell them apart ("bad" fails the block)
    from hexpipe.sweep.report import plot_pareto

    def cost(value):
        return {"cost_of_transport": value, "cost_of_transport_low": value, "cost_of_transport_high": value}

    report.table["bad"]["flat"] = {**report.table["good"]["flat"], **cost(0.1)}
    report.table["good"]["flat"] = {**report.table["good"]["flat"], **cost(5.0)}
    assert sorted(plot_pareto(report, tmp_path / "front.png")) == ["bad", "good"]  # cheaper, or more successful
    report.table["good"]["all"] = {**report.table["bad"]["all"]}  # no longer more successful: dominated
    assert plot_pareto(report, tmp_path / "front.png") == ["bad"]

    report.flat_terrain = "nowhere"  # flat ground not evaluated: no Pareto plot, a note instead
    write_report(tmp_path / "noflat", report)
    assert not (tmp_path / "noflat" / "pareto_nowhere.png").exists()
    assert "sweep.flat_terrain" in (tmp_path / "noflat" / "report.md").read_text()
