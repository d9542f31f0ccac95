"""`legged convert-checkpoints RUN --trust-pickles`: rewrite an old run's pickled checkpoints as data only.

The one place in legged that unpickles a file, and only when the user says the file is trusted: pickles
can run code when loaded. Each converted checkpoint is written atomically and read back with the safe
loaders before the pickle is removed.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path

import torch

from policies.brax_networks import params_template
from policies.checkpoints import (BRAX_SUFFIX, as_tensors, encode_brax_checkpoint, fill, load_brax_checkpoint,
                                  load_rsl_checkpoint)
from policies.run_dir import RunDir, RunDirError


def _convert_brax(run: RunDir, path: Path) -> Path:
    with open(path, "rb") as f:
        old = pickle.load(f)  # trusted by the user (--trust-pickles)
    meta = {"step": int(old["step"]), "obs_sizes": old["obs_sizes"], "num_actions": int(old["num_actions"]),
            "task": run.load_config().task}
    new = run.write_checkpoint(meta["step"], BRAX_SUFFIX,
                               encode_brax_checkpoint(meta, old["params"], old.get("optimizer_state")))
    payload = load_brax_checkpoint(new)
    fill(params_template(run.load_config(), payload["obs_sizes"], payload["num_actions"]), payload["params_leaves"],
         "parameters", new)
    path.unlink()
    return new


def _convert_rsl(run: RunDir, path: Path) -> Path:
    old = torch.load(path, map_location="cpu", weights_only=False)  # trusted by the user (--trust-pickles)
    if "opponent_pool" in old:
        old["opponent_pool"] = as_tensors(old["opponent_pool"])
    buffer = io.BytesIO()
    torch.save(old, buffer)
    step = int(old["step"])
    new = run.write_checkpoint(step, "pt", buffer.getvalue())
    load_rsl_checkpoint(new)
    return new


def needs_conversion(path: Path) -> bool:
    """Whether a checkpoint can only be read by unpickling arbitrary objects."""
    if path.suffix == ".pkl":
        return True
    if path.suffix == ".pt":
        try:
            load_rsl_checkpoint(path)
        except RunDirError as exc:
            return "beyond tensors" in str(exc)
    return False


def convert_run(run_dir: str | Path, trust_pickles: bool) -> dict:
    """Convert every checkpoint of a run that needs unpickling; without `trust_pickles` only list them."""
    run = RunDir(run_dir)
    run.load_config()  # a run directory, or a clear error
    pickled = [p for p in run.checkpoints() if needs_conversion(p)]
    if pickled and not trust_pickles:
        raise RunDirError(f"{len(pickled)} checkpoint(s) of {run.path} need unpickling ({', '.join(p.name for p in pickled)}); "
                          "pickles can run code when loaded: convert them only if you trust this run, with "
                          f"legged convert-checkpoints {run.path} --trust-pickles")
    converted = [str(_convert_brax(run, p) if p.suffix == ".pkl" else _convert_rsl(run, p)) for p in pickled]
    return {"run": str(run.path), "converted": converted, "checkpoints": [str(p) for p in run.checkpoints()]}
