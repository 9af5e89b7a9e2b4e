"""Evaluation statistics on synthetic episodes: intervals, the best-fixed-gait ranking and the verdict."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from hexpipe.evaluation.metrics import (
    adaptation,
    bootstrap_interval,
    rank_gaits,
    summarise,
    summary_numbers,
    verdict,
    wilson_interval,
)
from hexpipe.evaluation.report import adaptation_text, verdict_table


def episode(terrain="single_block", controller="policy", success=True, time=10.0, cot=2.0, b_before=0.45,
            b_open=0.2, **extra) -> dict:
    return {"terrain": terrain, "controller": controller, "success": success, "time": time,
            "distance": 3.0 if success else 0.5, "termination": "goal" if success else "stuck",
            "cost_of_transport": cot, "a_mean": 0.3, "b_mean": 0.3, "omega_mean": 4.7,
            "b_before_block": b_before, "b_open": b_open, **extra}


def test_wilson_interval_matches_the_formula_and_stays_inside_0_1():
    z = 1.959964
    for k, n in [(10, 20), (3, 7)]:
        p = k / n
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        assert wilson_interval(k, n) == pytest.approx((centre - half, centre + half), abs=1e-5)
    low, high = wilson_interval(20, 20)
    assert high == 1.0 and low == pytest.approx(0.8389, abs=1e-4)  # 20/20 still leaves 16 points of doubt
    assert wilson_interval(0, 20)[0] == 0.0


def test_bootstrap_interval_brackets_the_mean_and_is_reproducible():
    values = np.array([10.0, 11.0, 12.0, 14.0, 18.0])
    low, high = bootstrap_interval(values)
    assert low < values.mean() < high and low >= values.min() and high <= values.max()
    assert bootstrap_interval(values) == (low, high)
    assert bootstrap_interval([7.0]) == (7.0, 7.0)


def test_summary_has_success_interval_and_spread_of_time_and_cost():
    rows = pd.DataFrame([episode(time=t, cot=c) for t, c in [(10, 2.0), (12, 2.5), (14, 3.0)]]
                        + [episode(success=False, time=6.0, cot=9.0)])
    m = summarise(rows, ["single_block"], ["policy"])["single_block"]["policy"]
    assert (m["successes"], m["episodes"], m["success_rate"]) == (3, 4, 0.75)
    assert m["success_ci_low"] < 0.75 < m["success_ci_high"] < 1.0
    assert m["time_to_goal_mean"] == 12.0 and m["time_to_goal_std"] == pytest.approx(math.sqrt(8 / 3))
    assert 10.0 <= m["time_to_goal_ci_low"] < 12.0 < m["time_to_goal_ci_high"] <= 14.0
    assert m["cost_of_transport"] == 2.5  # the failed episode's 9.0 is left out
    assert m["cost_of_transport_ci_low"] < 2.5 < m["cost_of_transport_ci_high"]
    assert m["lift_before_block"] == pytest.approx(0.25)
    json.dumps(m, allow_nan=False)  # numbers only: dvc metrics diff reads them
    never = summarise(pd.DataFrame([episode(success=False)]), ["single_block"], ["policy"])["single_block"]["policy"]
    assert "time_to_goal_mean" not in never and "cost_of_transport_ci_low" not in never


def test_best_fixed_gait_is_chosen_by_success_then_cost_of_transport():
    def gait(name, successes, cot, time=10.0, episodes=4, distance=0.5):
        return [{"gait": name, "success": i < successes, "distance": 3.0 if i < successes else distance,
                 "time": time, "termination": "goal" if i < successes else "stuck", "cost_of_transport": cot}
                for i in range(episodes)]

    rows = pd.DataFrame(gait("fast_costly", 4, 3.0, time=8.0) + gait("slow_cheap", 4, 2.0, time=20.0)
                        + gait("cheapest_but_fails_once", 3, 1.0) + gait("never", 0, 5.0, distance=2.5)
                        + gait("stuck", 0, 5.0))
    ranked = rank_gaits(rows, goal_distance=3.0)
    assert ranked["gait"].tolist() == ["slow_cheap", "fast_costly", "cheapest_but_fails_once", "never", "stuck"]
    assert ranked.loc[0, "cost_of_transport"] == 2.0 and math.isnan(ranked.loc[3, "cost_of_transport"])


def table_for(policy: dict, fixed: dict, terrains=("flat", "single_block")) -> dict:
    rows = []
    for t in terrains:
        rows += [episode(t, "policy", **policy) for _ in range(20)]
        rows += [episode(t, "best_fixed", b_before=0.5, b_open=0.5, **fixed) for _ in range(20)]
    return summarise(pd.DataFrame(rows), terrains, ["policy", "best_fixed"])


def test_verdict_passes_a_faster_cheaper_policy_and_fails_a_costlier_one():
    fixed = {"time": 11.0, "cot": 2.1}
    good = table_for({"time": 10.0, "cot": 1.2}, fixed)
    calls = verdict(good, ["flat", "single_block"])
    assert [v.beats for v in calls] == [True, True]
    numbers = summary_numbers(good, ["flat", "single_block"], ["policy"])
    assert numbers["verdict/policy/beats_best_fixed_everywhere"] == 1 and numbers["verdict/policy/flat"] == 1
    assert "**Overall: yes**" in verdict_table(good, ["flat", "single_block"], "policy")

    costly = table_for({"time": 10.0, "cot": 2.5}, fixed)  # faster, but spends more energy per metre
    call = verdict(costly, ["flat"])[0]
    assert (call.success, call.time, call.cost_of_transport, call.beats) == (True, True, False, False)
    numbers = summary_numbers(costly, ["flat", "single_block"], ["policy"])
    assert numbers["verdict/policy/beats_best_fixed_everywhere"] == 0 and numbers["verdict/policy/terrains_beaten"] == 0
    assert "**Overall: no**" in verdict_table(costly, ["flat", "single_block"], "policy")


def test_verdict_success_margin_and_controllers_that_never_arrive():
    fixed = summarise(pd.DataFrame([episode(controller="best_fixed", time=11.0, cot=2.1) for _ in range(20)]),
                      ["single_block"], ["best_fixed"])["single_block"]["best_fixed"]

    def call(successes: int) -> tuple[bool, bool, bool]:
        rows = [episode(success=i < successes, time=9.0, cot=1.5) for i in range(20)]
        table = summarise(pd.DataFrame(rows), ["single_block"], ["policy"])
        table["single_block"]["best_fixed"] = fixed
        v = verdict(table, ["single_block"])[0]
        return v.success, v.time, v.cost_of_transport

    assert call(19) == (True, True, True)  # 95% against 100%: within 5 points
    assert call(18) == (False, True, True)  # 90%: 10 points below
    assert call(0) == (False, False, False)  # never arrives: no time or cost to compare
    stuck = summarise(pd.DataFrame([episode(success=False), episode(controller="best_fixed", success=False)]),
                      ["single_block"], ["policy", "best_fixed"])
    assert verdict(stuck, ["single_block"])[0].beats is False
    assert verdict(stuck, ["flat"]) == []  # a terrain not evaluated is not judged


def test_adaptation_measures_lift_before_the_face_and_success_on_moved_blocks():
    rows = [episode("single_block", b_before=0.45, b_open=0.2) for _ in range(10)]
    rows += [episode("block_near") for _ in range(10)]
    rows += [episode("block_far", success=i < 6) for i in range(10)]
    table = summarise(pd.DataFrame(rows), ["single_block", "block_near", "block_far"], ["policy"])
    numbers = adaptation(table)
    assert numbers["lift_before_face"] == pytest.approx(0.25) and numbers["lift_target_met"] == 1
    assert numbers["block_near_minus_single_block"] == 0.0
    assert numbers["block_far_minus_single_block"] == pytest.approx(-0.4)
    assert numbers["anywhere_target_met"] == 0 and "wide_block_minus_single_block" not in numbers
    text = adaptation_text(table, "policy")
    assert "+0.25 rad" in text and "block_far 60% (-40 points)" in text
    fixed_lift = summarise(pd.DataFrame([episode(b_before=0.3, b_open=0.3)]), ["single_block"], ["policy"])
    assert adaptation(fixed_lift)["lift_target_met"] == 0
