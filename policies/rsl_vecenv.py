"""rsl-rl's VecEnv over a `VectorEnv`: arrays cross between JAX and PyTorch through DLPack.

On a GPU both frameworks share the device memory (no copies); on the CPU DLPack shares host memory.
Observation groups: `state` (actor) and `privileged_state` (critic). `extras['time_outs']` marks episodes
cut by the time limit (rsl-rl bootstraps their value); `extras['log']` carries the mean of every
finished episode's statistics (return, length, each reward term, the task's metrics).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from legged.envs.vector import VectorEnv

OBS_GROUPS = {"actor": ["state"], "critic": ["privileged_state"]}
"""Asymmetric actor-critic: what the actor and the critic read."""


def to_torch(x: jax.Array, device: torch.device) -> torch.Tensor:
    """A JAX array as a torch tensor (shared memory through DLPack where the devices match)."""
    tensor = torch.from_dlpack(x)
    return tensor if tensor.device == device else tensor.to(device)


def to_jax(t: torch.Tensor) -> jax.Array:
    """A torch tensor as a JAX array through DLPack."""
    return jax.dlpack.from_dlpack(t.detach().contiguous())


class RslVecEnv(VecEnv):
    """rsl-rl interface to a batch of MJX environments (auto-reset, time-outs, episode logs)."""

    def __init__(self, vector: VectorEnv, seed: int, device: str = "cpu", cfg: dict | None = None):
        self.vector = vector
        self.num_envs = vector.num_envs
        self.num_actions = vector.env.action_size
        self.max_episode_length = vector.env.config.episode_steps
        self.device = torch.device(device)
        self.cfg = cfg or {}
        self.batch = vector.reset(jax.random.PRNGKey(seed))
        self._obs, self.last_result = self.batch.state.obs, None

    @property
    def episode_length_buf(self) -> torch.Tensor:
        return to_torch(self.batch.state.info["step"], self.device)

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        """Randomised initial episode lengths (rsl-rl's init_at_random_ep_len)."""
        self.batch.state.info["step"] = to_jax(value.to(torch.int32))

    def _observations(self, obs: dict) -> TensorDict:
        return TensorDict({k: to_torch(obs[k], self.device) for k in ("state", "privileged_state")},
                          batch_size=[self.num_envs], device=self.device)

    def get_observations(self) -> TensorDict:
        return self._observations(self._obs)

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        self.batch, result = self.vector.step(self.batch, to_jax(actions).astype(jnp.float32))
        self._obs, self.last_result = result.obs, result
        extras = {"time_outs": to_torch(result.time_out, self.device), "log": self._episode_log(result)}
        done = to_torch(result.done, self.device).long()
        return self.get_observations(), to_torch(result.reward, self.device), done, extras

    @staticmethod
    def _episode_log(result) -> dict:
        """Mean of each statistic over the episodes that ended this step ({} if none did)."""
        count = float(result.done.sum())
        if count == 0:
            return {}
        return {f"/episode/{k}": float(v.sum()) / count for k, v in result.finished.items()}

