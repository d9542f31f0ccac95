"""Held-out learning curves: a run's checkpoints evaluated on the same held-out episodes, each against the wall time
from the training process's start at which it was saved (imports, environment build and compilation included:
each process's first metrics record holds its `startup_s`). `legged curve RUN [RUN ...]`."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from legged.tasks import task_entry
from policies.eval_report import EvalRequest, evaluation_report
from policies.plots import line_plot
from policies.run_dir import RunDir, checkpoint_step

FIGURES = ("tracking_error_mps", "episodes_with_a_fall", "falls_per_episode", "episode_return", "success_rate",
           "collisions_per_episode", "final_distance_m", "goals_for_per_episode", "goals_against_per_episode",
           "win_rate")
"""Figures of an evaluation report a curve keeps (those the task reports)."""


def saved_at(run: RunDir) -> dict[int, float]:
    """Seconds from the training process's start to each logged step of `run` (its records' `wall_s` plus the
    `startup_s` of every process so far; runs logged before `startup_s` existed count from the training loop)."""
    out, startup = {}, 0.0
    for record in run.metrics():
        startup += float(record.get("startup_s") or 0.0)
        if isinstance(record.get("wall_s"), (int, float)) and isinstance(record.get("step"), int):
            out[record["step"]] = startup + float(record["wall_s"])
    return out


def learning_curve(request: EvalRequest, every: int = 1) -> dict:
    """`request` (a `legged eval` request; its checkpoint is ignored) applied to every `every`-th checkpoint of its
    run and to the last: {"run", "points": [{"step", "wall_s", figures...}]} (a confined task's figures are those of
    its one level, `request.difficulty`); ValueError when a confined run is not given exactly one level, or the run
    has no checkpoint or its metrics do not say when one was saved."""
    run = RunDir(request.run_dir)
    task = run.load_config().task  # RunDirError naming the path if it is not a run
    confined = task_entry(task).kind == "confined"
    if confined and (request.difficulty is None or len(request.difficulty) != 1):
        raise ValueError(f"{run.path}: {task} is evaluated per difficulty level; give one, e.g. --difficulty 0 "
                         "(legged curve plots one figure per checkpoint)")
    checkpoints = run.checkpoints()
    if not checkpoints:
        raise ValueError(f"{run.path} has no checkpoint to evaluate")
    if every < 1:
        raise ValueError(f"--every {every}: evaluate every Nth checkpoint, N >= 1")
    chosen = checkpoints[::-1][::every][::-1]  # the last one always
    times = saved_at(run)
    points = []
    for path in chosen:
        step = checkpoint_step(path)
        if step not in times:
            raise ValueError(f"{path}: {run.metrics_path} has no record of step {step} (when was it saved?)")
        report = evaluation_report(dataclasses.replace(request, checkpoint=str(path)))
        if confined:
            report = report["difficulties"][str(request.difficulty[0])]
        points.append({"step": step, "wall_s": times[step], **{k: report[k] for k in FIGURES if k in report}})
    level = {"difficulty": request.difficulty[0]} if confined else {}
    return {"run": str(run.path), "episodes": request.episodes, "seed": request.seed, "physics": request.physics,
            **level, "points": points}


def plot_curves(curves: list[dict], figure: str, out: str | Path, goal: float | None = None) -> Path:
    """`figure` of each curve against minutes from its process's start, one line per run, into a PNG."""
    series = {Path(c["run"]).name: ([p["wall_s"] / 60.0 for p in c["points"]], [p.get(figure) for p in c["points"]])
              for c in curves}
    return line_plot(series, out, "minutes from the training process's start", figure,
                     f"{figure}, held-out episodes", hline=goal)
