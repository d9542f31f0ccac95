"""KL-regularised RL towards a teacher (the soccer anchors' distillation, PAPERS.md section 2), as a loss.

The student trains with PPO on its own observations (the vision player: proprioception and the head
camera; the critic reads the privileged state) and is pulled towards a frozen state-based teacher by
`weight * KL(teacher(. | s) || student(. | o))` over the same steps, the teacher reading its own features of
the state. The weight starts at `distill.kl_weight` and is multiplied by `distill.kl_decay` after every
iteration, so the student leans on the teacher early and on its own return later (Haarnoja et al. decay the
weight of their skill teachers; Tirumala et al. adapt it).

rsl-rl's PPO adds an extension's loss to its own through the symmetry seam (as HIB does, policies.hib):
this class fills it, so PPO's update runs unchanged.
"""

from __future__ import annotations

import torch


class TeacherKL:
    """`weight * KL(teacher || student)` on the mini-batch PPO just evaluated (see the module docstring)."""

    use_mirror_loss = True

    def __init__(self, teacher: torch.nn.Module, weight: float, decay: float, iteration: int = 0):
        self.teacher = teacher.eval()
        for p in self.teacher.parameters():
            p.requires_grad_(False)
        self.decay = decay
        self.mirror_loss_coeff = weight * decay ** iteration
        """The current weight (rsl-rl multiplies the returned loss by it)."""
        self._sum, self._count = 0.0, 0

    def augment_batch(self, batch, original_batch_size: int) -> None:
        """No augmentation (the seam's first call)."""

    def compute_loss(self, actor, batch, original_batch_size: int) -> torch.Tensor:
        """Mean KL(teacher || student) of the batch; the student's distribution is PPO's last forward pass."""
        with torch.no_grad():
            self.teacher(batch.observations, stochastic_output=True)
            teacher = self.teacher.output_distribution_params
        kl = actor.get_kl_divergence(teacher, actor.output_distribution_params).mean()
        self._sum += float(kl.detach())
        self._count += 1
        return kl

    def end_iteration(self) -> None:
        """Decay the weight (once per training iteration)."""
        self.mirror_loss_coeff *= self.decay

    def means(self) -> dict:
        """Mean KL to the teacher since the last call (then reset) and the weight in use."""
        out = {"teacher_kl": self._sum / max(self._count, 1), "teacher_kl_weight": self.mirror_loss_coeff}
        self._sum, self._count = 0.0, 0
        return out
