"""Soccer game states as native MjData, for inspection (camera images) without compiling MJX."""

from __future__ import annotations

import jax
import mujoco
import numpy as np


def game_start(env, seed: int) -> mujoco.MjData:
    """The forward-computed start of the game that `env.reset(jax.random.PRNGKey(seed))` begins (the same
    robot and ball placement, computed eagerly with the env's own start rule, no MJX compilation)."""
    spawn = env.spawn(jax.random.split(jax.random.PRNGKey(seed))[0])  # as MjxEnv.reset splits its key
    data = mujoco.MjData(env.mj_model)
    data.qpos[:] = np.asarray(spawn.qpos)
    data.qvel[:] = np.asarray(spawn.qvel)
    data.ctrl[:] = np.asarray(spawn.ctrl)
    mujoco.mj_forward(env.mj_model, data)
    return data
