"""`legged slim RUN`: a run's checkpoints rewritten with only what a finished policy needs.

A checkpoint saved while training holds, besides the networks, what only going on with that training needs: the
optimiser's moments (Adam keeps two per weight, so they are twice the networks), a soccer run's pool of past
selves its learner plays against and the random generator's state. A shipped policy is evaluated, watched,
exported, averaged, distilled and fine-tuned from, never resumed, so its checkpoint needs none of them: a soccer
player's file shrinks from 12 MB to 2 MB. What a fine-tune of the same task reads to go on where the run stood
stays, as it is small: each environment's terrain-curriculum level and the learning rate the optimiser had
reached (`learning_rate`; policies.warm_start). A slimmed checkpoint says so (`slimmed`), and `legged train
--resume` refuses it in one line that names the way on (`--init-from`).
"""

from __future__ import annotations

import io
from pathlib import Path

import torch

from legged.files import write_atomic
from policies.checkpoints import BRAX_SUFFIX, encode_brax_checkpoint, load_brax_checkpoint, load_rsl_checkpoint
from policies.run_dir import RunDir, RunDirError

TRAINING_STATE = ("optimizer_state_dict", "rnd_optimizer_state_dict")
"""Parts of an rsl-rl learner's state (`alg`) that only further training reads: its optimisers."""

RESUME_ONLY = ("opponent_pool", "randomization_scales", "torch_rng")
"""Entries of an rsl checkpoint that only a resumed run reads (policies.rsl_backend.train_rsl); its
`curriculum_levels` stay for a fine-tune (policies.warm_start.source_levels)."""


def slim_payload(payload: dict) -> dict:
    """An rsl checkpoint's payload without what only resuming needs, marked `slimmed`; the learning rate its
    optimiser had reached is kept as `learning_rate` (a fine-tune of the same task starts its new optimiser there)."""
    alg = {k: v for k, v in payload["alg"].items() if k not in TRAINING_STATE}
    slim = dict({k: v for k, v in payload.items() if k not in RESUME_ONLY}, alg=alg, slimmed=True)
    optimiser = payload["alg"].get("optimizer_state_dict")
    if optimiser and optimiser.get("param_groups"):
        slim["learning_rate"] = float(optimiser["param_groups"][0]["lr"])
    return slim


def load_any(path: Path) -> dict:
    """A checkpoint of either backend, read with its safe loader."""
    return load_brax_checkpoint(path) if path.suffix == f".{BRAX_SUFFIX}" else load_rsl_checkpoint(path)


def refuse_slimmed(path: Path, task: str = "TASK") -> None:
    """RunDirError in one line if checkpoint `path` (of a run of `task`) was slimmed: nothing to resume from."""
    if load_any(path).get("slimmed"):
        run = path.parent.parent
        raise RunDirError(f"{path} holds a finished policy's weights only (slimmed by `legged slim`: no optimiser "
                          f"state), so {run} cannot be resumed; fine-tune from it instead: legged train {task} "
                          f"--init-from {run}")


def _slimmed_bytes(path: Path) -> bytes | None:
    """The slimmed file's bytes, or None if `path` is slimmed already."""
    payload = load_any(path)
    if payload.get("slimmed"):
        return None
    if path.suffix == f".{BRAX_SUFFIX}":
        meta = {k: v for k, v in payload.items() if k not in ("backend", "params_leaves", "optimizer_leaves")}
        return encode_brax_checkpoint(dict(meta, slimmed=True), payload["params_leaves"])
    buffer = io.BytesIO()
    torch.save(slim_payload(payload), buffer)
    return buffer.getvalue()


def slim_run(run_dir: str | Path) -> dict:
    """Slim every checkpoint of run `run_dir` in place (each written atomically and read back with the safe
    loader); returns the run, its checkpoints and their sizes before and after."""
    run = RunDir(run_dir)
    if not run.config_path.is_file():
        raise RunDirError(f"{run.path} is not a run directory (no config.yaml)")
    paths = run.checkpoints()
    if not paths:
        raise RunDirError(f"{run.path} has no checkpoint to slim")
    before = after = 0
    rewritten = []
    for path in paths:
        before += path.stat().st_size
        data = _slimmed_bytes(path)
        if data is not None:
            write_atomic(path, data)
            load_any(path)  # it reads back with the safe loader
            rewritten.append(str(path))
        after += path.stat().st_size
    return {"run": str(run.path), "checkpoints": len(paths), "slimmed": rewritten, "bytes_before": before,
            "bytes_after": after}
