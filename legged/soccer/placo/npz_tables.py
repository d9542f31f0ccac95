"""Reading and writing the OP3's motion tables (gait, kick) as .npz files without pickles."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def load_arrays(path, fields, xp=np) -> dict:
    """The named arrays of an .npz file as `xp` (np or jnp) float32 arrays, keyed by field."""
    with np.load(path, allow_pickle=False) as f:
        return {k: xp.asarray(f[k], dtype=xp.float32) for k in fields}


def save_arrays(path, data: dict) -> Path:
    """Write `data` (name -> numpy array) compressed to `path`, creating its directory; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **data)
    return path
