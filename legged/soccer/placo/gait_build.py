"""Building the OP3 gait table (legged/soccer/placo/gait_table.py) from placo's walk; needs placo.

`PlacoWalk` (legged/soccer/placo/walk.py) needs placo, a C++ library, at every control period. Here it
is run offline instead, once per command of a grid, and what it outputs is kept: for each command a
least-squares fit of a periodic piecewise-linear curve (`n_phase` knots) to `record_strides` strides
of servo targets, sampled at the control rate after `settle_strides` strides from standing (the stride
period is not a multiple of the control period, so the strides sample different phases); plus the
start (standing to the first swing) and stop (zero-command gait back to standing) sequences and the
speeds placo actually plans for each grid command.

Regenerate (about 35 s): `python -m legged.soccer.placo.gait_build --out assets/placo/op3_gait.npz`
(add `--compare` for `compare_table_to_solver`'s numbers, about 2 more minutes).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import time

import numpy as np

from legged.robots.op3 import OP3
from legged.soccer.placo.gait_table import GAIT_PATH, load_gait_table
from legged.soccer.placo.npz_tables import save_arrays
from legged.soccer.placo.walk import PlacoWalk, PlacoWalkConfig


@dataclasses.dataclass(frozen=True)
class GaitBuildConfig:
    """The command grid `build_gait_table` runs placo's walk over, and how it fits the strides."""

    vx: tuple[float, ...] = (-0.08, -0.04, 0.0, 0.1, 0.2)
    """Forward speeds of the grid, m/s: placo's limits are -0.083 (0.04 m per step) and 0.208 (0.1 m)."""
    vy: tuple[float, ...] = (-0.04, 0.0, 0.04)
    """Lateral speeds, m/s (+ left): placo plans at most about 0.043 m/s sideways with these feet."""
    yaw_rate: tuple[float, ...] = (-0.56, -0.28, 0.0, 0.28, 0.56)
    """Yaw rates, rad/s (+ counter-clockwise): placo plans at most 0.57 rad/s."""
    n_phase: int = 48
    """Phase samples per stride (the control rate gives 38.4 per stride)."""
    settle_strides: int = 3
    """Strides walked from standing before recording (the walk reaches its steady stride)."""
    record_strides: int = 5
    """Strides recorded and fitted per command."""
    command_tau: float = 0.5
    """Time constant of the table's command low-pass filter, s (about one step: placo's own delay)."""
    walk: PlacoWalkConfig = dataclasses.field(default_factory=PlacoWalkConfig)
    """The walk that is tabulated."""


def _yaw(rot) -> float:
    return float(np.arctan2(rot[1, 0], rot[0, 0]))


def _timing(walk: PlacoWalk) -> tuple[float, float, float]:
    """(control period, stride period, time of the first left swing)."""
    c = walk.config
    return c.ctrl_dt, 2 * c.step_period, float(walk.parameters.startend_double_support_duration())


def _periodic_basis(phases: np.ndarray, n: int) -> np.ndarray:
    """(samples, n) weights of the n knots on [0, 1) of a periodic piecewise-linear curve at `phases`."""
    p = np.mod(phases, 1.0) * n
    j = np.floor(p).astype(int) % n
    w = p - np.floor(p)
    basis = np.zeros((len(p), n))
    np.add.at(basis, (np.arange(len(p)), j), 1 - w)
    np.add.at(basis, (np.arange(len(p)), (j + 1) % n), w)
    return basis


def _planned_speed(taus, feet, starts) -> np.ndarray:
    """Mean (forward, lateral, yaw rate) of the feet's midpoint `feet` (x, y, yaw) between the sample
    indices `starts` (stride starts): displacement in the mid-stride heading / stride time."""
    yaw = np.unwrap(feet[:, 2])
    v = []
    for a, b in itertools.pairwise(starts):
        d, h = feet[b, :2] - feet[a, :2], (yaw[a] + yaw[b]) / 2
        dt = taus[b] - taus[a]
        v.append(((np.cos(h) * d[0] + np.sin(h) * d[1]) / dt, (-np.sin(h) * d[0] + np.cos(h) * d[1]) / dt,
                  (yaw[b] - yaw[a]) / dt))
    return np.mean(v, axis=0)


def record_stride(walk: PlacoWalk, command, config: GaitBuildConfig = GaitBuildConfig()) -> dict:
    """Walk from standing with a constant command and fit one stride of servo targets against phase:
    knots (n_phase, 20), fit residual rms / max (rad) and placo's planned speed."""
    dt, period, t0 = _timing(walk)
    walk.reset(tuple(command))
    t_rec = t0 + config.settle_strides * period
    t_end = t0 + (config.settle_strides + config.record_strides) * period
    taus, qs, feet = [], [], []
    tau = 0.0  # time of the targets `step` returns: the IK runs one period ahead
    while tau < t_end + dt:
        q = walk.step()
        tau = walk.t - dt
        if tau >= t_rec - 1e-9:
            taus.append(tau)
            qs.append(q)
            tl, tr = walk.robot.get_T_world_left(), walk.robot.get_T_world_right()
            feet.append((*(tl[:2, 3] + tr[:2, 3]) / 2, _yaw(tl[:3, :3])))
    taus, qs, feet = np.array(taus), np.array(qs), np.array(feet)
    basis = _periodic_basis((taus - t0) / period, config.n_phase)
    knots = np.linalg.lstsq(basis, qs, rcond=None)[0]
    resid = basis @ knots - qs
    starts = [int(np.argmin(np.abs(taus - (t_rec + k * period)))) for k in range(config.record_strides + 1)]
    return {"knots": knots, "rms": float(np.sqrt((resid**2).mean())), "max": float(np.abs(resid).max()),
            "kin_speed": _planned_speed(taus, feet, starts)}


def record_start(walk: PlacoWalk) -> tuple[np.ndarray, np.ndarray, float]:
    """(stand, start sequence, start_phase): standing targets and those up to the first swing."""
    dt, period, t0 = _timing(walk)
    stand = walk.reset((0.0, 0.0, 0.0))
    seq = [stand]  # the i-th output (i >= 1) of `step` is the target at time (i - 1) dt
    while (len(seq) - 1) * dt < t0 - 1e-9:
        seq.append(walk.step())
    return stand, np.array(seq), ((len(seq) - 1) * dt - t0) / period


def record_stop(walk: PlacoWalk, stride_index=3, tol=1e-4) -> tuple[np.ndarray, float]:
    """Stop sequence: from gait phase 0 of the zero-command walk (its `stride_index`-th stride) to
    standing, via placo's end double support (the next swing is cancelled). Returns (targets, phase)."""
    dt, period, t0 = _timing(walk)
    stand = walk.reset((0.0, 0.0, 0.0))
    t_stop = t0 + stride_index * period
    n_before = int(np.ceil(t_stop / dt - 1e-9))  # the first target at or after t_stop: output n_before + 1
    for _ in range(n_before):
        walk.step()
    walk.finish()  # the swing that starts at t_stop is cancelled: the walk ends standing
    seq = []
    while True:
        seq.append(walk.step())
        if walk.t > walk.trajectory.t_end and np.abs(seq[-1] - stand).max() < tol and len(seq) > 2:
            break
        if len(seq) > 400:
            raise RuntimeError("the stop did not converge to the standing pose")
    seq[-1] = stand
    return np.array(seq), (n_before * dt - t0) / period % 1.0


def build_gait_table(config: GaitBuildConfig = GaitBuildConfig(), progress=print) -> dict:
    """Run `PlacoWalk` over the command grid; return the .npz content (numpy, float32 arrays)."""
    c = config
    walk = PlacoWalk(c.walk)
    dt, period, _ = _timing(walk)
    shape = (len(c.vx), len(c.vy), len(c.yaw_rate))
    targets = np.zeros((*shape, c.n_phase, len(OP3.joint_names)))
    kin, fit_rms, fit_max = np.zeros((*shape, 3)), np.zeros(shape), np.zeros(shape)
    t_wall = time.perf_counter()
    for n, (i, j, k) in enumerate(np.ndindex(shape)):
        rec = record_stride(walk, (c.vx[i], c.vy[j], c.yaw_rate[k]), c)
        targets[i, j, k], kin[i, j, k] = rec["knots"], rec["kin_speed"]
        fit_rms[i, j, k], fit_max[i, j, k] = rec["rms"], rec["max"]
        if progress:
            progress(f"[{n + 1}/{np.prod(shape)}] command ({c.vx[i]:+.2f}, {c.vy[j]:+.2f}, {c.yaw_rate[k]:+.2f}): "
                     f"planned ({kin[i, j, k, 0]:+.3f}, {kin[i, j, k, 1]:+.3f}, {kin[i, j, k, 2]:+.3f}), "
                     f"fit rms {rec['rms']:.4f} max {rec['max']:.4f} rad ({time.perf_counter() - t_wall:.0f} s)")
    stand, start, start_phase = record_start(walk)
    stop, stop_phase = record_stop(walk)
    settings = {**dataclasses.asdict(c), "phase_zero": "start of the left foot's swing (right single support)"}
    f32 = lambda a: np.asarray(a, dtype=np.float32)
    return {"vx": f32(c.vx), "vy": f32(c.vy), "yaw_rate": f32(c.yaw_rate), "targets": f32(targets),
            "period": f32(period), "ctrl_dt": f32(dt), "stand": f32(stand), "start": f32(start),
            "start_phase": f32(start_phase), "stop": f32(stop), "stop_phase": f32(stop_phase),
            "command_tau": f32(c.command_tau), "kin_speed": f32(kin), "fit_rms": f32(fit_rms), "fit_max": f32(fit_max),
            "joint_names": np.array(OP3.joint_names), "config_json": np.array(json.dumps(settings))}


def main(argv=None):
    """Build and save the gait table; optionally compare it with the live walk."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(GAIT_PATH), help="output .npz")
    parser.add_argument("--n-phase", type=int, default=GaitBuildConfig.n_phase)
    parser.add_argument("--compare", action="store_true", help="also print compare_table_to_solver's numbers")
    parser.add_argument("--skip-build", action="store_true", help="compare an existing table only")
    args = parser.parse_args(argv)
    if not args.skip_build:
        data = build_gait_table(GaitBuildConfig(n_phase=args.n_phase))
        path = save_arrays(args.out, data)
        print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB): targets {data['targets'].shape}, "
              f"period {float(data['period']):.3f} s, start {len(data['start'])}, stop {len(data['stop'])} samples")
    if args.compare:
        from legged.soccer.placo.open_loop import compare_table_to_solver  # JAX and MuJoCo load for --compare only

        table = load_gait_table(args.out, xp=np)
        for mode in ("filter", "stride"):
            r = compare_table_to_solver(table, mode=mode, grid_speeds=mode == "filter")
            grid = r.pop("grid_speeds", None)
            r.pop("rms_per_joint")
            print(json.dumps(r))
            for g in grid or []:
                print(g)


if __name__ == "__main__":
    main()
