"""Native-MuJoCo soccer: `mujoco.mj_step` physics with the MJX environment's own rules, rewards and
observations (its `reset` and `transition`, jitted once for one game)."""

from __future__ import annotations

import jax
import mujoco
import numpy as np
from brax.envs.base import State

from legged.envs.native import with_native_fields
from legged.soccer.env import SoccerEnv


class NativeSoccer:
    """One game of `env` stepped by native MuJoCo."""

    def __init__(self, env: SoccerEnv):
        self.env = env
        self.model = env.mj_model
        self.data = mujoco.MjData(self.model)
        self._reset = jax.jit(env.reset)
        self._transition = jax.jit(env.transition)
        self._targets = jax.jit(env.joint_targets)
        self.state: State | None = None

    def reset(self, seed: int) -> State:
        """Start a game from the environment's reset for PRNG seed `seed`."""
        self.state = self._reset(jax.random.PRNGKey(seed))
        self._load(self.state.pipeline_state)
        return self.state

    def _load(self, mjx_data) -> None:
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = np.asarray(mjx_data.qpos)
        self.data.qvel[:] = np.asarray(mjx_data.qvel)
        self.data.ctrl[:] = np.asarray(mjx_data.ctrl)
        mujoco.mj_forward(self.model, self.data)

    def step(self, actions) -> State:
        """One control step for actions [n_agents, action_size]; restarts (goal, ball out) carry over."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        actions = np.asarray(actions, np.float32)
        if actions.shape != (self.env.n_agents, self.env.action_size):
            raise ValueError(f"actions must have shape ({self.env.n_agents}, {self.env.action_size}), "
                             f"got {actions.shape}")
        self.data.ctrl[:] = np.asarray(self._targets(actions))
        for _ in range(self.env.n_substeps):
            mujoco.mj_step(self.model, self.data)
        self.state = self._transition(self.state, with_native_fields(self.state.pipeline_state, self.data), actions)
        restarted = not np.array_equal(np.asarray(self.state.pipeline_state.qpos, np.float32),
                                       self.data.qpos.astype(np.float32))
        if restarted:  # the rules moved robots or ball (kick-off, ball back in play)
            self._load(self.state.pipeline_state)
        return self.state
