"""`legged bench update`: what one PPO update costs on this CPU with each option torch offers for it.

A PPO update of rsl-rl's shape (actor and critic MLPs with ELU, a Gaussian policy, the clipped surrogate, the value
loss and the entropy bonus, gradients clipped at norm 1, Adam; `epochs` passes over `mini_batches` mini-batches of
one iteration's rollout) on random data, timed under each variant, interleaved round by round so that a change of
the machine's load falls on every variant alike. Reported as each variant's ratio to the plain one, measured in the
one run (absolute times differ between machines and loads).
"""

from __future__ import annotations

import statistics
import time

import torch

VARIANTS = {
    "plain": "torch's defaults as rsl-rl uses them: eager modules, Adam's per-parameter loop",
    "foreach-adam": "Adam updating all parameters in one multi-tensor call (foreach=True)",
    "fused-adam": "Adam's fused kernel (fused=True)",
    "compiled": "actor and critic through torch.compile (inductor; C++ compiled on the first update)",
    "one-thread": "the plain update on one torch thread instead of all",
}
"""Variant name -> what it changes."""


def _mlp(inputs: int, hidden: tuple[int, ...], outputs: int) -> torch.nn.Sequential:
    layers, width = [], inputs
    for size in hidden:
        layers += [torch.nn.Linear(width, size), torch.nn.ELU()]
        width = size
    return torch.nn.Sequential(*layers, torch.nn.Linear(width, outputs))


class _Update:
    """A PPO learner of one variant and the rollout it learns from."""

    def __init__(self, variant: str, inputs: int, hidden: tuple[int, ...], actions: int, batch: int, seed: int):
        torch.manual_seed(seed)
        self.actor, self.critic = _mlp(inputs, hidden, actions), _mlp(inputs, hidden, 1)
        self.log_std = torch.nn.Parameter(torch.zeros(actions))
        self.params = [*self.actor.parameters(), *self.critic.parameters(), self.log_std]
        options = {"foreach-adam": {"foreach": True}, "fused-adam": {"fused": True}}.get(variant, {})
        self.optimizer = torch.optim.Adam(self.params, lr=1e-3, **options)
        self.forward_actor, self.forward_critic = self.actor, self.critic
        if variant == "compiled":
            self.forward_actor, self.forward_critic = torch.compile(self.actor), torch.compile(self.critic)
        self.threads = 1 if variant == "one-thread" else torch.get_num_threads()
        self.obs = torch.randn(batch, inputs)
        self.actions, self.old_log_prob = torch.randn(batch, actions), -torch.rand(batch) * actions
        self.advantages, self.returns = torch.randn(batch), torch.randn(batch)

    def run(self, epochs: int, mini_batches: int) -> float:
        """Seconds of one update: `epochs` passes over the rollout in `mini_batches` shuffled mini-batches."""
        before = torch.get_num_threads()
        torch.set_num_threads(self.threads)
        try:
            start = time.perf_counter()
            size = self.obs.shape[0] // mini_batches
            for _ in range(epochs):
                order = torch.randperm(self.obs.shape[0])
                for k in range(mini_batches):
                    self._step(order[k * size:(k + 1) * size])
            return time.perf_counter() - start
        finally:
            torch.set_num_threads(before)

    def _step(self, idx: torch.Tensor) -> None:
        obs, actions = self.obs[idx], self.actions[idx]
        std = self.log_std.exp()
        log_prob = torch.distributions.Normal(self.forward_actor(obs), std).log_prob(actions).sum(-1)
        ratio = torch.exp(log_prob - self.old_log_prob[idx])
        advantages = self.advantages[idx]
        surrogate = -torch.min(ratio * advantages, ratio.clamp(0.8, 1.2) * advantages).mean()
        value_loss = (self.forward_critic(obs).squeeze(-1) - self.returns[idx]).pow(2).mean()
        entropy = (0.5 + 0.5 * torch.log(torch.tensor(2 * torch.pi)) + self.log_std).sum()
        loss = surrogate + value_loss - 0.01 * entropy
        self.optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.params, 1.0)
        self.optimizer.step()


def bench_update(inputs: int, hidden: tuple[int, ...], actions: int = 12, batch: int = 24576, epochs: int = 5,
                 mini_batches: int = 4, rounds: int = 5, variants: tuple[str, ...] = tuple(VARIANTS),
                 seed: int = 0) -> dict:
    """Seconds per update of each variant (median of `rounds`, interleaved; the first update of each, which
    compiles for `compiled`, is timed apart) and each median's ratio to the plain update's."""
    unknown = sorted(set(variants) - set(VARIANTS))
    if unknown or "plain" not in variants:
        raise ValueError(f"variants {unknown or list(variants)}: pick from {', '.join(VARIANTS)}, plain among them")
    learners = {v: _Update(v, inputs, hidden, actions, batch, seed) for v in variants}
    first = {v: learner.run(epochs, mini_batches) for v, learner in learners.items()}
    times = {v: [] for v in variants}
    for _ in range(rounds):
        for v, learner in learners.items():
            times[v].append(learner.run(epochs, mini_batches))
    medians = {v: statistics.median(t) for v, t in times.items()}
    return {"inputs": inputs, "hidden": list(hidden), "actions": actions, "batch": batch, "epochs": epochs,
            "mini_batches": mini_batches, "threads": torch.get_num_threads(), "rounds": rounds,
            "variants": {v: {"what": VARIANTS[v], "update_s": medians[v], "first_update_s": first[v],
                             "update_s_each": times[v], "speed_vs_plain": medians["plain"] / medians[v]}
                         for v in variants}}
