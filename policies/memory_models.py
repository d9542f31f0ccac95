"""Vision actors with memory: a camera encoder whose features, with the state, feed a GRU.

A player that sees its game through a 56-degree head camera seldom has the ball and a goal in view together;
its state teacher always knows both. `MemoryCNNModel` (the actor of a vision student with
`distill.student_memory` > 0) gives it memory, as the anchors' vision players have (Tirumala et al. 2024): the
image's CNN features and the normalised state go through a GRU, and the MLP head reads the GRU's output beside
the current features (the present need not pass through the memory). rsl-rl's Distillation trains it by
truncated backpropagation through time (`distill.gradient_length` steps); rsl-rl's PPO (`--method kl`) on the
padded trajectories of its rollouts.

`DeployedMemoryActor` is its deterministic actor for deployment and export: (state, camera, memory) ->
(actions, memory), the memory a [1, n, memory_dim] tensor that starts at zero in every episode.
"""

from __future__ import annotations

import copy

import torch
from rsl_rl.models import CNNModel
from rsl_rl.modules import RNN
from rsl_rl.utils import unpad_trajectories
from tensordict import TensorDict


class MemoryCNNModel(CNNModel):
    """rsl-rl CNNModel with a GRU between its features (normalised 1D groups, CNN of the 2D groups) and its MLP
    head; the head reads [GRU output, features]."""

    is_recurrent = True

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, memory_dim: int = 128,
                 **kwargs):
        self.memory_dim = memory_dim
        super().__init__(obs, obs_groups, obs_set, output_dim, **kwargs)
        self.rnn = RNN(self.obs_dim + self.cnn_latent_dim, memory_dim, 1, "gru")

    def get_latent(self, obs: TensorDict, masks=None, hidden_state=None) -> torch.Tensor:
        """[GRU output, features] of one step of every environment, or (PPO's update: `masks` and the
        trajectories' first `hidden_state`) of the valid steps of padded trajectories [time, trajectories]."""
        if masks is None:
            features = super().get_latent(obs)
            return torch.cat([self.rnn(features, None, hidden_state).squeeze(0), features], dim=-1)
        steps = obs.batch_size[:2]  # the CNN reads images [n, channels, height, width]: fold time into n
        features = super().get_latent(obs.flatten(0, 1)).unflatten(0, steps)
        memory = self.rnn(features, masks, hidden_state)
        return torch.cat([memory, unpad_trajectories(features, masks)], dim=-1)

    def reset(self, dones: torch.Tensor | None = None, hidden_state=None) -> None:
        """Forget the episodes that ended (`dones`), or set the memory of every environment."""
        self.rnn.reset(dones, hidden_state)

    def get_hidden_state(self):
        """The GRU's memory, [1, n, memory_dim] (None before the first step)."""
        return self.rnn.hidden_state

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        """Cut the backpropagation through time here (for every environment, or those in `dones`)."""
        self.rnn.detach_hidden_state(dones)

    def _get_latent_dim(self) -> int:
        return self.memory_dim + super()._get_latent_dim()

    def as_onnx(self, verbose: bool = False) -> torch.nn.Module:
        return DeployedMemoryActor(self)

    def as_jit(self) -> torch.nn.Module:
        raise ValueError("a memory actor has no TorchScript export: use `legged export --onnx` (DeployedMemoryActor, "
                         "whose memory is an input and an output)")


class DeployedMemoryActor(torch.nn.Module):
    """A MemoryCNNModel for deployment and export: (state, camera, memory) -> (deterministic actions, memory)."""

    is_recurrent = True

    def __init__(self, model: MemoryCNNModel):
        super().__init__()
        if len(model.obs_groups_2d) != 1 or list(model.obs_groups) != ["state"]:
            raise ValueError(f"a deployed memory actor reads `state` and one image group, this one reads "
                             f"{model.obs_groups} and {model.obs_groups_2d}")
        self.normalizer, self.cnn, self.gru, self.head = (copy.deepcopy(m) for m in (
            model.obs_normalizer, model.cnns[model.obs_groups_2d[0]], model.rnn.rnn, model.mlp))
        self.output = (model.distribution.as_deterministic_output_module() if model.distribution is not None
                       else torch.nn.Identity())
        self.memory_dim = model.memory_dim

    def initial_memory(self, n: int) -> torch.Tensor:
        """The memory of `n` new episodes (zeros)."""
        return torch.zeros(1, n, self.memory_dim)

    def forward(self, state: torch.Tensor, camera: torch.Tensor,
                memory: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        features = torch.cat([self.normalizer(state), self.cnn(camera)], dim=-1)
        out, memory = self.gru(features.unsqueeze(0), memory)
        return self.output(self.head(torch.cat([out.squeeze(0), features], dim=-1))), memory
