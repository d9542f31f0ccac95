"""The paired goal ratio `legged eval --compare-teacher` reports: a student's goals over its teacher's in the same
games, with a bootstrap interval over the games."""

import numpy as np
import pytest

from policies.evaluate import paired_goal_ratio


def test_the_ratio_is_of_the_sums_and_its_interval_holds_it():
    student = [0, 1, 0, 2, 0, 1, 0, 0, 1, 0] * 10
    teacher = [1, 1, 0, 1, 1, 1, 0, 1, 1, 0] * 10
    out = paired_goal_ratio(student, teacher)
    assert out["games"] == 100 and out["goals"] == 50 and out["baseline_goals"] == 70
    assert out["ratio"] == round(50 / 70, 4)
    low, high = out["ratio_ci95"]
    assert low < out["ratio"] < high and 0.0 < low and high < 1.2
    assert paired_goal_ratio(student, teacher) == out  # deterministic
    assert paired_goal_ratio(student, teacher, seed=1)["ratio_ci95"] != out["ratio_ci95"]


def test_pairing_narrows_the_interval_when_both_players_score_in_the_same_games():
    rng = np.random.default_rng(3)
    easy = rng.random(200) < 0.4  # games where anyone scores
    teacher = easy.astype(int)
    student = (easy & (rng.random(200) < 0.8)).astype(int)
    paired = paired_goal_ratio(student, teacher)["ratio_ci95"]
    unpaired = paired_goal_ratio(student, rng.permutation(teacher))["ratio_ci95"]  # the same sums, pairs broken
    assert paired[1] - paired[0] < unpaired[1] - unpaired[0]


def test_no_ratio_without_teacher_goals_and_errors_for_unpaired_counts():
    out = paired_goal_ratio([1, 0], [0, 0])
    assert out["ratio"] is None and out["ratio_ci95"] is None and out["goals"] == 1
    for a, b in (([1, 0], [1]), ([], []), ([[1]], [[1]])):
        with pytest.raises(ValueError, match="one count per game"):
            paired_goal_ratio(a, b)
