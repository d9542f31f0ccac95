"""Self-play for the soccer tasks: a pool of frozen snapshots of the learner, sampled as opponents.

Snapshots are `legged.soccer.opponents.Opponent` pytrees (data): handing a different one to the
environment's step swaps the opponent without recompiling. The pool lives in the rsl checkpoints, so a
resumed run plays against the same past selves.
"""

from __future__ import annotations

import numpy as np
import torch

from legged.soccer.opponents import (
    Opponent,
    network_opponent,
    opponent_from_numpy,
    opponent_to_numpy,
    placo_opponent,
    scripted_opponent,
)
from policies.soccer.config import SelfPlayConfig


def snapshot_rsl_actor(actor: torch.nn.Module) -> Opponent:
    """The deterministic part of an rsl-rl MLPModel actor (normaliser + MLP) as an Opponent (a deployed actor's clip
    left to the environment, which clips the actions it applies to the same bound)."""
    actor = getattr(actor, "bounded", actor)
    linear = [m for m in actor.mlp if isinstance(m, torch.nn.Linear)]
    layers = [(m.weight.detach().cpu().numpy().T, m.bias.detach().cpu().numpy()) for m in linear]
    n = layers[0][0].shape[0]
    norm = actor.obs_normalizer
    if isinstance(norm, torch.nn.Identity):
        mean, std = np.zeros(n), np.ones(n)
    else:
        mean = norm._mean.detach().cpu().numpy().reshape(-1)
        std = norm._std.detach().cpu().numpy().reshape(-1) + norm.eps
    return network_opponent(mean, std, layers)


def script_opponents(config: SelfPlayConfig, obs_size: int, action_size: int, players_per_team: int) -> tuple:
    """The env-step arguments of a soccer run without a pool (vision tasks, `soccer.selfplay.opponent=scripted`): the
    script `config.script` drives every other robot, the learner's teammate in 2v2 too."""
    script = (placo_opponent if config.script == "placo" else scripted_opponent)(obs_size, action_size)
    return (script, script) if players_per_team > 1 else (script,)


class OpponentPool:
    """The last `pool_size` snapshots; `sample` picks the script (`config.script`) or a snapshot for the next
    iteration."""

    def __init__(self, config: SelfPlayConfig, obs_size: int, action_size: int, hidden: tuple[int, ...], seed: int):
        self.config = config
        script = placo_opponent if config.script == "placo" else scripted_opponent
        self.scripted = script(obs_size, action_size, hidden)
        self.snapshots: list[Opponent] = []
        self.rng = np.random.default_rng(seed)

    def add(self, opponent: Opponent) -> None:
        """Add a snapshot, dropping the oldest beyond `pool_size`."""
        self.snapshots = (self.snapshots + [opponent])[-self.config.pool_size:]

    def sample(self) -> tuple[int, Opponent]:
        """(index in the pool or -1 for the script, opponent) for the next iteration."""
        if not self.snapshots or self.rng.random() < self.config.scripted_fraction:
            return -1, self.scripted
        i = int(self.rng.integers(len(self.snapshots)))
        return i, self.snapshots[i]

    def teammate(self) -> Opponent:
        """Who plays beside the learner in 2v2: its newest snapshot (the script while the pool is empty)."""
        return self.snapshots[-1] if self.snapshots else self.scripted

    def state_dict(self) -> dict:
        """Picklable pool contents and sampler state (for checkpoints)."""
        return {"snapshots": [opponent_to_numpy(o) for o in self.snapshots], "rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict) -> None:
        """Restore what `state_dict` saved."""
        self.snapshots = [opponent_from_numpy(d) for d in state["snapshots"]]
        self.rng.bit_generator.state = state["rng"]
