"""placo's walk as data: the OP3 gait table and its pure lookups, for jitted JAX (MJX) steps or numpy.

The table (`assets/placo/op3_gait.npz`, built offline by legged/soccer/placo/gait_build.py, which runs
`PlacoWalk` once per command of a grid) holds:

- `targets[ix, iy, iz, p]`: one steady stride (two steps) of servo targets (OP3.joint_names order, the
  walk's output including its feedforward) for the command (vx[ix], vy[iy], yaw_rate[iz]) at gait
  phase p / n_phase. Phase 0 is the start of the left foot's swing (right support); [0, 0.5) is the
  left step, [0.5, 1) the right step (each: single support, then double support);
- `period`: the stride duration, s (2 x (single + double support));
- `stand`: the walk's standing pose (double support, feet `feet_spacing` apart, CoM at `com_height`:
  knees about 0.19 rad more bent than OP3.default_pose). Blend to it from any pose (e.g. over 0.5 s);
- `start`: servo targets, one per control period, from `stand` to the first swing (placo's start
  double support, zero command); the gait table follows at phase `start_phase`;
- `stop`: servo targets, one per control period, from phase `stop_phase` of the zero-command gait
  back to `stand` (placo's end double support); switch to it only once the filtered command is near 0;
- `command_tau`: time constant of the first-order low-pass filter the table's command goes through
  (`filter_command`): the table switches command instantly, placo only from the next-but-one footstep;
- `kin_speed[ix, iy, iz]`: what placo actually plans for each grid command (forward, lateral, yaw rate
  of the feet's midpoint, robot frame): the walk clips steps and scales combined commands down.

The lookups are pure functions of arrays, usable under jit and vmap and with numpy tables and inputs:
`gait_targets` (multilinear over the command grid, clipped to it; linear over phase, wrapping),
`planned_speed` (the same over `kin_speed`), `advance_phase`, `filter_command` and `sequence_targets`
(`start`, `stop` and the kicks of legged/soccer/placo/kick_table.py). A player's memory is then its phase,
its filtered command and where it is in a start / stop sequence. Importing this module needs no placo.
"""

from __future__ import annotations

import json
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from legged.robots.spec import ASSETS_DIR
from legged.soccer.placo.npz_tables import load_arrays

GAIT_PATH = ASSETS_DIR / "placo" / "op3_gait.npz"
"""The committed gait table (regenerate with `python -m legged.soccer.placo.gait_build --out ...`)."""


class GaitTable(NamedTuple):
    """The walk as arrays (jnp or np); a pytree, so it can be passed through jit / vmap unchanged."""

    vx: jax.Array
    """(nx,) forward speeds of the command grid, m/s, increasing."""
    vy: jax.Array
    """(ny,) lateral speeds, m/s, increasing."""
    yaw_rate: jax.Array
    """(nz,) yaw rates, rad/s, increasing."""
    targets: jax.Array
    """(nx, ny, nz, n_phase, 20) servo targets over one stride, rad, OP3.joint_names order."""
    period: jax.Array
    """() stride duration, s."""
    ctrl_dt: jax.Array
    """() the control period the sequences are sampled at, s."""
    stand: jax.Array
    """(20,) standing pose (the start of `start`, the end of `stop` and of the kicks)."""
    start: jax.Array
    """(n_start, 20) targets from `stand` to the first swing, one per control period."""
    start_phase: jax.Array
    """() gait phase of the control period that follows `start`."""
    stop: jax.Array
    """(n_stop, 20) targets from gait phase `stop_phase` (zero command) to `stand`."""
    stop_phase: jax.Array
    """() gait phase at which `stop[0]` replaces the gait."""
    command_tau: jax.Array
    """() low-pass time constant of the command, s."""
    kin_speed: jax.Array
    """(nx, ny, nz, 3) placo's planned (forward, lateral, yaw rate) for each grid command."""

    @property
    def command_low(self) -> jax.Array:
        """(3,) the grid's lowest (vx, vy, yaw rate)."""
        return jnp.stack([self.vx[0], self.vy[0], self.yaw_rate[0]])

    @property
    def command_high(self) -> jax.Array:
        """(3,) the grid's highest (vx, vy, yaw rate)."""
        return jnp.stack([self.vx[-1], self.vy[-1], self.yaw_rate[-1]])


def load_gait_table(path=GAIT_PATH, xp=jnp) -> GaitTable:
    """Read a gait table .npz (no pickles) into a `GaitTable` of `xp` (jnp or np) float32 arrays."""
    return GaitTable(**load_arrays(path, GaitTable._fields, xp))


def load_gait_metadata(path=GAIT_PATH) -> dict:
    """The table's joint names, build settings (PlacoWalkConfig and grid) and fit residuals."""
    with np.load(path, allow_pickle=False) as f:
        return {"joint_names": tuple(str(n) for n in f["joint_names"]), "config": json.loads(str(f["config_json"])),
                "fit_rms": np.asarray(f["fit_rms"]), "fit_max": np.asarray(f["fit_max"])}


def _grid_cell(axis, x):
    """Lower index and weight of the upper neighbour of x on an increasing axis (x clipped to it)."""
    x = jnp.clip(x, axis[0], axis[-1])
    i = jnp.clip(jnp.searchsorted(axis, x, side="right") - 1, 0, axis.shape[0] - 2)
    return i, (x - axis[i]) / (axis[i + 1] - axis[i])


def _command_cell(table: GaitTable, command):
    """Lower grid indices (ix, iy, iz) and (2, 2, 2) corner weights of the grid cell of `command`."""
    command = jnp.asarray(command, dtype=table.targets.dtype)
    axes = (table.vx, table.vy, table.yaw_rate)
    (ix, wx), (iy, wy), (iz, wz) = (_grid_cell(axis, command[k]) for k, axis in enumerate(axes))
    w = [jnp.stack([1.0 - v, v]) for v in (wx, wy, wz)]
    return (ix, iy, iz), w[0][:, None, None] * w[1][None, :, None] * w[2][None, None, :]


def gait_targets(table: GaitTable, phase, command) -> jax.Array:
    """Servo targets (20,) at gait `phase` (any real: wraps to [0, 1)) for `command` (3,) = (vx, vy, yaw
    rate), interpolated multilinearly over the command grid (clipped to it) and linearly over phase.

    One robot: scalar phase, (3,) command; vmap it for several."""
    (ix, iy, iz), w_command = _command_cell(table, command)
    n = table.targets.shape[3]
    p = jnp.mod(jnp.asarray(phase, dtype=table.targets.dtype), 1.0) * n
    j = jnp.floor(p)
    wp = p - j
    j = j.astype(jnp.int32) % n
    two = jnp.arange(2)
    corners = table.targets[(ix + two)[:, None, None, None], (iy + two)[None, :, None, None],
                            (iz + two)[None, None, :, None], ((j + two) % n)[None, None, None, :]]
    weights = w_command[..., None] * jnp.stack([1.0 - wp, wp])
    return jnp.einsum("abcd,abcdj->j", weights, corners)


def planned_speed(table: GaitTable, command) -> jax.Array:
    """placo's planned (forward, lateral, yaw rate) for `command`, multilinear over the grid like the targets."""
    (ix, iy, iz), weights = _command_cell(table, command)
    two = jnp.arange(2)
    corners = table.kin_speed[(ix + two)[:, None, None], (iy + two)[None, :, None], (iz + two)[None, None, :]]
    return jnp.einsum("abc,abcj->j", weights, corners)


def advance_phase(phase, dt, table: GaitTable):
    """Gait phase after dt seconds, wrapped to [0, 1)."""
    return jnp.mod(phase + dt / table.period, 1.0)


def filter_command(filtered, command, dt, table: GaitTable, tau=None):
    """One step of the command low-pass filter (time constant `tau`, default table.command_tau), with
    the command first clipped to the grid: the command the table is looked up with."""
    tau = table.command_tau if tau is None else tau
    command = jnp.clip(jnp.asarray(command, dtype=table.targets.dtype), table.command_low, table.command_high)
    return filtered + (1.0 - jnp.exp(-dt / tau)) * (command - filtered)


def sequence_targets(sequence, t, dt):
    """Targets of a sequence sampled every dt (start, stop, kick), at time t since its first sample:
    linear interpolation, held at the ends."""
    n = sequence.shape[0]
    s = jnp.clip(jnp.asarray(t, dtype=sequence.dtype) / dt, 0.0, n - 1)
    i = jnp.clip(jnp.floor(s).astype(jnp.int32), 0, max(n - 2, 0))
    w = s - i
    return (1.0 - w) * sequence[i] + w * sequence[jnp.minimum(i + 1, n - 1)]
