"""The checkpoint formats, data only: what a run directory's checkpoints hold and how they are read and written.

    rsl   RUN/checkpoints/step_N.pt   torch.save of tensors, numbers, strings, lists and dicts, read back with
                                      `torch.load(weights_only=True)`, which never runs code from the file
    brax  RUN/checkpoints/step_N.npz  numpy arrays (the parameters' and optimiser state's leaves) and JSON text,
                                      read with `numpy.load(allow_pickle=False)`

Loaders raise RunDirError naming the file when it is damaged, foreign, or (rsl) holds Python objects; old pickled
checkpoints are converted once by `legged convert-checkpoints` (policies.convert). The networks the parameters
fill are built elsewhere (policies.algorithms, policies.brax_networks); this module knows only the files.
"""

from __future__ import annotations

import io
import json
import pickle
import warnings
import zipfile
from pathlib import Path

import jax
import numpy as np
import torch

from policies.run_dir import RunDir, RunDirError


def load_rsl_checkpoint(path: Path) -> dict:
    """A checkpoint written by `save_rsl_checkpoint`, read as data only (tensors, numbers, strings, lists and dicts:
    `torch.load(weights_only=True)`, which never runs code from the file); RunDirError naming the file if it
    is damaged, foreign, or holds anything else."""
    if not zipfile.is_zipfile(path):
        raise RunDirError(f"checkpoint {path} cannot be read: not a torch checkpoint (torch.save writes zip files)")
    try:
        with warnings.catch_warnings():  # torch warns about pickle protocols before it refuses them
            warnings.simplefilter("ignore")
            payload = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        cause = next((line[line.index("Unsupported global"):].split(" was not")[0] for line in lines
                      if "Unsupported global" in line), None)
        if cause is None:  # not an object the safe loader refused: the file is damaged or not a checkpoint
            reason = next((line for line in lines if "load key" in line or "truncated" in line),
                          lines[-1] if lines else "")
            raise RunDirError(f"checkpoint {path} cannot be read: {reason}") from None
        raise RunDirError(f"checkpoint {path} holds Python objects beyond tensors and plain data, and is not "
                          f"loaded (loading it could run code from it): {cause}. If you trust its run, convert it "
                          f"once with: legged convert-checkpoints {path.parent.parent} --trust-pickles") from None
    except Exception as exc:
        raise RunDirError(f"checkpoint {path} cannot be read: {exc}") from None
    if not isinstance(payload, dict) or payload.get("backend") != "rsl":
        raise RunDirError(f"{path} is not an rsl-rl checkpoint of this project")
    if "opponent_pool" in payload:
        payload["opponent_pool"] = as_numpy(payload["opponent_pool"])
    return payload


def save_rsl_checkpoint(run: RunDir, alg, iteration: int, step: int, obs_sizes: dict, num_actions: int,
                        extra: dict | None = None, curriculum_levels: np.ndarray | None = None,
                        randomization_scales: np.ndarray | None = None) -> Path:
    """Model, optimiser, counters, RNG state of the rsl-rl algorithm `alg`, what the task family adds (`extra`, e.g.
    soccer self-play's `opponent_pool`; its arrays stored as tensors), (terrain curricula) each environment's
    level and (a randomisation curriculum) each environment's scale, written atomically."""
    buffer = io.BytesIO()
    payload = {"backend": "rsl", "alg": alg.save(), "iteration": iteration, "step": step, "obs_sizes": obs_sizes,
               "num_actions": num_actions, "torch_rng": torch.get_rng_state()}
    payload.update({k: as_tensors(v) for k, v in (extra or {}).items()})
    if curriculum_levels is not None:
        payload["curriculum_levels"] = torch.from_numpy(np.array(curriculum_levels))  # a writable copy
    if randomization_scales is not None:
        payload["randomization_scales"] = torch.from_numpy(np.array(randomization_scales))
    torch.save(payload, buffer)
    return run.write_checkpoint(step, "pt", buffer.getvalue())


def as_tensors(obj):
    """numpy arrays inside nested dicts, lists and tuples as torch tensors (data-only checkpoints)."""
    if isinstance(obj, np.ndarray):
        return torch.from_numpy(np.array(obj))  # a contiguous, writable copy
    if isinstance(obj, dict):
        return {k: as_tensors(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(as_tensors(v) for v in obj)
    return obj


def as_numpy(obj):
    """The inverse of `as_tensors`."""
    if isinstance(obj, torch.Tensor):
        return obj.numpy()
    if isinstance(obj, dict):
        return {k: as_numpy(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(as_numpy(v) for v in obj)
    return obj


BRAX_SUFFIX = "npz"
"""Brax checkpoints are .npz files of arrays (numpy.load with allow_pickle=False never runs code)."""


def encode_brax_checkpoint(meta: dict, params, optimizer_state=None) -> bytes:
    """A data-only checkpoint: the leaves of `params` ((normalizer, policy, value)) and of the optimiser
    state as arrays, `meta` (step, obs_sizes, num_actions, ...) as JSON text. The tree structures are not
    stored: loaders rebuild them from the run's config (policies.brax_networks.params_template) or from Brax's
    fresh state."""
    arrays = {f"params_{i:05d}": np.asarray(x) for i, x in enumerate(jax.tree_util.tree_leaves(params))}
    if optimizer_state is not None:
        arrays.update({f"optimizer_{i:05d}": np.asarray(x)
                       for i, x in enumerate(jax.tree_util.tree_leaves(optimizer_state))})
    arrays["meta"] = np.array(json.dumps({"backend": "brax", **meta}))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def load_brax_checkpoint(path) -> dict:
    """A Brax checkpoint of this project as data: its meta entries plus `params_leaves` and
    `optimizer_leaves` (lists of arrays); RunDirError naming the file if it is damaged or foreign."""
    path = Path(path)
    if path.suffix == ".pkl":
        raise RunDirError(f"{path} is a pickled checkpoint of an earlier version of legged; pickles can run code "
                          "when loaded, so legged no longer reads them. If you trust the file, convert its run "
                          f"once with: legged convert-checkpoints {path.parent.parent} --trust-pickles")
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            leaves = lambda prefix: [z[k] for k in sorted(n for n in z.files if n.startswith(prefix))]
            payload = dict(meta, params_leaves=leaves("params_"), optimizer_leaves=leaves("optimizer_") or None)
    except Exception as exc:
        raise RunDirError(f"checkpoint {path} cannot be read: {exc}") from None
    if payload.get("backend") != "brax":
        raise RunDirError(f"{path} is not a Brax checkpoint of this project")
    payload["obs_sizes"] = {k: v if isinstance(v, int) else tuple(v) for k, v in payload["obs_sizes"].items()}
    return payload


def fill(template, leaves: list, what: str, path):
    """`template`'s tree with `leaves` (checked one by one); RunDirError naming `what` if they do not fit."""
    expected = jax.tree_util.tree_leaves(template)
    if len(expected) != len(leaves) or any(np.shape(a) != np.shape(b) for a, b in zip(expected, leaves)):
        raise RunDirError(f"{path}: the saved {what} ({len(leaves)} arrays) do not fit this run's networks "
                          f"({len(expected)} arrays); was it written with other layer sizes?")
    return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(template),
                                        [np.asarray(b, np.asarray(a).dtype) for a, b in zip(expected, leaves)])
