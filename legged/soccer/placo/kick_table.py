"""The OP3's kicks as data: the kick table and its pure lookups, for jitted JAX (MJX) steps or numpy.

The table (`assets/placo/op3_kick.npz`, built offline by legged/soccer/placo/kick_build.py from placo's
whole-body IK) holds `targets[side, k]` for side 0 = right foot, 1 = left foot (its mirror image),
k = 0 .. n-1 at kick phase k / (n - 1), one control period apart. Both ends are the gait table's
`stand`, so a player can go walk -> stop -> kick -> start -> walk. Importing this needs no placo.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from legged.robots.spec import ASSETS_DIR
from legged.soccer.placo.gait_table import sequence_targets
from legged.soccer.placo.npz_tables import load_arrays

KICK_PATH = ASSETS_DIR / "placo" / "op3_kick.npz"
"""The committed kick table (regenerate with `python -m legged.soccer.placo.kick_build --out ...`)."""
SIDES = ("right", "left")
"""Kicking foot of `targets[side]`."""


class KickTable(NamedTuple):
    """The kicks as arrays (jnp or np): a pytree for jit / vmap."""

    targets: jax.Array
    """(2, n, 20) servo targets over kick phase [0, 1] (side 0: right foot, 1: left foot)."""
    duration: jax.Array
    """() kick duration, s (targets are ctrl_dt apart)."""
    ctrl_dt: jax.Array
    """() the control period the targets are sampled at, s."""
    stand: jax.Array
    """(20,) the standing pose both ends equal (the gait table's `stand`)."""
    ball: jax.Array
    """(2, 2) ball centre (x, y) to aim for, in the standing robot's frame (origin midway between the
    sole centres, x forward, y left), for each side."""
    contact_phase: jax.Array
    """() kick phase at which the kicking foot's target reaches the ball."""


def load_kick_table(path=KICK_PATH, xp=jnp) -> KickTable:
    """Read a kick table .npz (no pickles) into a `KickTable` of `xp` (jnp or np) float32 arrays."""
    return KickTable(**load_arrays(path, KickTable._fields, xp))


def kick_targets(table: KickTable, phase, side) -> jax.Array:
    """Servo targets (20,) at kick `phase` in [0, 1] (clipped) for `side` (0 right foot, 1 left foot)."""
    sequence = table.targets[jnp.asarray(side, dtype=jnp.int32)]
    return sequence_targets(sequence, jnp.asarray(phase, dtype=sequence.dtype) * (sequence.shape[0] - 1), 1.0)


def advance_kick_phase(phase, dt, table: KickTable):
    """Kick phase after dt seconds (not wrapped: >= 1 means the kick is over)."""
    return phase + dt / table.duration
