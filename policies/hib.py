"""HIB, the Historical Information Bottleneck (He et al., CoRL 2024), as a loss.

The history encoder q(z | h) should keep what predicts the privileged state s^p and drop the rest:
minimise  -I(Z; S^p) + alpha * I(H; Z), with the standard bounds:

- I(Z; S^p) >= log K - InfoNCE (K the candidates of each softmax),
  InfoNCE = -mean_i log softmax_j(sim(g(z_i), f(s^p_j)) / tau)_ii, where f
  embeds the privileged state, g projects z, sim is the cosine similarity and the other samples j of the
  mini-batch are the negatives. Samples of one episode share its randomised dynamics, so they would be false
  negatives of each other (many of them sit in every mini-batch): pairs whose randomised parameters are equal
  are left out of each softmax (the anchor's own pair is kept);
- I(H; Z) <= E KL(q(z | h) || N(0, I)) for the Gaussian encoder.

`loss = infonce_weight * InfoNCE + kl_weight * KL` is added to PPO's loss on every mini-batch, so the encoder
learns from both (one stage). z is sampled with noise that the rollout stored (policies.latent_models). With
`ib=False` (the hib-no-ib ablation) the encoder learns from the RL loss only: no KL, and InfoNCE trains only
the embedding and projection heads, on a detached z and with an optimiser of their own, so its curve still
measures what z holds.

rsl-rl's PPO adds an extension's loss to its own through the symmetry seam (`augment_batch`,
`compute_loss(actor, batch, n)`, `use_mirror_loss`, `mirror_loss_coeff`); this class fills that seam, so
PPO's update runs unchanged and the sum is differentiated once.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch.distributions import Normal, kl_divergence

from policies.latent_models import LatentActor


def gaussian_kl(mean: torch.Tensor, log_std: torch.Tensor) -> torch.Tensor:
    """KL(N(mean, std^2) || N(0, I)) per sample, summed over the latent dimensions: torch's
    `kl_divergence(Normal(mean, exp(log_std)), Normal(0, 1))`. Arguments are not validated, so a non-finite latent
    gives a non-finite loss (which the trainer's divergence guard stops on) rather than an error."""
    return kl_divergence(Normal(mean, log_std.exp(), validate_args=False),
                         Normal(0.0, 1.0, validate_args=False)).sum(-1)


def info_nce(z_proj: torch.Tensor, p_embed: torch.Tensor, temperature: float,
             same_dynamics: torch.Tensor | None = None) -> torch.Tensor:
    """InfoNCE of matching pairs (row i of both) against the other rows; `same_dynamics[i, j]` True removes
    pair (i, j != i) from the negatives."""
    logits = F.normalize(z_proj, dim=-1) @ F.normalize(p_embed, dim=-1).T / temperature
    if same_dynamics is not None:
        eye = torch.eye(len(logits), dtype=torch.bool, device=logits.device)
        logits = logits.masked_fill(same_dynamics & ~eye, float("-inf"))
    return F.cross_entropy(logits, torch.arange(len(logits), device=logits.device))


def same_dynamics(dynamics: torch.Tensor) -> torch.Tensor:
    """[n, n] True where two samples' randomised parameters are equal. Exactly: one episode's values are
    bit-identical, while `torch.cdist` on many rows computes distances through a matrix product whose
    rounding leaves equal rows about 1e-3 apart."""
    return (dynamics[:, None] == dynamics[None]).all(-1)


class InformationBottleneck:
    """HIB's loss on a LatentActor's last forward pass, for rsl-rl's PPO (see the module docstring)."""

    use_mirror_loss = True
    mirror_loss_coeff = 1.0

    def __init__(self, kl_weight: float, infonce_weight: float, temperature: float, samples: int,
                 dynamics_slices: list[slice], ib: bool = True, seed: int = 0):
        self.kl_weight, self.infonce_weight, self.temperature = kl_weight, infonce_weight, temperature
        self.samples, self.dynamics_slices, self.ib = samples, dynamics_slices, ib
        self.generator = torch.Generator().manual_seed(seed)
        self._sums = {"kl": 0.0, "infonce": 0.0, "mi_lower_bound": 0.0}
        self._count = 0
        self._heads = None

    head_learning_rate = 1e-3
    """Adam step size of the InfoNCE heads in hib-no-ib (their optimiser's state is not checkpointed)."""

    def augment_batch(self, batch, original_batch_size: int) -> None:
        """No augmentation (the seam's first call)."""

    def compute_loss(self, actor: LatentActor, batch, original_batch_size: int) -> torch.Tensor:
        """infonce_weight * InfoNCE + kl_weight * KL of the mini-batch PPO just evaluated (0 without IB)."""
        mean, log_std = actor.latent_mean, actor.latent_log_std
        kl = gaussian_kl(mean, log_std).mean()
        n = min(self.samples, len(mean))
        pick = torch.randperm(len(mean), generator=self.generator)[:n].to(mean.device)
        privileged = batch.observations["privileged_state"][pick]
        dynamics = torch.cat([privileged[:, s] for s in self.dynamics_slices], dim=-1)
        same = same_dynamics(dynamics)
        z = actor.latent[pick] if self.ib else actor.latent[pick].detach()
        nce = info_nce(actor.projection(z), actor.embed_privileged(privileged), self.temperature, same)
        candidates = n - same.sum(-1) + 1  # each anchor's softmax: its pair and the negatives left in
        self._sums["kl"] += float(kl.detach())
        self._sums["infonce"] += float(nce.detach())
        self._sums["mi_lower_bound"] += float(candidates.float().log().mean()) - float(nce.detach())
        self._count += 1
        if not self.ib:  # the ablation: InfoNCE trains only the probe's two heads, apart from PPO's step
            self._step_heads(actor, self.infonce_weight * nce)
            return torch.zeros((), device=nce.device)
        return self.infonce_weight * nce + self.kl_weight * kl

    def _step_heads(self, actor: LatentActor, loss: torch.Tensor) -> None:
        """One Adam step of the embedding and projection heads on `loss` (hib-no-ib), with an optimiser of
        their own: inside PPO's loss, their gradients would count in its gradient-norm clipping of the actor
        and so scale the RL gradient, which the ablation must leave alone."""
        params = list(actor.embedding.parameters()) + list(actor.projection.parameters())
        if self._heads is None:
            self._heads = torch.optim.Adam(params, lr=self.head_learning_rate)
        self._heads.zero_grad()
        loss.backward()
        self._heads.step()
        self._heads.zero_grad()

    def means(self) -> dict:
        """Mean KL, InfoNCE and the bound log K - InfoNCE since the last call (then reset)."""
        out = {f"hib_{k}": v / max(self._count, 1) for k, v in self._sums.items()}
        self._sums = dict.fromkeys(self._sums, 0.0)
        self._count = 0
        return out
