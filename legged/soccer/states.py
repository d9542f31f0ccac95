"""Soccer game states as native MjData, for inspection (camera images) without compiling MJX."""

from __future__ import annotations

import jax
import mujoco
import numpy as np


def game_start(env, seed: int) -> mujoco.MjData:
    """The forward-computed start of the game that `env.reset(jax.random.PRNGKey(seed))` begins (the same
    robot and ball placement, computed eagerly with the env's own start rule, no MJX compilation)."""
    k_start = jax.random.split(jax.random.PRNGKey(seed), 3)[1]
    qpos, qvel = env.start_state(k_start)
    data = mujoco.MjData(env.mj_model)
    data.qpos[:] = np.asarray(qpos)
    data.qvel[:] = np.asarray(qvel)
    data.ctrl[:] = env.layout.default_ctrl(env.mj_model, env.robot)
    mujoco.mj_forward(env.mj_model, data)
    return data
