"""`legged bench train`'s pieces: the loop's time split from a run's records, and MuJoCo's profile of a step.

(The loop's own time fields are checked on a real run in tests/test_training.py; the benchmark's figures are
measured, not asserted: assets/benchmarks/.)"""

import mujoco
import pytest

from legged.bench import PROFILE_TIMERS, attach_peer, physics_profile
from policies.bench_train import PARTS, loop_split


def _record(wall, physics=1.0, env=0.5, policy=0.25, update=0.2, saving=0.05):
    return {"wall_s": wall, "time_physics_s": physics, "time_env_s": env, "time_policy_s": policy,
            "time_update_s": update, "time_saving_s": saving}


def test_the_split_leaves_out_the_warm_up_iterations_and_sums_to_the_loop():
    records = [_record(30.0, physics=20.0), _record(35.0)] + [_record(35.0 + 2.0 * k) for k in range(1, 5)]
    split = loop_split(records, warmup=2, per_iteration=1000)
    assert split["iterations"] == 4 and split["seconds_per_iteration"] == 2.0
    assert split["loop_env_steps_per_s"] == 500.0
    assert split["physics_share"] == 0.5 and split["physics_s_per_iteration"] == 1.0
    assert sum(split[f"{p}_share"] for p in PARTS) == pytest.approx(1.0)


def test_mjx_records_have_no_physics_part():
    records = [_record(1.0 + k, physics=None) for k in range(4)]
    split = loop_split(records, warmup=1, per_iteration=10)
    assert split["physics_share"] is None and split["env_share"] == 0.5


def test_a_split_needs_iterations_after_the_warm_up():
    with pytest.raises(ValueError, match="no iteration after the 3 warm-up"):
        loop_split([_record(1.0)] * 3, warmup=3, per_iteration=10)


def test_the_profile_reads_mujocos_timers_and_constraint_counts():
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="plane" size="1 1 0.1"/><body pos="0 0 0.1"><freejoint/>'
        '<geom type="box" size="0.1 0.1 0.1"/></body></worldbody></mujoco>')
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    profile = physics_profile(model, [data, data], steps=20)
    assert profile["physics_steps"] == 40 and data.time == 0.0  # the states given are left as they were
    assert profile["contacts"] == 4.0 and profile["constraint_rows"] > 0 and profile["solver_iterations"] > 0
    assert all(profile[f"{t}_us"] >= 0 for t in PROFILE_TIMERS) and profile["step_us"] > 0
    assert profile["step_us"] >= profile["constraint_us"] and profile["solver"] == "mjSOL_NEWTON"


def test_each_task_is_set_beside_its_own_playground_peer():
    records = [{"task": t, "physics": p, "batch": 256, "env_steps_per_s": 3000.0}
               for t in ("go1-flat", "go1-rough", "confined-waypoints") for p in ("mjx", "native")]
    peer = {("Go1JoystickFlatTerrain", 256): {"env": "Go1JoystickFlatTerrain", "env_steps_per_s": 6000.0},
            ("Go1JoystickRoughTerrain", 256): {"env": "Go1JoystickRoughTerrain", "env_steps_per_s": 2000.0}}
    attach_peer(records, peer)
    mjx = {r["task"]: r for r in records if r["physics"] == "mjx"}
    assert mjx["go1-flat"]["peer"] == "Go1JoystickFlatTerrain" and mjx["go1-flat"]["ratio_vs_peer"] == 0.5
    assert mjx["go1-rough"]["peer"] == "Go1JoystickRoughTerrain" and mjx["go1-rough"]["ratio_vs_peer"] == 1.5
    assert mjx["confined-waypoints"]["peer"] == "Go1JoystickRoughTerrain"  # the nearest Playground has
    assert not any("peer" in r for r in records if r["physics"] == "native")  # MJX beside MJX only


def test_the_update_bench_times_every_variant_against_the_plain_update():
    """`legged bench update`: each variant's median over its interleaved rounds, as a ratio to the plain update's
    (speeds are measured, not asserted); an unknown variant, or none plain to compare with, is refused."""
    import torch

    from policies.bench_update import bench_update

    torch.set_num_threads(1)
    record = bench_update(20, (16,), batch=64, epochs=2, mini_batches=2, rounds=3,
                          variants=("plain", "fused-adam", "foreach-adam", "one-thread"))
    assert set(record["variants"]) == {"plain", "fused-adam", "foreach-adam", "one-thread"}
    for figures in record["variants"].values():
        assert len(figures["update_s_each"]) == 3 and figures["update_s"] == sorted(figures["update_s_each"])[1]
        assert figures["speed_vs_plain"] == pytest.approx(record["variants"]["plain"]["update_s"] / figures["update_s"])
    assert record["variants"]["plain"]["speed_vs_plain"] == 1.0
    with pytest.raises(ValueError, match="pick from plain"):
        bench_update(20, (16,), variants=("fused-adam", "turbo"))
