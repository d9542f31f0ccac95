"""The Brax `Env` properties every environment here derives the same way (one place, not one per env)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from brax.envs.base import Env


class MjxEnv(Env):
    """Brax Env properties from `self.config.ctrl_dt`, `self.robot` and the observations `reset` returns."""

    @property
    def dt(self) -> float:
        """Control period, seconds."""
        return self.config.ctrl_dt

    @property
    def action_size(self) -> int:
        """Actions per robot (its actuated joints)."""
        return self.robot.num_joints

    @property
    def observation_size(self) -> dict:
        """Shape of each observation (traced once from `reset`, without compiling)."""
        if self.__dict__.get("_obs_size") is None:
            shapes = jax.eval_shape(self.reset, jax.random.PRNGKey(0)).obs
            self._obs_size = {k: v.shape for k, v in shapes.items()}
        return self._obs_size

    def observation_dims(self) -> dict:
        """Size of each observation: an int for vectors, a shape tuple otherwise (e.g. camera images)."""
        return {k: int(s[0]) if len(s) == 1 else tuple(int(d) for d in s) for k, s in self.observation_size.items()}

    @property
    def backend(self) -> str:
        return "mjx"


def reject_divergence(data, previous, limit: float):
    """(bad, data): `bad` when stepped physics `data` has a NaN or |qvel| above `limit`; then `data` is
    replaced by `previous` (the last good state), so a diverged environment never spreads NaNs."""
    bad = ~(jnp.all(jnp.isfinite(data.qpos)) & jnp.all(jnp.isfinite(data.qvel)) & jnp.all(jnp.abs(data.qvel) < limit))
    return bad, jax.tree_util.tree_map(lambda new, old: jnp.where(bad, old, new), data, previous)
