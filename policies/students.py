"""What a distillation's student is made of, shared by `legged distill` (policies.distill) and the rsl-rl backend
(policies.rsl_backend), which trains every student like any other run.

- the distillation losses: `MixedDAgger` (rsl-rl's Distillation, with the teacher acting in a falling share of
  the environments at first, and labels weighed by group: `GroupedLoss`) and `LatentRegression` (the student's
  history encoder regresses the teacher's latent);
- the teacher: which runs can teach which task (`teacher_config`, `vision_student_task`) and its checkpoint,
  checked against the student's environment (`load_teacher`);
- the student's start: the teacher's networks where the method takes them (`start_student`), and a vision
  student's camera encoder and normaliser, or its whole network, from an earlier student (`distill.student_init`),
  widened when the state grew (`load_student_encoder`, `load_student_whole`).
"""

from __future__ import annotations

from pathlib import Path

import torch
import torch.nn.functional as F
from rsl_rl.algorithms import Distillation

from legged.tasks import TASKS
from policies.checkpoints import load_rsl_checkpoint
from policies.config import ConfigError, TrainConfig
from policies.run_dir import RunDir, RunDirError
from policies.warm_start import ADAPT_SAMPLES


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
    teacher acts in a share of the environments (DAgger's beta): `teacher_act_fraction` of
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
                    actions = self.student(batch.observations)
                    totals["action_gap"] += F.mse_loss(actions, batch.privileged_actions).item()
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
    path = Path(config.distill.teacher)
    teacher = teacher_config(path, config.task)
    payload = load_rsl_checkpoint(RunDir(path).latest_checkpoint())
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
            statistic = getattr(source.obs_normalizer, name)[:, :state]
            getattr(student.obs_normalizer, name).copy_(statistic.repeat(1, steps))
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
    source = load_rsl_checkpoint(check_student_init(run_path))["alg"]["student_state_dict"]
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
    mine = dict(student.state_dict())
    source = _grown_state(load_rsl_checkpoint(check_student_init(run_path))["alg"]["student_state_dict"], mine,
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
