"""`legged average SOURCE SOURCE... --out RUN`: one policy whose weights are the mean of several checkpoints.

Checkpoints of one network fine-tuned from a common start usually lie in one basin of the loss, and the mean of
their weights (a "uniform soup", Wortsman et al. 2022; along one run, stochastic weight averaging, Izmailov et al.
2018) is often steadier than any one of them. Every floating-point tensor of the learner is averaged: the
actor's (or student's) weights, its observation normaliser's mean and variance (its standard deviation is the
square root of the mean variance) and the optimiser's moments; whole numbers (counts) and other plain numbers
(an optimiser's learning rate) are the largest of the sources. A distillation's teacher must be the same in
every source (it is copied). The output is a run directory that eval, view, drill, export and `distill.student_init`
accept: the first source's config.yaml (and teacher.yaml), one checkpoint named by the largest source step, and
averaged_from.json naming the sources and their weights. If any source was slimmed (policies.slim: weights only),
the mean is slimmed too.
"""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import torch

from policies.checkpoints import load_rsl_checkpoint
from policies.config import to_dict
from policies.run_dir import RunDir, RunDirError
from policies.slim import slim_payload

TEACHER = "teacher_state_dict"
"""The frozen teacher of a distillation checkpoint: copied, never averaged."""


def resolve_source(source: str | Path) -> tuple[RunDir, Path]:
    """A run directory (its newest checkpoint) or a checkpoint file inside RUN/checkpoints/."""
    path = Path(source)
    if path.is_file():
        run = RunDir(path.parent.parent)
        if path.parent.name != "checkpoints" or not run.config_path.is_file():
            raise RunDirError(f"{path} is not a checkpoint inside a run (RUN/checkpoints/step_*.pt)")
        return run, path
    if not path.is_dir():
        raise RunDirError(f"{path} is neither a run directory nor a checkpoint file")
    run = RunDir(path)
    run.load_config()  # names the path when it is not a run
    return run, run.latest_checkpoint()


def _mean(values: list, weights: list[float], where: str):
    """The weighted mean of matching nested structures (dicts, lists, tensors; other values must agree)."""
    first = values[0]
    if isinstance(first, dict):
        if any(not isinstance(v, dict) or v.keys() != first.keys() for v in values):
            raise RunDirError(f"the checkpoints differ in what {where} holds: not the same network")
        return {k: _mean([v[k] for v in values], weights, f"{where}.{k}") for k in first}
    if isinstance(first, (list, tuple)):
        if any(not isinstance(v, (list, tuple)) or len(v) != len(first) for v in values):
            raise RunDirError(f"the checkpoints differ in the length of {where}")
        return type(first)(_mean([v[i] for v in values], weights, f"{where}[{i}]") for i in range(len(first)))
    if isinstance(first, torch.Tensor):
        if any(not isinstance(v, torch.Tensor) or v.shape != first.shape for v in values):
            shapes = [tuple(v.shape) if isinstance(v, torch.Tensor) else type(v).__name__ for v in values]
            raise RunDirError(f"{where} has shapes {shapes} in the checkpoints: not the same network")
        if first.is_floating_point():
            return sum(w * v.to(torch.float64) for w, v in zip(weights, values)).to(first.dtype)
        return torch.stack(list(values)).max(dim=0).values  # counts: the largest
    if isinstance(first, bool) or not isinstance(first, (int, float)):
        if any(v != first for v in values):
            raise RunDirError(f"the checkpoints differ in {where} ({values}): not the same setting")
        return first
    return max(values)  # plain numbers (optimiser steps)


def _fix_normalisers(state: dict) -> None:
    """rsl-rl's empirical normaliser divides by `_std`, kept the square root of its `_var`: so here too."""
    for key in [k for k in state if isinstance(k, str) and k.endswith("._var")]:
        std = key[: -len("_var")] + "_std"
        if std in state:
            state[std] = torch.sqrt(state[key])


def average_checkpoints(sources: list[str | Path], out: str | Path, weights: list[float] | None = None) -> dict:
    """Write the weighted mean of the sources' learners as a new run at `out`; a report of what was averaged."""
    if len(sources) < 2:
        raise ValueError(f"averaging needs at least two sources, got {len(sources)}")
    weights = [1.0] * len(sources) if weights is None else [float(w) for w in weights]
    if len(weights) != len(sources) or any(not w > 0 for w in weights):
        raise ValueError(f"--weights needs one positive number per source ({len(sources)}), got {weights}")
    weights = [w / sum(weights) for w in weights]
    resolved = [resolve_source(s) for s in sources]
    configs = [run.load_config() for run, _ in resolved]
    for (run, _), config in zip(resolved, configs):
        if config.backend != "rsl":
            raise RunDirError(f"averaging reads rsl-rl checkpoints; {run.path} is a {config.backend} run")
    for (run, _), config in zip(resolved[1:], configs[1:]):
        for field in ("task", "algo"):
            if getattr(config, field) != getattr(configs[0], field):
                raise RunDirError(f"{resolved[0][0].path} and {run.path} differ in {field} "
                                  f"({getattr(configs[0], field)!r} and {getattr(config, field)!r})")
        if to_dict(config)["env"] != to_dict(configs[0])["env"]:
            raise RunDirError(f"{resolved[0][0].path} and {run.path} were trained in differently configured "
                              "environments (their config.yaml `env` sections differ)")
    target = RunDir(out)
    if target.config_path.exists():  # before any checkpoint is read
        raise RunDirError(f"{target.path} already holds a run; choose another --out")
    payloads = [load_rsl_checkpoint(path) for _, path in resolved]
    for key in ("obs_sizes", "num_actions"):
        if any(p[key] != payloads[0][key] for p in payloads):
            raise RunDirError(f"the checkpoints differ in {key}: {[p[key] for p in payloads]}")
    if any(p.get("slimmed") for p in payloads):  # one source holds weights only: so does the mean
        payloads = [slim_payload(p) for p in payloads]
    if any(p["alg"].keys() != payloads[0]["alg"].keys() for p in payloads):
        raise RunDirError(f"the checkpoints hold different learners: {[sorted(p['alg']) for p in payloads]}")
    alg = {}
    for part in payloads[0]["alg"]:
        values = [p["alg"][part] for p in payloads]
        if part == TEACHER:
            if any(v.keys() != values[0].keys() or any(not torch.equal(v[k], values[0][k]) for k in v)
                   for v in values):
                raise RunDirError("the sources were distilled from different teachers (teacher_state_dict "
                                  "differs): a student's mean is only meaningful for one teacher")
            alg[part] = values[0]
        else:
            alg[part] = _mean(values, weights, part)
            if isinstance(alg[part], dict):
                _fix_normalisers(alg[part])
    step = max(int(p["step"]) for p in payloads)
    payload = dict(payloads[0], alg=alg, step=step, iteration=max(int(p["iteration"]) for p in payloads))
    record = {"sources": [{"checkpoint": str(path), "step": int(p["step"]), "weight": round(w, 6)}
                          for (_, path), p, w in zip(resolved, payloads, weights)], "step": step}

    target.create(configs[0])
    first = resolved[0][0].path
    if (first / "teacher.yaml").is_file():
        shutil.copyfile(first / "teacher.yaml", target.path / "teacher.yaml")
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    checkpoint = target.write_checkpoint(step, "pt", buffer.getvalue())
    (target.path / "averaged_from.json").write_text(json.dumps(record, indent=2) + "\n")
    load_rsl_checkpoint(checkpoint)  # it reads back with the safe loader
    return dict(record, run=str(target.path), checkpoint=str(checkpoint))
