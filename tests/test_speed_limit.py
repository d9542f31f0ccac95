"""The confined tasks' speed limit: exploration pays no speed beyond it, `overspeed` charges for the excess, a
planned path may lower it at its waypoints, and a policy trained with `speed_command` is told the limit in force (and,
with `preview`, the waypoint after the current one); an opt-in roll/pitch-rate cost charges tipping.
Runs saved before the limit existed load with their old observations. A robot that stands still too long ends its
training episode (`stall_timeout_s`), never an evaluation's, and navigation runs the robot model as it is when asked.

The task's hooks are called directly on a spawned episode (no physics, nothing compiled): the file takes seconds.
"""

import dataclasses
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from brax.envs.base import State

from legged.envs.config import NoiseConfig, RandomizationConfig
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.paths import pad_speeds, straight_path
from legged.worlds import Terrain, generate_world

FOLLOWER = Path(__file__).resolve().parents[1] / "assets" / "policies" / "go1-confined-follower-v1"
"""The tunnel follower (shipped until the level-world follower replaced it), trained before the speed limit existed."""
NOMINAL = dict(randomization=RandomizationConfig(), noise=NoiseConfig())


@pytest.fixture(scope="module")
def terrain():
    return Terrain.from_worlds([generate_world(11, 0)])


def _env(terrain, speeds=None, **config) -> ConfinedEnv:
    return ConfinedEnv(ConfinedConfig(**{**NOMINAL, "max_speed": 1.0, **config}), terrain=terrain, speeds=speeds)


def _moving(env, speed: float, seed: int = 0):
    """(view, info) of a new episode whose body stands at the path's start moving at `speed` toward the waypoint."""
    view, info = env._spawned_view(jax.random.PRNGKey(seed))
    start, target = info["path"][0, :3], info["path"][info["waypoint"], :3]
    direction = (target[:2] - start[:2]) / jnp.linalg.norm(target[:2] - start[:2])
    view = view.replace(xpos=view.xpos.at[env._trunk].set(start), qvel=view.qvel.at[0:2].set(speed * direction))
    return view, dict(info, step=jnp.int32(1))  # the step count as the transition gives it to the task


def _step(env, speed: float, seed: int = 0):
    view, info = _moving(env, speed, seed)
    terms, success, metrics, _ = env._task_step(view, info, jnp.zeros(env.action_size))
    assert not bool(success)
    return {k: float(v) for k, v in terms.items()}, {k: float(v) for k, v in metrics.items()}


def test_exploration_is_capped_at_the_limit_and_overspeed_is_charged(terrain):
    env = _env(terrain)
    w, limit = env.config.rewards, env.config.max_speed
    assert limit == 1.0
    fast, fast_metrics = _step(env, 1.5 * limit)
    assert fast["exploration"] == pytest.approx(w.exploration * limit, rel=1e-4)
    assert fast["overspeed"] < 0 and fast["overspeed"] == pytest.approx(w.overspeed * 0.5 * limit, rel=1e-4)
    assert fast_metrics["speed"] == pytest.approx(1.5 * limit, rel=1e-4)
    assert fast_metrics["overspeed_mps"] == pytest.approx(0.5 * limit, rel=1e-4)
    assert fast_metrics["speed_limit"] == pytest.approx(limit)
    at_limit, _ = _step(env, limit)
    # running at 1.5x the limit clearly loses: half the limit's reward per step, a third per metre
    assert fast["exploration"] + fast["overspeed"] <= 0.5 * (at_limit["exploration"] + at_limit["overspeed"]) + 1e-4
    slow, slow_metrics = _step(env, 0.5)
    assert slow["exploration"] == pytest.approx(w.exploration * 0.5, rel=1e-4)
    assert slow["overspeed"] == 0.0 and slow_metrics["overspeed_mps"] == 0.0
    assert slow_metrics["mean_speed_mps"] == pytest.approx(0.5, rel=1e-4)


def test_the_roll_and_pitch_rate_cost_is_opt_in_and_ignores_yaw(terrain):
    view, info = _moving(_env(terrain), 0.5)
    view = view.replace(qvel=view.qvel.at[3:6].set(jnp.array([2.0, -1.0, 5.0])))  # body-frame roll, pitch, yaw rates
    default = _env(terrain)._task_step(view, info, jnp.zeros(12))[0]
    assert "ang_vel_xy" not in default
    rewards = dataclasses.replace(ConfinedConfig().rewards, ang_vel_xy=-0.05)
    charged = _env(terrain, rewards=rewards)._task_step(view, info, jnp.zeros(12))[0]
    assert float(charged["ang_vel_xy"]) == pytest.approx(-0.05 * (2.0**2 + 1.0**2), rel=1e-5)


def test_a_waypoint_limit_lowers_the_limit_in_force_and_the_command_tells_it(terrain):
    n = len(straight_path(terrain.starts[0], terrain.goals[0], ConfinedConfig().waypoint_spacing))
    speeds = np.full(n, np.nan)
    speeds[1] = 0.4  # the first waypoint ahead: slow down there
    env = _env(terrain, [speeds], six_dof_command=True, speed_command=True)
    assert env.command_names[-1] == "speed_limit" and len(env.command_names) == 7
    view, info = _moving(env, 1.5)
    assert float(env.speed_limit(info)) == pytest.approx(0.4)
    cmd = env._command(view, info)
    assert cmd.shape == (7,) and float(cmd[-1]) == pytest.approx(0.4)
    terms, metrics = _step(env, 1.5)
    assert terms["exploration"] == pytest.approx(0.4, rel=1e-4) and metrics["overspeed_mps"] == pytest.approx(1.1)
    # past that waypoint (its own limit NaN) the episode's limit holds again
    assert float(env.speed_limit(dict(info, waypoint=jnp.int32(2)))) == pytest.approx(1.0)
    assert ("command/speed_limit", 1) in env.observation_layout()["state"]
    off = _env(terrain, [speeds], six_dof_command=True)
    assert off.command_names == ("dx", "dy", "dz", "roll", "pitch", "dyaw")
    assert off._command(view, info).shape == (6,)
    assert env.observation_size["state"][0] == off.observation_size["state"][0] + 1


def test_the_command_can_preview_the_waypoint_after_the_current_one(terrain):
    env = _env(terrain, six_dof_command=True, speed_command=True, preview=True)
    assert env.command_names == ("dx", "dy", "dz", "roll", "pitch", "dyaw", "next_dx", "next_dy", "speed_limit")
    view, info = _moving(env, 0.5)
    cmd, base, path = np.asarray(env._command(view, info)), np.asarray(view.xpos[env._trunk]), np.asarray(info["path"])
    # both in the yaw frame: the distances to the current and the next waypoint, and the step between them, hold
    assert np.linalg.norm(cmd[0:2]) == pytest.approx(np.linalg.norm(path[1, :2] - base[:2]), rel=1e-5)
    assert np.linalg.norm(cmd[6:8]) == pytest.approx(np.linalg.norm(path[2, :2] - base[:2]), rel=1e-5)
    assert np.linalg.norm(cmd[6:8] - cmd[0:2]) == pytest.approx(np.linalg.norm(path[2, :2] - path[1, :2]), rel=1e-5)
    at_goal = np.asarray(env._command(view, dict(info, waypoint=info["path_len"] - 1)))
    np.testing.assert_allclose(at_goal[6:8], at_goal[0:2])  # nothing after the goal: the preview is the goal
    assert ("command/next_dx", 1) in env.observation_layout()["state"]
    assert _env(terrain, mode="goal", preview=True).command_names == ("dx", "dy")  # goal mode has no waypoints


def test_velocity_commands_respect_the_limit(terrain):
    n = len(straight_path(terrain.starts[0], terrain.goals[0], ConfinedConfig().waypoint_spacing))
    speeds = np.full(n, 0.3)
    env = _env(terrain, [speeds], mode="velocity", speed_command=True)
    assert env.command_names == ("vx", "vy", "yaw_rate", "speed_limit")
    view, info = _moving(env, 0.0)
    cmd = np.asarray(env._command(view, info))
    assert np.linalg.norm(cmd[:2]) == pytest.approx(0.3, rel=1e-4) and cmd[-1] == pytest.approx(0.3)
    plain = _env(terrain, mode="velocity")  # no waypoint limits: the commanded 0.5 m/s is under the 1 m/s limit
    view, info = _moving(plain, 0.0)
    assert np.linalg.norm(np.asarray(plain._command(view, info))[:2]) == pytest.approx(0.5, rel=1e-4)


def test_episodes_draw_their_limit_from_the_range_and_keep_their_other_draws(terrain):
    ranged = _env(terrain, speed_range=(0.3, 0.6))
    capped = _env(terrain, speed_range=(0.5, 3.0), max_speed=0.8)
    plain = _env(terrain)
    limits, tops = [], []
    for k in range(20):
        key = jax.random.PRNGKey(k)
        pos, yaw, info = ranged._task_reset(key)
        limits.append(float(info["speed_limit"]))
        tops.append(float(capped._task_reset(key)[2]["speed_limit"]))
        old_pos, old_yaw, old_info = plain._task_reset(key)
        assert float(old_info["speed_limit"]) == 1.0
        np.testing.assert_array_equal(np.asarray(pos), np.asarray(old_pos))  # the tile and yaw draws are unchanged
        assert float(yaw) == float(old_yaw) and int(info["tile"]) == int(old_info["tile"])
    assert min(limits) >= 0.3 and max(limits) <= 0.6 and np.std(limits) > 0.03
    assert max(tops) <= 0.8 + 1e-6 and min(tops) >= 0.5


def test_a_navigator_hands_over_new_limits_with_a_new_plan(terrain):
    from policies.navigate import _hand_over

    @dataclasses.dataclass
    class Batch:
        state: State

    env = _env(terrain, speed_command=True)
    _, info = env._spawned_view(jax.random.PRNGKey(0))
    batched = jax.tree_util.tree_map(lambda x: x[None], info)
    batch = Batch(State(None, {}, jnp.zeros(1), jnp.zeros(1), {}, batched))
    waypoints = np.asarray(info["path"])[:4]  # a replan: four waypoints, two with limits of their own
    new = _hand_over(batch, waypoints, np.array([np.nan, 0.5, np.nan, 0.2]), env.config.max_speed).state.info
    capacity = info["path"].shape[0]
    np.testing.assert_allclose(np.asarray(new["speeds"][0]), [1.0, 0.5, 1.0] + [0.2] * (capacity - 3))
    assert int(new["path_len"][0]) == 4 and int(new["waypoint"][0]) == 1
    one = jax.tree_util.tree_map(lambda x: x[0], new)
    assert float(env.speed_limit(one)) == pytest.approx(0.5)
    plain = _hand_over(batch, waypoints, None, env.config.max_speed).state.info  # a plan without limits
    assert np.all(np.asarray(plain["speeds"]) == 1.0)


def test_bad_limits_are_refused_naming_the_field():
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="max_speed"):
            ConfinedConfig(max_speed=bad)
    assert ConfinedConfig().max_speed == float("inf")  # runs saved before the limit: none, as they trained
    for bad in ((0.5, 0.2), (0.0, 1.0), (-0.1, 0.5), (0.3,)):
        with pytest.raises(ValueError, match="speed_range"):
            ConfinedConfig(speed_range=bad)
    with pytest.raises(ValueError, match="one per waypoint"):
        pad_speeds([np.ones(3)], [4], 5, 1.0)
    with pytest.raises(ValueError, match="positive"):
        pad_speeds([np.array([1.0, -0.5])], [2], 2, 1.0)

    from policies.config import TrainConfig, apply_overrides

    with pytest.raises(ValueError, match="max_speed"):
        apply_overrides(TrainConfig(task="confined-waypoints").resolved(), ["env.max_speed=-1"])
    cfg = apply_overrides(TrainConfig(task="confined-waypoints").resolved(), ["env.speed_range=[0.2, 0.4]"])
    assert cfg.env.speed_range == (0.2, 0.4)


def test_new_runs_train_with_the_limit_in_the_command_over_a_range_of_limits():
    from legged.tasks import default_config

    for task in ("confined-waypoints", "confined-goal", "confined-velocity", "confined-skills"):
        config = default_config(task)
        assert config.speed_command and config.speed_range == (0.3, 1.0) and config.max_speed == 1.0, task
        assert config.stall_timeout_s == 3.0, task  # and a stalled training episode ends


def test_the_tunnel_follower_loads_with_its_old_observations(terrain):
    """Its config.yaml predates the speed limit: it loads with the dataclass defaults (no speed in the command, one
    limit for every episode), and its policy reads the observations it was trained on."""
    from policies.policy_io import load_policy
    from policies.run_dir import RunDir, RunDirError, check_policy

    config = RunDir(FOLLOWER).load_config()
    assert not config.env.speed_command and config.env.speed_range is None and config.env.max_speed == float("inf")
    policy, _ = load_policy(FOLLOWER)
    env = ConfinedEnv(config.env, terrain=terrain)
    assert "speed_limit" not in env.command_names and len(env.command_names) == 6
    check_policy(policy, env)  # the observation sizes it was trained with
    told = ConfinedEnv(dataclasses.replace(config.env, speed_command=True), terrain=terrain)
    assert told.observation_size["state"][0] == env.observation_size["state"][0] + 1
    with pytest.raises(RunDirError):
        check_policy(policy, told)


def test_a_robot_standing_still_too_long_ends_its_training_episode_only(terrain):
    from policies.evaluate import confined_eval_config, held_out

    env = _env(terrain, stall_timeout_s=0.1)
    steps = round(0.1 / env.dt)  # 5 control steps at 50 Hz
    view, info = _moving(env, 0.0)
    for _ in range(steps):
        assert not bool(env._task_failed(view, info))
        _, _, metrics, info = env._task_step(view, info, jnp.zeros(env.action_size))
    assert int(info["stalled_steps"]) == steps and bool(env._task_failed(view, info))
    assert float(metrics["stalled_out"]) == 1
    moving, _ = _moving(env, 0.5)
    _, _, metrics, info = env._task_step(moving, info, jnp.zeros(env.action_size))
    assert int(info["stalled_steps"]) == 0 and float(metrics["stalled_out"]) == 0  # a step on the move starts it over
    view, info = _moving(_env(terrain), 0.0)
    for _ in range(steps):
        _, _, _, info = env._task_step(view, info, jnp.zeros(env.action_size))
    assert not bool(_env(terrain)._task_failed(view, info))  # the default: never (runs saved before it existed)
    config = env.config
    assert confined_eval_config(config, 2, 10, None).stall_timeout_s == float("inf")
    assert held_out("confined-waypoints", config).stall_timeout_s == float("inf")
    with pytest.raises(ValueError, match="stall_timeout_s must be a positive"):
        ConfinedConfig(stall_timeout_s=0.0)


def test_navigation_draws_a_robot_per_episode_unless_asked_for_it_as_it_is(monkeypatch):
    """`navigate(..., nominal=True)` (the demo's) runs the robot model as it is: randomisation and noise off."""
    import policies.navigate as nav

    class Built(Exception):
        pass

    seen = []

    def built(config, *args, **kwargs):
        seen.append(config)
        raise Built

    monkeypatch.setattr(nav, "ConfinedEnv", built)
    world = generate_world(11, 0)
    shipped = FOLLOWER.parent / "go1-confined-follower"
    for nominal in (False, True):
        with pytest.raises(Built):
            nav.navigate_seeds(str(shipped), world, world.start, world.goal, [0], nominal=nominal)
    assert [(c.randomization.enabled, c.noise.enabled) for c in seen] == [(True, True), (False, False)]
    assert all(c.stall_timeout_s == float("inf") for c in seen)  # a stalled robot is replanned, never cut short


def test_training_plans_and_navigation_share_the_followers_turn_limit_and_headings(monkeypatch):
    """`env.plan_turn_accel` and `env.plan_face_travel`: the training worlds are planned with them, and navigation with
    such a follower plans with them unless told otherwise."""
    import planners.planned_env as planned
    import policies.navigate as nav
    from planners import PlannerConfig, follower_planner

    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="plan_turn_accel"):
            ConfinedConfig(plan_turn_accel=bad)
    trained = ConfinedConfig(plan_turn_accel=1.0)
    assert follower_planner(trained, PlannerConfig()).turn_accel == 1.0
    assert follower_planner(trained, PlannerConfig(turn_accel=2.0)).turn_accel == 2.0  # the user's wins
    assert follower_planner(ConfinedConfig(), PlannerConfig()) == PlannerConfig()  # older runs: as before
    facing = ConfinedConfig(plan_face_travel=True)
    assert follower_planner(facing, PlannerConfig()).face_travel is True
    assert follower_planner(facing, PlannerConfig(face_travel=False)).face_travel is False  # the user's wins

    class Planned(Exception):
        pass

    seen = []

    def planning(*args, **kwargs):
        seen.append(next(a for a in (*args, *kwargs.values()) if isinstance(a, PlannerConfig)))
        raise Planned

    monkeypatch.setattr(planned, "feasible_worlds", planning)
    with pytest.raises(Planned):
        planned.make_planned_env("confined-waypoints", num_worlds=2, plan_turn_accel=0.8, plan_face_travel=True)
    real_load = nav.load_follower

    def follower_with_turns(*args, **kwargs):
        policy, config = real_load(*args, **kwargs)
        return policy, dataclasses.replace(config, env=dataclasses.replace(config.env, plan_turn_accel=0.7,
                                                                           plan_face_travel=True))

    monkeypatch.setattr(nav, "load_follower", follower_with_turns)
    monkeypatch.setattr(nav, "plan_path", planning)
    world = generate_world(11, 0)
    with pytest.raises(Planned):
        nav.navigate_seeds(str(FOLLOWER.parent / "go1-confined-follower"), world, world.start, world.goal, [0])
    assert [(p.turn_accel, p.face_travel) for p in seen] == [(0.8, True), (0.7, True)]
