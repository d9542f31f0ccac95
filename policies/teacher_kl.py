"""KL-regularised RL towards a teacher (how the humanoid soccer work distils skill teachers into one player), as a loss.

The student trains with PPO on its own observations (the vision player: proprioception and the head
camera; the critic reads the privileged state) and is pulled towards a frozen state-based teacher by
`weight * KL(teacher(. | s) || student(. | o))` over the same steps, the teacher reading its own features of
the state. The weight starts at `distill.kl_weight` and is multiplied by `distill.kl_decay` after every
iteration, so the student leans on the teacher early and on its own return later (Haarnoja et al. decay the
weight of their skill teachers; Tirumala et al. adapt it).

A student that estimates the game (command_prior=placo: its actions are corrections, then the game features
its placo command is computed from) has more actions than its teacher's distribution: the teacher's labels
beyond it (the true features, policies.algorithms.WorldLabeller) are regressed by the student's mean with
the squared error of DAgger, at a weight of 1 that does not decay, and the KL's teacher mean is its
corrections' label (clipped as `distill.correction_margin` says, raw by default). A student started from an earlier one
(distill.student_init) can first hold its actor still for `critic_warmup` iterations while the fresh critic
learns its return.

rsl-rl's PPO adds an extension's loss to its own through the symmetry seam (as HIB does, policies.hib):
this class fills it, so PPO's update runs unchanged (on the valid steps of padded trajectories when the
student has memory).
"""

from __future__ import annotations

import torch
from rsl_rl.utils import unpad_trajectories


class TeacherKL:
    """`weight * KL(teacher || student)` (+ the squared error of estimated labels) on the mini-batch PPO just
    evaluated (see the module docstring)."""

    use_mirror_loss = True
    mirror_loss_coeff = 1.0
    """rsl-rl multiplies the returned loss by it; the weights are applied inside."""

    def __init__(self, teacher: torch.nn.Module, weight: float, decay: float, iteration: int = 0,
                 actor: torch.nn.Module | None = None, critic_warmup: int = 0):
        self.teacher = teacher.eval()
        for p in self.teacher.parameters():
            p.requires_grad_(False)
        self.decay, self.weight = decay, weight * decay ** iteration
        self.actor, self.iteration, self.critic_warmup = actor, iteration, critic_warmup
        self._sums, self._count = {"teacher_kl": 0.0}, 0
        self._hold_actor()

    def augment_batch(self, batch, original_batch_size: int) -> None:
        """No augmentation (the seam's first call)."""

    def compute_loss(self, actor, batch, original_batch_size: int) -> torch.Tensor:
        """weight x mean KL(teacher || student) over the teacher's actions (the student's distribution is PPO's
        last forward pass), plus the mean squared error of the student's further actions to the teacher's labels."""
        masks = getattr(batch, "masks", None)  # set by a recurrent rollout: padded trajectories
        obs = batch.observations if masks is None else unpad_trajectories(batch.observations, masks)
        with torch.no_grad():
            labels = self.teacher(obs)  # its mean (a WorldLabeller's: corrections as distill.correction_margin
            k = self.teacher.distribution.output_dim  # clips them), then any labels beyond its distribution
            self.teacher.distribution.update(labels[..., :k])  # its Gaussian about those labels
            teacher = self.teacher.output_distribution_params
        mean, std = actor.output_distribution_params
        kl = actor.get_kl_divergence(teacher, (mean[..., :k], std[..., :k])).mean()
        loss = self.weight * kl
        self._sums["teacher_kl"] += float(kl.detach())
        if mean.shape[-1] > k:  # the game it estimates, labelled by the truth
            estimate = ((mean[..., k:] - labels[..., k:]) ** 2).mean()
            loss = loss + estimate
            self._sums["estimate_mse"] = self._sums.get("estimate_mse", 0.0) + float(estimate.detach())
        self._count += 1
        return loss

    def end_iteration(self) -> None:
        """Decay the weight; free the actor once the critic's warm-up is over (once per training iteration)."""
        self.weight *= self.decay
        self.iteration += 1
        self._hold_actor()

    def _hold_actor(self) -> None:
        """The actor's parameters learn only after `critic_warmup` iterations."""
        if self.actor is not None:
            for p in self.actor.parameters():
                p.requires_grad_(self.iteration >= self.critic_warmup)

    def means(self) -> dict:
        """Mean KL to the teacher (and error of the estimated labels) since the last call (then reset), the
        weight in use, and whether the actor was held still."""
        out = {k: v / max(self._count, 1) for k, v in self._sums.items()}
        out.update(teacher_kl_weight=self.weight, actor_frozen=float(self.iteration < self.critic_warmup))
        self._sums, self._count = dict.fromkeys(self._sums, 0.0), 0
        return out
