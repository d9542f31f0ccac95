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
- a state soccer player (soccer-1v1, `--algo ppo`), whose student plays the vision task
  (`--task soccer-1v1-vision`) from proprioception and the head camera; the teacher reads the state features
  the vision task gives as `features`. Methods: dagger (as above) and kl (the anchors' KL-regularised RL,
  policies.teacher_kl). A teacher that commands a walker (`walker`) passes it on: the student commands it too.
  A teacher whose commands corrected the placo player's (`command_prior`) is taught whole: its student's game
  observes that command (`command_prior`), the teacher's outputs add it (policies.algorithms.PriorCorrector),
  and the student, which cannot see the ball's state, learns the whole command from the camera. With
  `--set command_prior=placo` the student instead estimates what the placo command is computed from: its
  actions are the teacher's corrections and the game features after the proprioception (ball, goals,
  opponent), labelled by the teacher's outputs and the truth (policies.algorithms.WorldLabeller), and its game
  adds the placo command computed from that estimate (legged.soccer.learner). Such a student learns by kl too:
  PPO on its return plus the KL of its corrections to the teacher's and the squared error of its estimate
  (policies.teacher_kl), typically started whole from a dagger student (`distill.student_init`,
  `student_init_whole`) with its critic warmed up first (`distill.critic_warmup`).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import torch
import torch.nn.functional as F
import yaml
from rsl_rl.algorithms import Distillation

from policies.config import ConfigError, TrainConfig, apply_overrides, to_dict
from policies.run_dir import RunDir, RunDirError
from policies.warm_start import ADAPT_SAMPLES

METHODS = ("dagger", "rma", "kl")
"""Distillation methods."""


def teacher_share(fraction: float, iterations: int, done: int) -> float:
    """DAgger's beta after `done` iterations: `fraction`, falling linearly to 0 over `iterations` (0: constant)."""
    if not iterations:
        return fraction
    return fraction * max(0.0, 1.0 - done / iterations)


class GroupedLoss:
    """Behaviour loss over named groups of labels: the mean over steps and labels of `weights` x the squared
    error (all weights 1: F.mse_loss); it keeps each group's unweighted mean squared error for the report."""

    def __init__(self, groups: dict[str, tuple[int, int]], weights: list[float]):
        self.groups, self.weights = groups, torch.as_tensor(weights, dtype=torch.float32)
        self.sums, self.count = torch.zeros(len(weights)), 0

    def __call__(self, actions: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
        if actions.shape[-1] != len(self.weights):
            raise ValueError(f"{actions.shape[-1]} actions but {len(self.weights)} label weights")
        squared = (actions - labels) ** 2
        self.sums = self.sums.to(squared.device) + squared.detach().reshape(-1, squared.shape[-1]).mean(0)
        self.count += 1
        return (squared * self.weights.to(squared.device)).mean()

    def report(self) -> dict[str, float]:
        """Each group's mean squared error since the last report (`behavior_<group>`), then a fresh start."""
        means = self.sums / max(self.count, 1)
        out = {f"behavior_{name}": means[a:b].mean().item() for name, (a, b) in self.groups.items()}
        self.sums, self.count = torch.zeros_like(self.sums), 0
        return out


class MixedDAgger(Distillation):
    """rsl-rl's Distillation (DAgger: the student acts, the teacher labels every step) in which, at first, the
    teacher acts in a share of the environments (DAgger's beta, Ross et al. 2011): `teacher_act_fraction` of
    them, falling linearly to none over `teacher_act_iterations` (0: the share stays). The student learns on
    every step either way; the teacher's share shows it the states of a game played well. With `label_groups`
    (name -> [start, stop) of the actions) the loss weighs each label by `label_weights` (GroupedLoss) and the
    report holds each group's error."""

    def __init__(self, *args, teacher_act_fraction: float = 0.0, teacher_act_iterations: int = 0,
                 label_groups: dict[str, tuple[int, int]] | None = None, label_weights: list[float] | None = None,
                 **kwargs):
        super().__init__(*args, **kwargs)
        self.teacher_act_fraction, self.teacher_act_iterations = teacher_act_fraction, teacher_act_iterations
        if label_groups:
            self.loss_fn = GroupedLoss(label_groups, label_weights)

    def update(self) -> dict[str, float]:
        """rsl-rl's update; with label groups, each group's mean squared error beside the (weighted) loss."""
        losses = super().update()
        if isinstance(self.loss_fn, GroupedLoss):
            losses.update(self.loss_fn.report())
        return losses

    def act(self, obs):
        actions = super().act(obs)
        share = teacher_share(self.teacher_act_fraction, self.teacher_act_iterations, self.num_updates)
        count = round(share * len(actions))
        if count:
            actions = actions.clone()
            actions[:count] = self.transition.privileged_actions[:count]
        return actions


class LatentRegression(Distillation):
    """RMA's second phase: rsl-rl's Distillation with the loss on latents (student encoder vs the teacher's
    z_p) instead of actions; the student's head and normaliser stay as the teacher's."""

    def act(self, obs):
        self.transition.actions = self.student(obs, stochastic_output=True).detach()
        self.transition.privileged_actions = self.teacher(obs).detach()
        self.transition.observations = obs
        return self.transition.actions

    def update(self) -> dict[str, float]:
        """Regress the student's z on the teacher's over the rollout (`gradient_length` steps per gradient
        step); the losses also report how far the student's actions are from the teacher's."""
        self.num_updates += 1
        totals, count, loss = {"latent": 0.0, "action_gap": 0.0}, 0, 0.0
        for _ in range(self.num_learning_epochs):
            for batch in self.storage.generator():
                with torch.no_grad():
                    target = self.teacher.encode(batch.observations)[0]
                z = self.student.encode(batch.observations)[0]
                step_loss = F.mse_loss(z, target)
                loss = loss + step_loss
                totals["latent"] += step_loss.item()
                with torch.no_grad():
                    totals["action_gap"] += F.mse_loss(self.student(batch.observations), batch.privileged_actions).item()
                count += 1
                if count % self.gradient_length == 0:
                    self.optimizer.zero_grad()
                    loss.backward()
                    if self.max_grad_norm:
                        torch.nn.utils.clip_grad_norm_(self.student.parameters(), self.max_grad_norm)
                    self.optimizer.step()
                    loss = 0.0
        self.storage.clear()
        return {k: v / max(count, 1) for k, v in totals.items()}


def vision_student_task(teacher_task: str) -> str | None:
    """The vision task a state soccer player's student plays (None when there is none)."""
    from legged.tasks import TASKS

    task = f"{teacher_task}-vision"
    return task if task in TASKS and TASKS[task].vision and TASKS[teacher_task].kind == "soccer" else None


def teacher_config(path: Path, student_task: str | None = None) -> TrainConfig:
    """The config of a teacher run for a student of `student_task` (default: the teacher's own task);
    ConfigError naming the problem when it cannot teach it."""
    run = RunDir(path)
    if not (run.path / "config.yaml").is_file():
        raise ConfigError(f"teacher {path} is not a run directory (no config.yaml)")
    config = run.load_config()
    if config.backend != "rsl":
        raise ConfigError(f"teacher {path} was trained with the {config.backend} backend; distillation needs an "
                          f"rsl teacher trained with --algo teacher")
    if student_task not in (None, config.task):
        if student_task != vision_student_task(config.task) or config.algo != "ppo":
            raise ConfigError(f"teacher {path} ({config.task}, --algo {config.algo}) cannot teach {student_task}: "
                              f"a student of another task is the vision student of a state soccer player "
                              f"(soccer-1v1 -> soccer-1v1-vision)")
        if not run.checkpoints():
            raise ConfigError(f"teacher {path} has no checkpoint yet")
        return config
    if config.algo != "teacher":
        vision = vision_student_task(config.task)
        hint = f" (or distil this soccer player into its vision student: --task {vision})" if vision else ""
        raise ConfigError(f"teacher {path} was trained with --algo {config.algo}; a teacher reads privileged "
                          f"observations: train one with `legged train {config.task} --algo teacher`{hint}")
    if not run.checkpoints():
        raise ConfigError(f"teacher {path} has no checkpoint yet")
    return config


def load_teacher(config: TrainConfig, env) -> tuple[TrainConfig, dict]:
    """(teacher config, teacher checkpoint payload) of a distillation run, checked against its environment."""
    from policies.rsl_backend import load_checkpoint

    path = Path(config.distill.teacher)
    teacher = teacher_config(path, config.task)
    payload = load_checkpoint(RunDir(path).latest_checkpoint())
    sizes = env.observation_dims()
    mine = {"state": "features"} if teacher.task != config.task else {}  # a vision student's teacher
    for group in ("state", "privileged_state"):
        if payload["obs_sizes"].get(group) != sizes.get(mine.get(group, group)):
            raise RunDirError(f"teacher {path} observed {group} of size {payload['obs_sizes'].get(group)}, this "
                              f"environment gives {sizes.get(mine.get(group, group))}")
    labels = payload["num_actions"] + getattr(env, "world_size", 0)  # a student that estimates the world: more
    if labels != env.action_size:
        raise RunDirError(f"teacher {path} has {payload['num_actions']} actions, its student {env.action_size}")
    return teacher, payload


def start_student(alg, config: TrainConfig, teacher: TrainConfig, payload: dict) -> None:
    """Load the teacher's actor into a new distillation (kl: the teacher is attached apart, policies.teacher_kl)
    and `distill.student_init` into its student (kl: its actor); rma also takes the teacher's head and
    normaliser."""
    student = alg.actor if config.algo == "kl" else alg.student
    if config.algo != "kl":
        alg.load(payload["alg"], {"teacher": True}, strict=True)
    if config.distill.student_init_whole:
        load_student_whole(student, Path(config.distill.student_init))
    elif config.distill.student_init:
        load_student_encoder(student, Path(config.distill.student_init))
    if config.algo != "rma":
        return
    student, source = alg.student, alg.teacher
    student.mlp.load_state_dict(source.mlp.state_dict())
    if student.obs_normalization:  # [state, history]: the teacher's state statistics, repeated
        steps, state = config.latent.history_steps + 1, student.state_dim
        for name in ("_mean", "_var", "_std"):
            getattr(student.obs_normalizer, name).copy_(getattr(source.obs_normalizer, name)[:, :state].repeat(1, steps))
        student.obs_normalization = False  # frozen: the head expects the teacher's scaling
    for p in list(student.mlp.parameters()) + list(student.distribution.parameters()):
        p.requires_grad_(False)


def check_student_init(init: Path) -> Path:
    """The checkpoint `distill.student_init` names: a run directory's newest, or a checkpoint file of a run
    (RUN/checkpoints/step_N.pt); RunDirError unless its run is a dagger vision student with that checkpoint."""
    file = init if init.suffix == ".pt" else None
    run = RunDir(init.parent.parent if file is not None else init)
    source = run.load_config()  # RunDirError naming the path if it is not a run
    if source.algo != "dagger" or not getattr(source.env, "vision", False) or not run.checkpoints():
        raise RunDirError(f"distill.student_init {init}: not a dagger vision student with a checkpoint (it "
                          f"trained {source.task} with --algo {source.algo})")
    if file is not None and not file.is_file():
        raise RunDirError(f"distill.student_init {init}: no such checkpoint; {run.path} has "
                          f"{', '.join(p.name for p in run.checkpoints())}")
    return file if file is not None else run.latest_checkpoint()


def load_student_whole(student: torch.nn.Module, run_path: Path) -> None:
    """Start `student` as the student of `run_path` (`distill.student_init`, with `student_init_whole`): every
    network and statistic; RunDirError naming the entries that do not fit. A state that grew at its end (e.g.
    `env.vision_sightings` added) is taken too: the new entries reach every layer that reads the state
    through zero weights, so the student starts acting exactly as its source did, and their normaliser's
    statistics follow the data within a few iterations."""
    from policies.rsl_backend import load_checkpoint

    source = load_checkpoint(check_student_init(run_path))["alg"]["student_state_dict"]
    mine = student.state_dict()
    source = _grown_state(source, mine, getattr(student, "cnn_latent_dim", 0))
    wrong = sorted(k for k in set(mine) | set(source) if k not in mine or k not in source
                   or tuple(source[k].shape) != tuple(mine[k].shape))
    if wrong:
        raise RunDirError(f"distill.student_init {run_path}: its student does not fit this one whole (missing or "
                          f"differently shaped: {', '.join(wrong[:8])}{' ...' if len(wrong) > 8 else ''}); drop "
                          f"distill.student_init_whole to take its camera encoder and normaliser only")
    student.load_state_dict({k: torch.as_tensor(v) for k, v in source.items()}, strict=True)


def _grown_state(source: dict, mine: dict, image_features: int) -> dict:
    """`source` widened to a student (`mine`) whose state has more entries at its end: the normaliser keeps the
    new entries' fresh statistics (its sample count capped), and every weight matrix that reads the state
    (the inputs [..., state, image features]) gets zero columns for them. Unchanged when nothing grew."""
    key = "obs_normalizer._mean"
    if key not in source or key not in mine or source[key].shape[-1] >= mine[key].shape[-1]:
        return source
    grown = mine[key].shape[-1] - source[key].shape[-1]
    out = dict(source)
    for name, value in source.items():
        value, target = torch.as_tensor(value), mine.get(name)
        if target is None or value.shape == target.shape:
            continue
        if name.startswith("obs_normalizer.") and value.dim() == 2 and target.shape[1] == value.shape[1] + grown:
            out[name] = torch.cat([value, target[:, value.shape[1]:]], dim=1)
        elif (name.rsplit(".", 1)[-1].startswith("weight") and value.dim() == 2 and target.shape[0] == value.shape[0]
              and target.shape[1] == value.shape[1] + grown):
            at = value.shape[1] - image_features  # the state ends where the image features begin
            zeros = torch.zeros(value.shape[0], grown, dtype=value.dtype)
            out[name] = torch.cat([value[:, :at], zeros, value[:, at:]], dim=1)
    if "obs_normalizer.count" in out:
        out["obs_normalizer.count"] = torch.clamp(torch.as_tensor(out["obs_normalizer.count"]), max=ADAPT_SAMPLES)
    return out


def load_student_encoder(student: torch.nn.Module, run_path: Path) -> None:
    """Start `student` with the camera encoder (`cnns.*`) and state normaliser (`obs_normalizer.*`) of the vision
    student `run_path` (`distill.student_init`: a run or one of its checkpoints); a state that grew at its end
    (e.g. `env.vision_heading`) takes the normaliser's statistics of the entries both have, with its sample count
    capped so that the new entries' statistics follow the data within a few iterations. RunDirError naming what
    does not fit."""
    from policies.rsl_backend import load_checkpoint

    mine = dict(student.state_dict())
    source = _grown_state(load_checkpoint(check_student_init(run_path))["alg"]["student_state_dict"], mine,
                          getattr(student, "cnn_latent_dim", 0))
    taken, wrong = {}, []
    for key, value in source.items():
        if not key.startswith(("cnns.", "obs_normalizer.")) or key not in mine:
            continue
        if tuple(value.shape) == tuple(mine[key].shape):
            taken[key] = torch.as_tensor(value)
        else:
            wrong.append(key)
    if not any(k.startswith("cnns.") for k in taken) or wrong:
        raise RunDirError(f"distill.student_init {run_path}: its camera encoder and normaliser do not fit this student "
                          f"({'shapes differ: ' + ', '.join(wrong) if wrong else 'no camera encoder'})")
    student.load_state_dict({**mine, **taken}, strict=True)


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
        changes.update(task=task, env=dataclasses.replace(teacher.env, vision=True), command_prior="",
                       selfplay=dataclasses.replace(teacher.selfplay, opponent="scripted"),
                       distill=dataclasses.replace(changes["distill"], teacher_prior=bool(teacher.command_prior)))
    for name, value in (("timesteps", timesteps), ("physics", physics), ("num_envs", num_envs), ("threads", threads)):
        if value is not None:
            changes[name] = value
    if method == "rma":  # the student acts with the teacher's head: same sizes
        changes["latent"] = dataclasses.replace(teacher.latent)
    config = apply_overrides(dataclasses.replace(teacher, **changes).resolved(), list(overrides))
    from policies.training import build_env, refuse_pilot

    refuse_pilot(config)
    if config.estimates_world and not teacher.command_prior:  # it adds the placo command itself, from its estimate
        raise ConfigError(f"command_prior=placo: the student adds the placo command to corrections it learns "
                          f"from a teacher that corrected that command; teacher {teacher_run} did not "
                          f"(its command_prior is '')")
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
    from policies.rsl_backend import train_rsl

    return train_rsl(build_env(config), config, run, resume=False, progress=progress)
