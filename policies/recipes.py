"""Each task's training recipe: the settings a new run of the task starts from on a trainer, before the command
line's `--set` overrides, written into the run's config.yaml like them. A task without one trains on TrainConfig's
defaults and its environment's. Runs already made keep the settings their config.yaml holds."""

from __future__ import annotations

import dataclasses

from policies.config import TrainConfig, apply_overrides

RECIPES: dict[tuple[str, str], tuple[str, ...]] = {
    ("go1-flat", "rsl"): (
        "num_envs=512",
        "ppo.actor_hidden=[256, 128, 64]",
        "ppo.critic_hidden=[256, 128, 64]",
        "env.rewards.feet_air_threshold=0.2",
        "randomization_curriculum=0.25",
        "random_episode_start=true",
    ),
}
"""(task, backend) -> `path=value` overrides, as `--set` takes them (docs/training.md, "A walker in minutes",
measures the go1-flat recipe against the defaults)."""


def task_config(task: str, backend: str = "rsl", **fields) -> TrainConfig:
    """The resolved TrainConfig of a new run of `task` on `backend`: TrainConfig's defaults, then the task's recipe,
    then `fields` (num_envs, seed, physics, ...; a field given as None keeps the recipe's or the default)."""
    config = apply_overrides(TrainConfig(task=task, backend=backend).resolved(), list(RECIPES.get((task, backend), ())))
    return dataclasses.replace(config, **{k: v for k, v in fields.items() if v is not None}).resolved()
