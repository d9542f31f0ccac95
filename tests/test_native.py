"""The native engine (mujoco.batch.Batch behind the task verbs) against MuJoCo itself and against MJX."""

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from conftest import BATCH
from legged.envs.contacts import native_contact_forces
from legged.envs.native import NativeEnvs, check_threads
from legged.envs.vector import VectorEnv
from legged.tasks import make
from policies.config import ConfigError, TrainConfig


def _random_ctrl(env, rng, n):
    return np.asarray(env.joint_targets(jnp.asarray(rng.uniform(-1, 1, (n, env.action_size)), jnp.float32)))


def test_batched_engine_equals_one_mjdata_per_env(confined):
    """Batch stepping of every simulation is bit-identical to mj_step on its own MjData."""
    env = confined.env
    native = NativeEnvs(env, BATCH, threads=2)
    native.reset(confined.keys(4))
    model = native.physics.model
    datas = []
    for i in range(BATCH):
        d = mujoco.MjData(model)
        d.qpos[:], d.qvel[:], d.ctrl[:] = (native.physics.batch.bind(k)[i] for k in ("qpos", "qvel", "ctrl"))
        datas.append(d)
    rng = np.random.default_rng(0)
    for _ in range(5):
        ctrl = _random_ctrl(env, rng, BATCH)
        view, bad = native.physics.step(ctrl)
        for i, d in enumerate(datas):
            d.ctrl[:] = ctrl[i]
            for _ in range(env.n_substeps):
                mujoco.mj_step(model, d)
        assert not bad.any()
    batch_qpos = native.physics.batch.bind("qpos")
    for i, d in enumerate(datas):
        assert np.array_equal(batch_qpos[i], d.qpos)
        # contact sensors read what mj_contactForce reads, on every watched geom
        reference = native_contact_forces(model, d, env.watched_geoms)
        assert np.allclose(view["contact_force"][i], reference, rtol=1e-5, atol=1e-4), (view["contact_force"][i], reference)


def test_same_states_with_one_or_two_threads(flat):
    """The same seed gives the same physics with 1 or 2 threads (bit for bit)."""
    out = []
    for threads in (1, 2):
        vector = VectorEnv(flat.env, BATCH, "native", threads)
        batch = vector.reset(jax.random.PRNGKey(3))
        rng = np.random.default_rng(1)
        for _ in range(10):
            batch, _ = vector.step(batch, jnp.asarray(rng.uniform(-1, 1, (BATCH, 12)), jnp.float32))
        out.append(np.asarray(batch.state.pipeline_state.qpos))
    assert np.array_equal(out[0], out[1])


def test_derived_fields_describe_the_state_before_the_last_substep(flat):
    """In both engines, xpos after a control step is the kinematics of the state before its last substep
    (as after mj_step), while qpos is the state after it."""
    env = flat.env
    state = flat.reset(flat.keys(2))
    action = jnp.asarray(np.random.default_rng(2).uniform(-1, 1, (BATCH, 12)), jnp.float32)
    mjx_next = flat.step(state, action)
    native = NativeEnvs(env, BATCH)
    nstate = native.reset(flat.keys(2))
    native_next = native.step(nstate, action)
    model, data = env.mj_model, mujoco.MjData(env.mj_model)
    for engine, nxt in (("mjx", mjx_next), ("native", native_next)):
        data.qpos[:] = np.asarray(nstate.pipeline_state.qpos[0])
        data.qvel[:] = np.asarray(nstate.pipeline_state.qvel[0])
        data.ctrl[:] = np.asarray(env.joint_targets(action[0]))
        for _ in range(env.n_substeps - 1):
            mujoco.mj_step(model, data)
        mujoco.mj_kinematics(model, data)
        before_last = data.xpos.copy()
        mujoco.mj_step(model, data)
        mujoco.mj_kinematics(model, data)  # the kinematics of the state after the last substep
        xpos = np.asarray(nxt.pipeline_state.xpos[0])
        assert np.allclose(xpos, before_last, atol=2e-4), engine
        assert not np.allclose(xpos, data.xpos, atol=1e-6), engine
        assert np.allclose(np.asarray(nxt.pipeline_state.qpos[0]), data.qpos, atol=2e-4), engine


def test_contact_forces_agree_between_engines_on_the_plane(flat):
    """Standing on the plane, the feet carry the robot's weight in both engines' read-outs."""
    env = flat.env
    state = flat.reset(flat.keys(0))
    native = NativeEnvs(env, BATCH)
    nstate = native.reset(flat.keys(0))
    zero = jnp.zeros((BATCH, env.action_size))
    for _ in range(25):
        state, nstate = flat.step(state, zero), native.step(nstate, zero)
    mjx_feet = np.asarray(flat.contact_forces(state.pipeline_state))[:, :4].sum(-1)
    native_feet = np.asarray(nstate.pipeline_state.contact_force)[:, :4].sum(-1)
    weight = env._weight
    assert np.allclose(mjx_feet, weight, rtol=0.1) and np.allclose(native_feet, weight, rtol=0.1)


def test_divergence_is_caught_per_simulation(flat):
    """A simulation pushed to an absurd velocity is flagged and shows its last good state; the others step on."""
    env = flat.env
    native = NativeEnvs(env, 3)
    native.reset(jax.random.split(jax.random.PRNGKey(0), 3))
    physics = native.physics
    before = physics.batch.bind("qpos").copy()
    physics.batch.bind("qvel")[1, 0] = 1e9
    view, bad = physics.step(np.tile(np.asarray(env._default_pose), (3, 1)))
    assert bad.tolist() == [False, True, False]
    assert np.allclose(view["qpos"][1], before[1].astype(np.float32))
    assert np.all(np.isfinite(view["qpos"]))


def test_randomised_model_fields_reach_each_simulation():
    """Domain randomisation in native physics: each simulation gets its own masses and gains (expand)."""
    from legged.envs.config import RandomizationConfig

    env = make("go1-flat", randomization=RandomizationConfig(enabled=True))
    native = NativeEnvs(env, 4)
    state = native.reset(jax.random.split(jax.random.PRNGKey(5), 4))
    trunk = env._trunk
    masses = native.physics.batch.expand("body_mass")[:, trunk]
    nominal = env.mj_model.body_mass[trunk]
    expected = (nominal * np.asarray(state.info["dr"]["mass_scale"])[:, trunk]
                + np.asarray(state.info["dr"]["base_mass"]))
    assert np.allclose(masses, expected, rtol=1e-5)
    assert len(np.unique(np.round(masses, 6))) == 4
    kp = native.physics.batch.expand("actuator_gainprm")[:, 0, 0]
    assert np.allclose(kp, env.robot.kp * np.asarray(state.info["dr"]["kp"]) * np.asarray(state.info["dr"]["strength"])[:, 0],
                       rtol=1e-5)


def test_bad_physics_inputs_are_one_line_errors():
    with pytest.raises(ValueError, match="unknown physics 'warp'"):
        VectorEnv(object(), 4, "warp")
    with pytest.raises(ValueError, match="threads must be >= 1"):
        check_threads(0)
    with pytest.raises(ConfigError, match="--backend brax needs --physics mjx"):
        TrainConfig(task="go1-flat", backend="brax", physics="native").resolved()
    with pytest.raises(ConfigError, match="physics must be"):
        TrainConfig(task="go1-flat", physics="gpu").resolved()
    with pytest.raises(ConfigError, match="soccer-1v1-vision trains with --backend rsl"):
        TrainConfig(task="soccer-1v1-vision", backend="brax").resolved()


def test_dashboard_records_native_rollouts(flat):
    """The dashboard's recorder rolls out with native physics too (the same trajectories, no MJX physics)."""
    from web.rollout import Recorder, RecorderConfig

    native = Recorder(flat.env, "go1-flat", RecorderConfig(num_envs=2, physics="native")).record(5, seed=1)
    assert native.qpos.shape == (6, 2, flat.env.mj_model.nq)
    assert np.all(np.isfinite(native.qpos)) and not native.done.any()
    with pytest.raises(ValueError, match="unknown physics"):
        Recorder(flat.env, "go1-flat", RecorderConfig(physics="gpu"))


def test_soak_counts_what_reaches_the_learner():
    """A short soak under randomisation with bang-bang actions: nothing non-finite reaches the learner."""
    from legged.bench import soak

    report = soak("go1-flat", steps=400, batch=8, seed=1)
    assert report["env_steps"] == 400 and report["randomization"] and report["physics"] == "native"
    assert report["non_finite_values"] == 0
    assert report["episodes"] >= 0 and report["diverged_episodes"] <= report["episodes"]


def test_resetting_a_few_environments_equals_resetting_all(flat):
    """Auto-reset of a few environments (observed in a padded sub-batch) gives those environments the same
    first states as a full reset with the same keys, and leaves the others alone."""
    env = flat.env
    native = NativeEnvs(env, BATCH)
    state = native.reset(flat.keys(0))
    for _ in range(3):
        state = native.step(state, jnp.zeros((BATCH, env.action_size)))
    keys = flat.keys(9)
    partial = native.reset(keys, np.array([1, 5]), state)
    full = NativeEnvs(env, BATCH).reset(keys)
    for name, a, b, c in zip(("qpos", "obs", "info step"), (partial.pipeline_state.qpos, partial.obs["state"],
                             partial.info["step"]), (full.pipeline_state.qpos, full.obs["state"], full.info["step"]),
                             (state.pipeline_state.qpos, state.obs["state"], state.info["step"])):
        assert np.allclose(np.asarray(a)[[1, 5]], np.asarray(b)[[1, 5]], atol=1e-6), name
        keep = [0, 2, 3, 4, 6, 7]
        assert np.array_equal(np.asarray(a)[keep], np.asarray(c)[keep]), name
    assert np.allclose(native.physics.batch.bind("qpos")[[1, 5]], np.asarray(full.pipeline_state.qpos)[[1, 5]],
                       atol=1e-6)
