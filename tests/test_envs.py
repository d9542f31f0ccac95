"""MJX environments: jit + vmap, shapes and dtypes, stability, determinism, standing, divergence."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.tasks import TASKS, UnknownTaskError, default_config, make
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.paths import straight_path
from legged.worlds import Terrain, generate_world


def test_shapes_and_dtypes(flat, confined):
    for c, state_size in ((flat, 3 + 3 + 36), (confined, 261)):
        state = c.reset(c.keys())
        assert state.obs["state"].shape == (8, state_size)
        assert state.obs["privileged_state"].shape[1] > state_size
        assert state.obs["state"].dtype == jnp.float32
        state = c.step(state, jnp.zeros((8, 12)))
        assert state.reward.shape == (8,) and state.done.shape == (8,)
        assert all(v.shape == (8,) for v in state.metrics.values())
        assert c.env.observation_size["state"] == (state_size,)


def test_reset_is_deterministic(confined):
    a, b = confined.reset(confined.keys(5)), confined.reset(confined.keys(5))
    assert jnp.array_equal(a.obs["state"], b.obs["state"])
    assert jnp.array_equal(a.pipeline_state.qpos, b.pipeline_state.qpos)
    c = confined.reset(confined.keys(6))
    assert not jnp.array_equal(a.pipeline_state.qpos, c.pipeline_state.qpos)


@pytest.mark.parametrize("name", ["flat", "confined"])
def test_no_nan_under_random_actions(name, request):
    c = request.getfixturevalue(name)
    state = c.reset(c.keys(1))
    key = jax.random.PRNGKey(2)
    steps = 0
    for _ in range(400):  # 8 envs x 400 steps = 3200 env steps
        key, k = jax.random.split(key)
        state = c.step(state, jax.random.uniform(k, (8, 12), minval=-1.0, maxval=1.0))
        if bool(state.done.any()):  # auto-reset by hand: re-spawn envs that finished
            fresh = c.reset(jax.random.split(k, 8))
            state = jax.tree_util.tree_map(
                lambda f, s: jnp.where(state.done.reshape((-1,) + (1,) * (s.ndim - 1)) > 0, f, s), fresh, state)
        steps += 8
        for part in (state.obs["state"], state.obs["privileged_state"], state.reward):
            assert bool(jnp.all(jnp.isfinite(part)))
    assert steps >= 3000
    assert float(state.metrics["diverged"].sum()) == 0.0


@pytest.mark.parametrize("name", ["flat", "confined"])
def test_go1_stands_under_zero_action(name, request):
    c = request.getfixturevalue(name)
    state = c.reset(c.keys(0))
    for _ in range(100):  # 2 s
        state = c.step(state, jnp.zeros((8, 12)))
    assert float(state.done.sum()) == 0
    height = np.asarray(state.metrics["base_height"])
    assert np.all(height > 0.22) and np.all(height < 0.32), height
    up = np.asarray(state.pipeline_state.xmat[:, c.env._trunk, 2, 2])
    assert np.all(up > 0.98)
    q = np.asarray(state.pipeline_state.qpos[:, 7:])
    assert np.abs(q - np.asarray(c.env.robot.default_pose)).max() < 0.35  # Kp 20 sags a little
    assert np.abs(np.asarray(state.pipeline_state.qvel)).max() < 0.05  # at rest


def test_divergence_is_detected_and_contained(confined):
    state = confined.reset(confined.keys(0))
    data = state.pipeline_state
    thrown = state.replace(pipeline_state=data.replace(qvel=data.qvel.at[0, 0].set(1e4)))
    out = confined.step(thrown, jnp.zeros((8, 12)))
    assert out.done.tolist() == [1.0] + [0.0] * 7
    assert out.metrics["diverged"].tolist() == [1.0] + [0.0] * 7
    assert bool(jnp.all(jnp.isfinite(out.obs["state"]))) and bool(jnp.all(jnp.isfinite(out.reward)))


def test_waypoints_advance_when_reached(confined):
    env = confined.env
    state = confined.reset(confined.keys(0))
    tile = int(state.info["tile"][0])
    wp = np.asarray(env._paths[tile, 1])
    data = state.pipeline_state
    qpos = data.qpos.at[0, 0:2].set(jnp.asarray(wp[:2]))
    moved = data.replace(qpos=qpos, xpos=data.xpos.at[0, env._trunk, 0:2].set(jnp.asarray(wp[:2])))
    out = confined.transition(state, confined.view(moved), jnp.zeros((8, 12)))
    assert int(out.info["waypoint"][0]) == 2
    assert out.info["waypoint"][1:].tolist() == [1] * 7
    assert float(out.metrics["reward/waypoint_reached"][0]) == env.config.rewards.waypoint_reached


def test_task_registry_and_errors():
    assert {"go1-flat", "confined-waypoints", "confined-goal", "confined-velocity", "confined-skills"} <= set(TASKS)
    with pytest.raises(UnknownTaskError, match="known tasks"):
        make("confined-typo")
    assert default_config("confined-skills").mode == "skills"
    with pytest.raises(ValueError, match="whole multiple"):
        dataclasses.replace(default_config("go1-flat"), ctrl_dt=0.021).n_substeps


def test_paths_must_match_the_worlds():
    terrain = Terrain.from_worlds([generate_world(1, 0)])
    wrong = straight_path(terrain.starts[0], terrain.goals[0] + [1.0, 0.0, 0.0], 0.5)
    with pytest.raises(ValueError, match="goal"):
        ConfinedEnv(ConfinedConfig(), terrain=terrain, paths=[wrong])
    with pytest.raises(ValueError, match="paths for a terrain"):
        ConfinedEnv(ConfinedConfig(), terrain=terrain, paths=[])
