"""MJX stepping against native MuJoCo stepping (the batched engine) of the same task, actions and keys."""

import jax.numpy as jnp
import numpy as np

from legged.envs.native import NativeEnvs

FLAT_QPOS_TOL = 1e-3
"""Max |qpos| gap after 25 control steps (100 physics steps) on the plane, random actions."""
CONFINED_BASE_TOL = 0.05
"""Max base position gap (m) after 5 control steps on height fields. MJX and native MuJoCo generate
height-field contacts differently (docs/environments.md, "MJX vs native MuJoCo"): measured 0.028 m for the base and 0.088 rad
for the joints after 5 steps, so only the base is held to a (loose) bound here."""


def _compare(compiled, steps, seed=0):
    """Step a batch in MJX and natively from the same reset keys; max gaps in qpos, base, reward."""
    env = compiled.env
    batch = compiled.reset(compiled.keys(seed))
    native = NativeEnvs(env, len(batch.reward))
    nstate = native.reset(compiled.keys(seed))  # the same keys: the same first states
    assert np.allclose(batch.pipeline_state.qpos, nstate.pipeline_state.qpos, atol=1e-6)
    assert np.allclose(batch.obs["state"], nstate.obs["state"], atol=1e-4)
    rng = np.random.default_rng(seed)
    gap, base_gap, reward_gap = 0.0, 0.0, 0.0
    for _ in range(steps):
        action = jnp.asarray(rng.uniform(-0.5, 0.5, (len(batch.reward), env.action_size)), jnp.float32)
        batch, nstate = compiled.step(batch, action), native.step(nstate, action)
        diff = jnp.abs(batch.pipeline_state.qpos - nstate.pipeline_state.qpos)
        gap, base_gap = max(gap, float(diff.max())), max(base_gap, float(diff[:, :3].max()))
        reward_gap = max(reward_gap, float(jnp.abs(batch.reward - nstate.reward).max()))
    return gap, base_gap, reward_gap


def test_flat_mjx_matches_native(flat):
    gap, _, reward_gap = _compare(flat, 25)
    assert gap < FLAT_QPOS_TOL, gap
    assert reward_gap < 1e-2, reward_gap


def test_confined_mjx_matches_native_short_horizon(confined):
    _, base_gap, _ = _compare(confined, 5)
    assert base_gap < CONFINED_BASE_TOL, base_gap
