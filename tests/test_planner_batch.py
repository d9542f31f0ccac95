"""Batch planning: the on-disk cache, replacement of blocked worlds, and planned paths in the environment."""

import json

import numpy as np
import pytest

import planners.batch as batch
from legged.cli import main
from legged.envs.confined import ConfinedEnv
from legged.envs.flat import FlatEnv
from legged.worlds import WorldConfig, generate_world
from planners import Plan, PlannerConfig, PlanningError, cache_key, make_planned_env, plan_world

FAST = PlannerConfig(time_limit=3.0)


def test_cache_hits_misses_and_keys(tmp_path):
    world = generate_world(0, 1)
    first, cached = plan_world(world, config=FAST, cache_dir=tmp_path)
    assert isinstance(first, Plan) and not cached
    again, cached = plan_world(world, config=FAST, cache_dir=tmp_path)
    assert cached
    np.testing.assert_array_equal(again.waypoints, first.waypoints)
    assert again.length_m == first.length_m and again.planner == first.planner
    from legged.robots import GO1

    key = cache_key(world, GO1, FAST)
    assert key != cache_key(world, GO1, PlannerConfig(time_limit=3.0, spacing=0.3))
    assert key != cache_key(generate_world(1, 1), GO1, FAST)
    (tmp_path / f"{key}.npz").write_bytes(b"not an npz")  # a damaged entry is planned again
    replanned, cached = plan_world(world, config=FAST, cache_dir=tmp_path)
    assert not cached and np.array_equal(replanned.waypoints, first.waypoints)


def test_failures_are_cached_with_their_message(tmp_path):
    world = generate_world(0, 0)
    floor = world.floor.copy()
    mid = floor.shape[0] // 2
    floor[mid - 2:mid + 2] = world.ceiling[mid - 2:mid + 2]
    blocked = type(world)(floor=floor, ceiling=world.ceiling, resolution=world.resolution, origin=world.origin,
                          start=world.start, goal=world.goal)
    config = PlannerConfig(time_limit=0.3)
    result, cached = plan_world(blocked, config=config, cache_dir=tmp_path)
    assert isinstance(result, PlanningError) and not cached
    again, cached = plan_world(blocked, config=config, cache_dir=tmp_path)
    assert cached and isinstance(again, PlanningError) and str(again) == str(result)


def test_blocked_worlds_are_replaced_by_fresh_ones(tmp_path, monkeypatch):
    real = batch.plan_worlds
    calls = []

    def first_world_blocked(worlds, *args, **kwargs):
        results = real(worlds, *args, **kwargs)
        calls.append([w.seed for w in worlds])
        if len(calls) == 1:
            results[0] = (PlanningError("blocked"), False)
        return results

    monkeypatch.setattr(batch, "plan_worlds", first_world_blocked)
    worlds, plans = batch.feasible_worlds(2, 5, (0, 1), WorldConfig(),
                                          config=FAST, cache_dir=tmp_path, progress=False)
    assert calls == [[500_015, 500_016], [500_017]]
    assert [w.seed for w in worlds] == [500_017, 500_016]
    assert [w.difficulty for w in worlds] == [0, 1]  # the replacement keeps the slot's difficulty
    assert all(isinstance(p, Plan) for p in plans)


def test_planned_env_gets_tiled_paths(tmp_path):
    env = make_planned_env("confined-waypoints", planner=FAST, cache_dir=tmp_path, progress=False, num_worlds=2)
    assert isinstance(env, ConfinedEnv)
    paths, lengths = np.asarray(env._paths), np.asarray(env._path_len)
    for k in range(2):
        np.testing.assert_allclose(paths[k, 0, :2], env.terrain.starts[k, :2], atol=1e-5)
        np.testing.assert_allclose(paths[k, lengths[k] - 1, :2], env.terrain.goals[k, :2], atol=1e-5)
        z = paths[k, :lengths[k], 2]
        floor = env.terrain.floor  # planned heights sit within leg reach of the tiled floor
        assert np.all(z > floor.min() + 0.2) and lengths[k] >= 2
    assert isinstance(make_planned_env("go1-flat"), FlatEnv)


def test_cli_bench_plan_json(capsys):
    assert main(["bench", "plan", "--worlds", "2", "--difficulties", "0", "--json", "--quiet"]) == 0
    (record,) = json.loads(capsys.readouterr().out)
    assert record["difficulty"] == 0 and record["worlds"] == 2
    assert record["solved"] + len(record["failed_seeds"]) == 2
    if record["solved"]:
        assert record["median_length_m"] >= record["straight_line_m"] - 1e-6


@pytest.mark.parametrize("argv, message", [
    (["plan", "--planner", "dijkstra"], "unknown planner"),
    (["plan", "--time-limit", "0"], "argument --time-limit: must be greater than 0"),
    (["plan", "--scene", "missing.xml"], "needs --start"),
])
def test_cli_plan_rejects_bad_input_before_planning(capsys, argv, message):
    assert main(argv) == 2
    assert message in capsys.readouterr().err
