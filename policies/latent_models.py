"""Actors with a latent: an encoder turns one observation group into z, and an MLP head acts on (state, z).

One rsl-rl model class serves the teacher and the students (rsl-rl builds it from `class_name`):
- the teacher encodes `privileged_state` into z_p (deterministic);
- HIB and its ablation encode the `history` into a Gaussian q(z | h): z = mean + std * noise while training,
  the noise read from the `latent_noise` observation (so the rollout stores it and PPO's ratio is computed
  on the same z), and z = mean when deployed (eval mode);
- the RMA student encodes the `history` deterministically and acts with the teacher's head.
With `privileged_embedding`, the model also holds HIB's embedding of `privileged_state` for the InfoNCE bound
(policies.hib); it is trained with the actor but never used to act.

`privileged_state` begins with a clean copy of `state` (legged.envs.base: observation_layout); the teacher's
encoder and HIB's embedding read only what follows it (velocities, contacts, randomised dynamics, terrain), so
that z_p, and the InfoNCE match, carry what the state cannot tell rather than a denoised copy of it.
"""

from __future__ import annotations

import torch
from rsl_rl.models import MLPModel
from rsl_rl.modules import MLP, EmpiricalNormalization
from rsl_rl.utils import resolve_nn_activation
from tensordict import TensorDict

NOISE_GROUP = "latent_noise"
"""Observation group of the standard-normal noise of Gaussian latents (added by policies.rsl_vecenv)."""


class HistoryConv(torch.nn.Module):
    """A history encoder shaped like RMA's adaptation module: each step's features embedded (linear +
    activation), then 1-D convolutions over time (`channels` wide; kernels 8, 5, 5, strides 4, 1, 1, as many
    as the history is long enough for), flattened, and a linear output. The windows end at the newest step:
    where the strides leave steps over, they are the oldest. Input: [..., steps * features], oldest step first.

    A convolution is a linear layer on each window (`Tensor.unfold`), kept in [batch, time, channels] layout:
    on the CPU this trains about twice as fast as `Conv1d`, which needs channel-first copies."""

    LAYERS = ((8, 4), (5, 1), (5, 1))
    """(kernel, stride) of the convolutions over time."""

    def __init__(self, steps: int, features: int, output_dim: int, activation: str = "elu", channels: int = 32):
        super().__init__()
        self.steps, self.features = steps, features
        self.embed = torch.nn.Linear(features, channels)
        self.activation = resolve_nn_activation(activation)
        self.windows, self.convs, length = [], torch.nn.ModuleList(), steps
        for kernel, stride in self.LAYERS:
            if length < kernel:
                break
            self.windows.append((kernel, stride, (length - kernel) % stride))  # the last: oldest steps left over
            self.convs.append(torch.nn.Linear(channels * kernel, channels))
            length = (length - kernel) // stride + 1
        self.output = torch.nn.Linear(channels * length, output_dim)

    def forward(self, history: torch.Tensor) -> torch.Tensor:
        lead = history.shape[:-1]
        x = self.activation(self.embed(history.reshape(-1, self.steps, self.features)))  # [B, steps, channels]
        exporting = torch.onnx.is_in_onnx_export()
        for conv, (kernel, stride, skip) in zip(self.convs, self.windows):
            if exporting:  # ONNX has no Unfold: the same windows gathered by index (Gather), [B, length, kernel, C]
                starts = torch.arange(skip, x.shape[1] - kernel + 1, stride)
                windows = x[:, starts[:, None] + torch.arange(kernel)[None]].transpose(2, 3)
            else:
                windows = x[:, skip:].unfold(1, kernel, stride)                        # [B, length, channels, kernel]
            x = self.activation(conv(windows.reshape(windows.shape[0], windows.shape[1], -1)))
        return self.output(x.flatten(1)).reshape(*lead, -1)


class LatentActor(MLPModel):
    """MLP head on (normalised `state`, z), z from an encoder of a second observation group (an MLP, or for
    the `history` group with `history_encoder="conv"` a HistoryConv)."""

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, *, latent_dim: int,
                 encoder_hidden: list, gaussian: bool = False, privileged_embedding: int = 0,
                 history_encoder: str = "mlp", **mlp_kwargs):
        groups = [g for g in obs_groups[obs_set] if g != NOISE_GROUP]
        if len(groups) != 2 or groups[0] != "state":
            raise ValueError(f"a LatentActor reads 'state' and one group to encode, got {obs_groups[obs_set]}")
        super().__init__(obs, {obs_set: groups}, obs_set, output_dim, **mlp_kwargs)
        activation = mlp_kwargs.get("activation", "elu")
        self.state_dim = obs["state"].shape[-1]
        self.latent_dim, self.gaussian = latent_dim, gaussian
        # where the encoded part of [state, group] starts: past the state, and past privileged_state's copy of it
        self.encoded_from = self.state_dim * (2 if groups[1] == "privileged_state" else 1)
        encoded = obs["state"].shape[-1] + obs[groups[1]].shape[-1] - self.encoded_from
        out = latent_dim * (2 if gaussian else 1)
        if groups[1] == "history" and history_encoder == "conv":
            self.encoder = HistoryConv(encoded // self.state_dim, self.state_dim, out, activation)
        else:
            self.encoder = MLP(encoded, out, encoder_hidden, activation)
        head = MLP(self.state_dim + latent_dim, self.mlp[-1].out_features, mlp_kwargs.get("hidden_dims"), activation)
        self.mlp = head
        if self.distribution is not None:
            self.distribution.init_mlp_weights(self.mlp)
        self.embedding = None
        if privileged_embedding:
            size = obs["privileged_state"].shape[-1] - self.state_dim
            self.embedding_normalizer = EmpiricalNormalization(size)
            self.embedding = MLP(size, privileged_embedding, encoder_hidden, activation)
            self.projection = MLP(latent_dim, privileged_embedding, [max(encoder_hidden[-1], latent_dim)], activation)
        self.latent_mean = self.latent_log_std = self.latent = None

    def encode(self, obs: TensorDict) -> tuple[torch.Tensor, torch.Tensor | None, torch.Tensor]:
        """(mean of z, its log std or None when deterministic, the normalised state)."""
        x = self.obs_normalizer(torch.cat([obs[g] for g in self.obs_groups], dim=-1))
        out = self.encoder(x[..., self.encoded_from:])
        if not self.gaussian:
            return out, None, x[..., :self.state_dim]
        mean, log_std = out.split(self.latent_dim, dim=-1)
        return mean, log_std.clamp(-8.0, 4.0), x[..., :self.state_dim]

    def get_latent(self, obs: TensorDict, masks=None, hidden_state=None) -> torch.Tensor:
        """The head's input (state, z); z is sampled with the observed noise in train mode, else the mean. The
        last z and (Gaussian) its mean and log std stay on the model for the HIB loss."""
        mean, log_std, state = self.encode(obs)
        self.latent_mean, self.latent_log_std = mean, log_std
        self.latent = mean + log_std.exp() * obs[NOISE_GROUP] if self.gaussian and self.training else mean
        return torch.cat([state, self.latent], dim=-1)

    def update_normalization(self, obs: TensorDict) -> None:
        super().update_normalization(obs)
        if self.embedding is not None and self.obs_normalization:
            self.embedding_normalizer.update(obs["privileged_state"][..., self.state_dim:])

    def embed_privileged(self, privileged: torch.Tensor) -> torch.Tensor:
        """HIB's embedding of the privileged state past its copy of the state (for the InfoNCE bound)."""
        return self.embedding(self.embedding_normalizer(privileged[..., self.state_dim:]))

    def as_onnx(self, verbose: bool = False) -> torch.nn.Module:
        return DeployedLatentActor(self)

    def as_jit(self) -> torch.nn.Module:
        return DeployedLatentActor(self)


class DeployedLatentActor(torch.nn.Module):
    """A LatentActor for deployment and export: inputs (state, encoded group), mean z, deterministic action."""

    is_recurrent = False

    def __init__(self, model: LatentActor):
        super().__init__()
        import copy

        self.normalizer, self.encoder, self.head = (copy.deepcopy(m) for m in (model.obs_normalizer, model.encoder,
                                                                                model.mlp))
        self.output = (model.distribution.as_deterministic_output_module() if model.distribution is not None
                       else torch.nn.Identity())
        self.state_dim, self.latent_dim, self.gaussian = model.state_dim, model.latent_dim, model.gaussian
        self.encoded_from = model.encoded_from
        self.input_names = list(model.obs_groups)

    def _state_and_latent(self, state: torch.Tensor, encoded: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = self.normalizer(torch.cat([state, encoded], dim=-1))
        return x[..., :self.state_dim], self.encoder(x[..., self.encoded_from:])[..., :self.latent_dim]

    def latent(self, state: torch.Tensor, encoded: torch.Tensor) -> torch.Tensor:
        """Mean z."""
        return self._state_and_latent(state, encoded)[1]

    def forward(self, state: torch.Tensor, encoded: torch.Tensor) -> torch.Tensor:
        return self.output(self.head(torch.cat(self._state_and_latent(state, encoded), dim=-1)))


class ConcatInputs(torch.nn.Module):
    """A deployed rsl-rl MLP actor on several observation groups, taking them as separate inputs."""

    is_recurrent = False

    def __init__(self, module: torch.nn.Module, input_names: list[str]):
        super().__init__()
        self.module, self.input_names = module, list(input_names)

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        return self.module(torch.cat(inputs, dim=-1))


def deployed_actor(model: MLPModel) -> torch.nn.Module:
    """The deterministic actor of an rsl-rl model as a module with one input per observation group (the same
    order as `model.obs_groups`), in eval mode."""
    if isinstance(model, LatentActor):
        return DeployedLatentActor(model).eval()
    inner = model.as_onnx(verbose=False).eval()
    if len(model.obs_groups) == 1 or hasattr(model, "obs_groups_2d"):  # CNN actors take (state, images)
        return inner
    return ConcatInputs(inner, model.obs_groups).eval()


def latent_features(model: MLPModel, obs: TensorDict) -> torch.Tensor | None:
    """What a probe reads from an actor: the mean z of a LatentActor, else the MLP's last hidden layer; None for
    image and memory actors (their latent needs the images or the memory of the rollout, not one flat batch)."""
    from rsl_rl.models import CNNModel

    with torch.no_grad():
        if isinstance(model, LatentActor):
            return model.encode(obs)[0]
        if isinstance(model, CNNModel) or getattr(model, "is_recurrent", False):
            return None
        x = MLPModel.get_latent(model, obs)
        for layer in list(model.mlp)[:-1]:
            x = layer(x)
        return x


def deployed_features(module: torch.nn.Module, *inputs: torch.Tensor) -> torch.Tensor | None:
    """`latent_features` of a deployed actor (`deployed_actor`): mean z, or the last hidden layer of an MLP;
    None for image actors."""
    if isinstance(module, DeployedLatentActor):
        return module.latent(*inputs)
    if isinstance(module, ConcatInputs):
        module, x = module.module, torch.cat(inputs, dim=-1)
    elif len(inputs) == 1:
        x = inputs[0]
    else:  # an image actor
        return None
    if not hasattr(module, "mlp"):
        return None
    x = module.obs_normalizer(x)
    for layer in list(module.mlp)[:-1]:
        x = layer(x)
    return x
