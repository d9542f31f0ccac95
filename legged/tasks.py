"""The task registry, the top of the core (legged.envs, legged.soccer and legged.skills sit below it): what each
task is, so that nothing else has to ask `isinstance`.

`make("confined-waypoints")` builds a task's environment; `task_entry(name)` says what it is (robot, kind,
physics engines and trainers it supports, whether its actor sees a camera); `learner_env(entry, env)` is
the single-agent environment trainers and evaluators step (soccer: agent 0's view of the game).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Literal

from legged.envs.config import NoiseConfig
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.flat import FlatConfig, FlatEnv
from legged.envs.rough import RoughConfig, RoughEnv
from legged.robots import GO1, OP3
from legged.robots.spec import RobotSpec
from legged.sensors.heightscan import ScanConfig
from legged.skills.config import GetUpConfig, WalkSkillConfig
from legged.soccer.config import SoccerConfig, SoccerSceneConfig
from legged.soccer.randomize import OP3_RANDOMIZATION
from legged.worlds.levels import LEVELS, LevelConfig

Kind = Literal["locomotion", "confined", "soccer"]


def _soccer(config: SoccerConfig):
    from legged.soccer.env import SoccerEnv  # imported on use (it builds the scene's MJX model)

    return SoccerEnv(config)


def _walk_skill(config):
    from legged.skills.env import WalkSkillEnv  # imported on use, as the soccer env it builds on

    return WalkSkillEnv(config)


def _getup_skill(config):
    from legged.skills.env import GetUpSkillEnv  # imported on use, as the soccer env it builds on

    return GetUpSkillEnv(config)


@dataclasses.dataclass(frozen=True)
class TaskEntry:
    """One registered task."""

    name: str
    """Task name (`legged tasks`)."""
    factory: Callable
    """Builds the environment from a config of the default's type."""
    config: object
    """Default environment config (a frozen dataclass)."""
    robot: RobotSpec
    """The robot it trains."""
    kind: Kind
    """locomotion (one robot's skill: velocity tracking, getting up), confined (worlds and planned
    waypoints: training needs the planner, legged.envs never imports it) or soccer (multi-agent; trainers
    see agent 0's view)."""
    physics: tuple[str, ...] = ("mjx", "native")
    """Physics engines it runs on."""
    backends: tuple[str, ...] = ("rsl", "brax")
    """Trainers it supports."""
    vision: bool = False
    """Its actor reads camera images (a CNN; the rsl backend only)."""
    robot_models: bool = False
    """It runs other models of its robot than the project's (`env.robot_model`, `--robot`; legged.robots.models)."""
    bounded_actions: bool = False
    """Its actions are bounded: joint targets the environment clips to +-`env.action_clip` (and feeds back clipped),
    or a soccer player's walker commands (policies.policy_io.action_bound); the deployed actor clips its output there
    too, in the framework and in its ONNX."""

    def check(self, physics: str | None = None, backend: str | None = None) -> None:
        """ValueError naming what to use instead when this task does not support `physics` or `backend`."""
        if physics is not None and physics not in self.physics:
            raise ValueError(f"{self.name} runs on physics {', '.join(self.physics)}, not {physics!r}")
        if backend is not None and backend not in self.backends:
            why = ": its actor reads camera images with a CNN, and the Brax backend builds MLPs only" if self.vision else ""
            raise ValueError(f"{self.name} trains with --backend {' or '.join(self.backends)}, not {backend!r}{why}")


_GO1 = dict(motor_curve=True)
"""What the Go1 tasks' configs set beyond their classes' defaults (runs saved before it existed load without)."""
_CONFINED = dict(_GO1, max_speed=1.0, speed_command=True, speed_range=(0.3, 1.0), levels=LevelConfig(),
                 difficulties=LEVELS,
                 scan=ScanConfig(x_range=(-0.3, 0.9), y_range=(-0.4, 0.4), spacing=0.05, ceiling_clip=0.3),
                 velocity_in_state=True, gyro_in_state=True, stall_timeout_s=3.0)
"""What the confined tasks' configs set beyond that (runs saved before them load without): a speed limit of 1 m/s,
each episode drawing its limit from 0.3-1 m/s and the command tells the policy the limit in force; the worlds are the levels d0-d4; the
height scans reach under the hind feet at 5 cm spacing (half the narrowest void) and read every roof over 0.3 m above
the base, and open sky, alike; the state holds the body's velocity (as an estimator gives it) and the gyro, so the
follower sees its own speed against the limit; a training episode that has stalled for 3 s ends as a failure (with
each step's reward clipped at 0, standing still cost nothing and filled about 40% of the rollouts)."""
_OP3 = dict(randomization=OP3_RANDOMIZATION, noise=NoiseConfig(enabled=True))
"""What the OP3 tasks' configs set beyond their classes' defaults: the randomisation that covers the reference models
and observation noise (runs saved before them load without)."""
_DEPLOYED = dict(robot_models=True, bounded_actions=True)
"""Tasks whose policies deploy: they run on other models of their robot, their actors' actions are bounded."""


TASKS: dict[str, TaskEntry] = {e.name: e for e in (
    TaskEntry("go1-flat", FlatEnv, FlatConfig(**_GO1), GO1, "locomotion", **_DEPLOYED),
    TaskEntry("go1-rough", RoughEnv, RoughConfig(**_GO1), GO1, "locomotion", **_DEPLOYED),
    TaskEntry("confined-waypoints", ConfinedEnv, ConfinedConfig(mode="waypoints", six_dof_command=True, **_CONFINED),
              GO1, "confined", **_DEPLOYED),
    TaskEntry("confined-goal", ConfinedEnv, ConfinedConfig(mode="goal", **_CONFINED), GO1, "confined", **_DEPLOYED),
    TaskEntry("confined-velocity", ConfinedEnv, ConfinedConfig(mode="velocity", success_bootstraps=True, **_CONFINED),
              GO1, "confined", **_DEPLOYED),
    TaskEntry("confined-skills", ConfinedEnv, ConfinedConfig(mode="skills", success_bootstraps=True, **_CONFINED),
              GO1, "confined", **_DEPLOYED),
    TaskEntry("op3-walk", _walk_skill, WalkSkillConfig(**_OP3), OP3, "locomotion", **_DEPLOYED),
    TaskEntry("op3-getup", _getup_skill, GetUpConfig(**_OP3), OP3, "locomotion", **_DEPLOYED),
    TaskEntry("soccer-1v1", _soccer, SoccerConfig(**_OP3), OP3, "soccer", **_DEPLOYED),
    TaskEntry("soccer-2v2", _soccer, SoccerConfig(scene=SoccerSceneConfig(players_per_team=2), **_OP3), OP3, "soccer",
              **_DEPLOYED),
    TaskEntry("soccer-1v1-vision", _soccer, SoccerConfig(vision=True, **_OP3), OP3, "soccer", backends=("rsl",),
              vision=True, **_DEPLOYED),
)}
"""Every task, by name."""


class UnknownTaskError(KeyError):
    """The task name is not registered."""

    def __str__(self) -> str:
        return self.args[0]


def task_entry(task: str) -> TaskEntry:
    """The registry entry of a task; UnknownTaskError listing the known ones."""
    if task not in TASKS:
        raise UnknownTaskError(f"unknown task {task!r}; known tasks: {', '.join(sorted(TASKS))}")
    return TASKS[task]


def default_config(task: str):
    """The default configuration of a task."""
    return task_entry(task).config


def make(task: str, config=None, **overrides):
    """Build a task's environment; `overrides` replace fields of its (default) config."""
    entry = task_entry(task)
    config = config or entry.config
    if overrides:
        config = dataclasses.replace(config, **overrides)
    return entry.factory(config)


def learner_env(entry: TaskEntry, env, activation: str = "elu", hidden: tuple[int, ...] = (), walker=None,
                teacher_prior: bool = False):
    """The single-agent environment trainers step: `env` itself, or for soccer agent 0's view of the game
    (the other robots driven by opponents handed to each step; `activation` and `hidden` shape them; with a
    `legged.soccer.walker.Walker` the players command velocities; `teacher_prior`: legged.soccer.learner)."""
    if entry.kind != "soccer":
        if walker is not None:
            raise ValueError(f"a walker drives soccer players; {entry.name} is a {entry.kind} task")
        return env
    from legged.soccer.learner import LearnerView  # imported on use, as the soccer env (legged.soccer.env) it wraps
    from legged.soccer.opponents import OpponentNet

    return LearnerView(env, OpponentNet(activation), hidden, walker, teacher_prior)
