"""Native-MuJoCo execution of an environment: native physics, the env's own observation/reward code.

Physics runs in `mujoco.mj_step` on the same MjModel the MJX env was built from (with the episode's
randomisation applied); the stepped MjData is converted with `mjx.put_data` and handed to the env's
`transition`, so observations, rewards, terminations and metrics are the same code as in training.
Used for evaluation and sim-to-sim checks.
"""

from __future__ import annotations

import copy

import jax
import mujoco
import numpy as np
from brax.envs.base import State

from legged.envs.base import LeggedEnv, randomized_fields
from legged.envs.contacts import native_contact_forces


class NativeRunner:
    """Steps one episode of `env` with native MuJoCo physics."""

    def __init__(self, env: LeggedEnv):
        self.env = env
        self.model = copy.deepcopy(env.mj_model)
        self.data = mujoco.MjData(self.model)
        self._nominal = {k: np.array(getattr(env.mj_model, k)) for k in (
            "body_mass", "body_inertia", "body_ipos", "pair_friction", "actuator_gainprm", "actuator_biasprm")}
        self._geoms = np.concatenate([env._feet, env._body_geoms])
        self._reset = jax.jit(env.reset)
        self._transition = jax.jit(env.transition)
        self._targets = jax.jit(env.joint_targets)
        self.state: State | None = None

    def reset(self, rng: jax.Array) -> State:
        """Start an episode: the env's own reset, copied into native MjData."""
        return self.start(self._reset(rng))

    def start(self, state: State) -> State:
        """Continue from an existing (unbatched) environment state, e.g. one made by the MJX env."""
        dr = jax.tree_util.tree_map(np.asarray, state.info["dr"])
        if self.env.config.randomization.enabled:
            for name, value in randomized_fields(self._nominal, dr, self.env._trunk, xp=np).items():
                getattr(self.model, name)[:] = value
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = np.asarray(state.pipeline_state.qpos)
        self.data.qvel[:] = np.asarray(state.pipeline_state.qvel)
        self.data.ctrl[:] = np.asarray(state.pipeline_state.ctrl)
        mujoco.mj_forward(self.model, self.data)
        self.state = state
        return state

    def step(self, action) -> State:
        """One control step: PD targets, `n_substeps` native physics steps, then the shared transition."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        self.data.ctrl[:] = np.asarray(self._targets(action))
        for _ in range(self.env.n_substeps):
            mujoco.mj_step(self.model, self.data)
        forces = native_contact_forces(self.model, self.data, self._geoms)
        data = with_native_fields(self.state.pipeline_state, self.data)
        self.state = self._transition(self.state, data, action, forces.astype(np.float32))
        return self.state


def with_native_fields(mjx_data, data: mujoco.MjData):
    """`mjx_data` with the fields the environments' transitions and cameras read copied from native `data`
    (state, controls, actuator forces, body, geom and camera poses; contacts are passed separately)."""
    return mjx_data.replace(
        qpos=data.qpos.copy(), qvel=data.qvel.copy(), ctrl=data.ctrl.copy(),
        xpos=data.xpos.copy(), xmat=data.xmat.reshape(-1, 3, 3).copy(),
        geom_xpos=data.geom_xpos.copy(), geom_xmat=data.geom_xmat.reshape(-1, 3, 3).copy(),
        cam_xpos=data.cam_xpos.copy(), cam_xmat=data.cam_xmat.reshape(-1, 3, 3).copy(),
        actuator_force=data.actuator_force.copy(), time=data.time)
