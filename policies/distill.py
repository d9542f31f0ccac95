"""`legged distill TEACHER_RUN --method dagger|rma|kl [--task T]`: students from a teacher, as ordinary run
directories (trained by policies.rsl_backend, like every rsl run).

Two kinds of teacher:
- a privileged teacher (trained with `--algo teacher`; its student plays the same task from its history):
  - dagger: rsl-rl's Distillation. The student (a head on the state and an encoding of its history) acts,
    with a little exploration noise, and the teacher labels every step; the loss is the squared action
    difference.
  - rma (Kumar et al. 2021, phase 2): the student's history encoder regresses the teacher's latent z_p of
    the same step, and the student acts with the teacher's head, copied and frozen, fed the state normalised
    as the teacher normalised it (its normaliser is the teacher's, frozen).
- a state soccer player (soccer-1v1, `--algo ppo`), whose student plays the vision task (`--task soccer-1v1-vision`)
  from proprioception and the head camera; the teacher reads the state features the vision task gives as `features`.
  Methods: dagger (as above) and kl (the anchors' KL-regularised RL, policies.teacher_kl). A teacher that commands a
  walker (`soccer.walker`) passes it on: the student commands it too. A teacher whose commands corrected the placo
  player's (`soccer.command_prior`) is taught whole: its student's game observes that command (the observation
  `command_prior`), the teacher's outputs add it (policies.algorithms.PriorCorrector), and the student, which cannot
  see the ball's state, learns the whole command from the camera. With `--set soccer.command_prior=placo` the
  student instead estimates what the placo command is computed from: its actions are the teacher's corrections and
  the game features after the proprioception (ball, goals, opponent), labelled by the teacher's outputs and the
  truth (policies.algorithms.WorldLabeller), and its game adds the placo command computed from that estimate
  (legged.soccer.learner). Such a student learns by kl too: PPO on its return plus the KL of its corrections to the
  teacher's and the squared error of its estimate (policies.teacher_kl), typically started whole from a dagger
  student (`distill.student_init`, `student_init_whole`) with its critic warmed up first (`distill.critic_warmup`).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import yaml

from policies.config import ConfigError, apply_overrides, to_dict
from policies.rsl_backend import train_rsl
from policies.run_dir import RunDir
from policies.students import (  # noqa: F401 (GroupedLoss, teacher_share: re-exports)
    GroupedLoss,
    check_student_init,
    teacher_config,
    teacher_share,
)
from policies.training import refuse_pilot, training_env

METHODS = ("dagger", "rma", "kl")
"""Distillation methods."""


def start_distill(teacher_run: str, method: str, run_dir: str | None, timesteps: int | None = None,
                  physics: str | None = None, overrides: list[str] = (), progress: bool = True,
                  num_envs: int | None = None, threads: int | None = None, task: str | None = None) -> dict:
    """Check the teacher, create the student's run directory (its config names the teacher), train; `task`:
    the student's (default: the teacher's own)."""
    if method not in METHODS:
        raise ConfigError(f"unknown distillation method {method!r}; methods: {', '.join(METHODS)}")
    teacher = teacher_config(Path(teacher_run), task)
    changes = dict(algo=method, distill=dataclasses.replace(teacher.distill, teacher=str(teacher_run)), init_from="")
    if task not in (None, teacher.task):  # a vision student: the teacher's game, seen through the camera
        if method == "rma":
            raise ConfigError("rma regresses a privileged teacher's latent; a vision student learns by dagger or kl")
        soccer = dataclasses.replace(teacher.soccer, command_prior="",
                                     selfplay=dataclasses.replace(teacher.soccer.selfplay, opponent="scripted"))
        changes.update(task=task, env=dataclasses.replace(teacher.env, vision=True), soccer=soccer,
                       distill=dataclasses.replace(changes["distill"],
                                                   teacher_prior=bool(teacher.soccer.command_prior)))
    for name, value in (("timesteps", timesteps), ("physics", physics), ("num_envs", num_envs), ("threads", threads)):
        if value is not None:
            changes[name] = value
    if method == "rma":  # the student acts with the teacher's head: same sizes
        changes["latent"] = dataclasses.replace(teacher.latent)
    config = apply_overrides(dataclasses.replace(teacher, **changes).resolved(), list(overrides))
    refuse_pilot(config)
    if config.estimates_world and not teacher.soccer.command_prior:  # it adds the placo command from its estimate
        raise ConfigError(f"soccer.command_prior=placo: the student adds the placo command to corrections it learns "
                          f"from a teacher that corrected that command; teacher {teacher_run} did not "
                          f"(its soccer.command_prior is '')")
    if method == "rma" and (config.ppo.actor_hidden, config.latent.latent_dim) != \
            (teacher.ppo.actor_hidden, teacher.latent.latent_dim):
        raise ConfigError("rma reuses the teacher's head: ppo.actor_hidden and latent.latent_dim must be the teacher's")
    if config.distill.student_init:
        check_student_init(Path(config.distill.student_init))
    run = RunDir(run_dir or Path("runs") / f"{teacher.task}-{method}-{time.strftime('%Y%m%d-%H%M%S')}")
    run.create(config)
    (run.path / "teacher.yaml").write_text(yaml.safe_dump(to_dict(teacher), sort_keys=False))  # a record
    if progress:
        print(f"[distill] {method} from {teacher_run} into {run.path}", flush=True)
    env, hooks = training_env(config)
    return train_rsl(env, config, run, resume=False, progress=progress, hooks=hooks)
