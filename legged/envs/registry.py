"""Task names -> environments. `make("confined-waypoints")` is how everything else gets an env."""

from __future__ import annotations

import dataclasses
from typing import Callable

from legged.envs.base import LeggedEnv
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.flat import FlatConfig, FlatEnv
from legged.soccer.config import SoccerSceneConfig
from legged.soccer.task_config import SoccerConfig


def _soccer(config: SoccerConfig):
    from legged.soccer.env import SoccerEnv  # imported on use: legged.soccer builds on legged.envs

    return SoccerEnv(config)


TASKS: dict[str, tuple[Callable[..., object], object]] = {
    "go1-flat": (FlatEnv, FlatConfig()),
    "confined-waypoints": (ConfinedEnv, ConfinedConfig(mode="waypoints")),
    "confined-goal": (ConfinedEnv, ConfinedConfig(mode="goal")),
    "confined-velocity": (ConfinedEnv, ConfinedConfig(mode="velocity")),
    "confined-skills": (ConfinedEnv, ConfinedConfig(mode="skills")),
    "soccer-1v1": (_soccer, SoccerConfig()),
    "soccer-2v2": (_soccer, SoccerConfig(scene=SoccerSceneConfig(players_per_team=2))),
    "soccer-1v1-vision": (_soccer, SoccerConfig(vision=True)),
}
"""Soccer tasks make the multi-agent `SoccerEnv`; training wraps it in `legged.soccer.learner.LearnerView`."""


class UnknownTaskError(KeyError):
    """The task name is not registered."""

    def __str__(self) -> str:
        return self.args[0]


def default_config(task: str):
    """The default configuration of a task."""
    if task not in TASKS:
        raise UnknownTaskError(f"unknown task {task!r}; known tasks: {', '.join(sorted(TASKS))}")
    return TASKS[task][1]


def make(task: str, config=None, **overrides) -> LeggedEnv:
    """Build a task's environment; `overrides` replace fields of its (default) config."""
    config = config or default_config(task)
    if overrides:
        config = dataclasses.replace(config, **overrides)
    return TASKS[task][0](config)
