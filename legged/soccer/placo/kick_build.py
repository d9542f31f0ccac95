"""Building the OP3's kick table (legged/soccer/placo/kick_table.py) from placo's whole-body kinematics; needs placo.

`build_kick` drives the same `KinematicsSolver` tasks as the walk (`PlacoWalk`: both feet 6-D, CoM,
trunk orientation, arms and head held) from the walk's standing pose (double support, `stand` of the
gait table) through:

1. shift: the CoM moves (quintic ease) from between the feet to above the support foot's sole;
2. lift: the kicking foot rises and swings back (a `placo.CubicSpline3D` through way-points, zero
   velocity at each way-point except the strike's);
3. strike: it swings forward through where the ball lies (`ball_offset`: the ball's centre ahead of
   the kicking sole centre, standing), fastest as the toe reaches the ball;
4. retract and land: back above its start point, then down onto it;
5. unshift: the CoM back between the feet: the standing pose again (the kick starts and ends exactly at
   the gait table's `stand`, so a player can go walk -> stop -> kick -> start -> walk).

The support foot is the floor anchor throughout (placo's `ensure_on_floor` on it after every IK step).
Servo targets are the IK positions plus the walk's feedforward (`servo_targets`; the gravity torques
blended between the feet by where the CoM lies in double support, the support foot's alone once the
kicking foot is off the floor).

The right kick is computed; the left one is its mirror image (legged/soccer/placo/mirror.py; a constant
correction makes its ends exactly `stand`). Regenerate (a few seconds):
`python -m legged.soccer.placo.kick_build --out assets/placo/op3_kick.npz` (`--test` adds the MuJoCo ball test).
"""

from __future__ import annotations

import argparse
import dataclasses
import json

import numpy as np
import placo

from legged.robots.op3 import OP3
from legged.soccer.placo.kick_table import KICK_PATH, SIDES, load_kick_table
from legged.soccer.placo.mirror import mirror_joints, mirror_signs
from legged.soccer.placo.npz_tables import save_arrays
from legged.soccer.placo.open_loop import kick_ball_in_mujoco, walk_kick_walk_in_mujoco
from legged.soccer.placo.walk import PlacoWalk, PlacoWalkConfig, servo_targets, split_static_torques, static_torques

TOE_AHEAD = 0.0635
"""How far the toe lies ahead of the sole centre (site), m."""
BALL_RADIUS = 0.07
"""The soccer ball's radius, m."""


@dataclasses.dataclass(frozen=True)
class PlacoKickConfig:
    """Timing and geometry of the kick (right foot; the left kick mirrors it). Lengths in m, times in s."""

    hold_duration: float = 0.1
    """Standing still at both ends."""
    shift_duration: float = 0.8
    """CoM from between the feet to above the support sole."""
    lift_duration: float = 0.35
    """Kicking foot up and back."""
    strike_duration: float = 0.15
    """Back-swing to the end of the follow-through."""
    retract_duration: float = 0.35
    """Follow-through back to above the start point."""
    land_duration: float = 0.3
    """Down onto the start point."""
    unshift_duration: float = 0.8
    """CoM back between the feet."""
    com_x: float = 0.005
    """CoM target ahead of the support sole centre (site) during the kick."""
    com_y: float = 0.005
    """CoM target outboard of the support sole centre (the sole is centred 12.5 mm outboard of it)."""
    com_height: float | None = None
    """CoM height during the kick (None: the walk's com_height)."""
    lift_height: float = 0.04
    """Sole height at the back-swing and above the landing point."""
    back_swing: float = 0.06
    """How far behind its start the kicking sole goes."""
    strike_reach: float = 0.13
    """How far ahead of its start the kicking sole goes (the end of the follow-through)."""
    strike_height: float = 0.045
    """Sole height through the strike (the sole is an 8 mm plate: it meets the ball below its centre)."""
    strike_speed: float = 1.6
    """Forward speed of the sole's target at the strike's mid-point (also its highest)."""
    ball_offset: tuple[float, float] = (0.155, -0.025)
    """Ball centre relative to the kicking sole centre when standing (x ahead, y outboard; the toe is
    0.0635 ahead of the sole centre and the ball radius 0.07, so 0.155 leaves a 2 cm gap; 2.5 cm
    inboard, the ball leaves straight ahead, within about 5 degrees, in MuJoCo)."""


def _smooth(u):
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u**2)


def build_kick(config: PlacoKickConfig = PlacoKickConfig(), walk_config: PlacoWalkConfig | None = None,
               side: str = "right") -> dict:
    """Run the kick through placo's IK: servo targets (n, 20) one control period apart, the standing pose
    they start and end at, the ball's aim point, the contact phase, timing and speed diagnostics."""
    wc = walk_config or PlacoWalkConfig()
    walk = PlacoWalk(wc)
    stand = walk.reset((0.0, 0.0, 0.0))
    robot, solver, tasks = walk.robot, walk.solver, walk.tasks
    dt = wc.ctrl_dt
    sub = wc.ik_substeps
    sgn = 1.0 if side == "right" else -1.0  # +: the kicking foot is on the right (y < 0)
    support_side = "left" if side == "right" else "right"
    kick_frame, support_frame = f"{side}_foot", f"{support_side}_foot"
    T_left0, T_right0 = robot.get_T_world_left().copy(), robot.get_T_world_right().copy()
    T_kick0, T_sup0 = (T_right0, T_left0) if side == "right" else (T_left0, T_right0)
    feet0 = (T_left0[:3, 3], T_right0[:3, 3])
    com0 = robot.com_world().copy()
    com_h = config.com_height or wc.com_height
    R_trunk = tasks.trunk_orientation_task.R_world_frame.copy()
    # CoM target above the support sole: `com_y` outboard (away from the kicking foot).
    sup = T_sup0[:3, 3]
    com_sup = np.array([sup[0] + config.com_x, sup[1] + sgn * config.com_y, com_h])

    c = config
    t_shift = c.hold_duration
    t_lift = t_shift + c.shift_duration
    t_back = t_lift + c.lift_duration
    t_strike_end = t_back + c.strike_duration
    t_retract = t_strike_end + c.retract_duration
    t_land = t_retract + c.land_duration
    t_unshift = t_land + c.unshift_duration
    t_end = t_unshift + c.hold_duration
    p0 = T_kick0[:3, 3].copy()
    spline = placo.CubicSpline3D()
    zero = np.zeros(3)
    spline.add_point(t_lift, p0, zero)
    spline.add_point(t_back, p0 + [-c.back_swing, 0.0, c.lift_height], zero)
    t_mid = t_back + c.strike_duration / 2
    mid = p0 + [(c.strike_reach - c.back_swing) / 2, 0.0, c.strike_height]
    spline.add_point(t_mid, mid, np.array([c.strike_speed, 0.0, 0.0]))
    spline.add_point(t_strike_end, p0 + [c.strike_reach, 0.0, c.strike_height], zero)
    spline.add_point(t_retract, p0 + [0.0, 0.0, c.lift_height], zero)
    spline.add_point(t_land, p0, zero)

    def com_target(t):
        if t < t_land:
            return com0 + _smooth((t - t_shift) / c.shift_duration) * (com_sup - com0)
        return com_sup + _smooth((t - t_land) / c.unshift_duration) * (com0 - com_sup)

    def kick_pose(t):
        T = T_kick0.copy()
        if t_lift < t < t_land:
            T[:3, 3] = spline.pos(t)
        return T

    def gravity(t):
        if t_lift <= t <= t_land:
            return static_torques(robot, support_frame)
        return split_static_torques(robot, robot.com_world(), *feet0)

    robot.update_support_side(support_side)
    n = round(t_end / dt) + 1
    qs, taus, kick_pos = [], [], []
    t = 0.0
    for k in range(n):
        if k > 0:
            for _ in range(sub):
                t += dt / sub
                T_kick = kick_pose(t)
                T_l, T_r = (T_left0, T_kick) if side == "right" else (T_kick, T_right0)
                tasks.left_foot_task.T_world_frame = T_l
                tasks.right_foot_task.T_world_frame = T_r
                tasks.com_task.target_world = com_target(t)
                tasks.trunk_orientation_task.R_world_frame = R_trunk
                robot.update_kinematics()
                solver.solve(True)
                robot.update_support_side(support_side)
                robot.ensure_on_floor()
            robot.update_kinematics()
        qs.append(walk.joint_positions())
        taus.append(gravity(k * dt))
        kick_pos.append(robot.get_T_world_frame(kick_frame)[:3, 3].copy())
    qs, taus = np.array(qs), np.array(taus)
    # Feedforward as in PlacoWalk (central differences; the ends are at rest).
    qp = np.concatenate([qs[:1], qs, qs[-1:]])
    targets = servo_targets(wc, qp[:-2], qs, qp[2:], taus)
    # The ends are the walk's standing targets (the kick is planned from that very posture).
    end_error = float(max(np.abs(targets[0] - stand).max(), np.abs(targets[-1] - stand).max()))
    targets[0] = targets[-1] = stand
    kick_pos = np.array(kick_pos)
    # Ball: ahead of the kicking sole's start, `ball_offset` (y outboard), in the standing robot frame.
    centre = (T_left0[:3, 3] + T_right0[:3, 3]) / 2
    ball = p0[:2] - centre[:2] + np.array([c.ball_offset[0], -sgn * c.ball_offset[1]])
    # Contact: the toe reaches the ball's back.
    toe_x = kick_pos[:, 0] - centre[0] + TOE_AHEAD
    reach = np.nonzero(toe_x >= ball[0] - BALL_RADIUS)[0]
    contact = float(reach[0] / (n - 1)) if len(reach) else float("nan")
    return {"targets": targets, "stand": stand, "end_error": end_error, "duration": t_end, "ctrl_dt": dt,
            "ball": ball, "contact_phase": contact,
            "max_joint_speed": float(np.abs(qp[2:] - qp[:-2]).max() / (2 * dt)),
            "foot_speed": float(np.abs(np.diff(kick_pos[:, 0])).max() / dt)}


def build_kick_table(config: PlacoKickConfig = PlacoKickConfig(), walk_config: PlacoWalkConfig | None = None,
                     progress=print) -> dict:
    """Right kick from placo, left kick by mirroring; the .npz content (float32)."""
    wc = walk_config or PlacoWalkConfig()
    right = build_kick(config, wc, "right")
    signs = mirror_signs()
    stand = right["stand"]
    left = mirror_joints(right["targets"], signs)
    left += stand - mirror_joints(stand, signs)  # exact ends (the standing pose is symmetric to ~1e-4)
    direct = build_kick(config, wc, "left")
    asym = float(np.abs(direct["targets"] - left).max())
    if progress:
        progress(f"right kick: {len(right['targets'])} samples ({right['duration']:.2f} s), contact at phase "
                 f"{right['contact_phase']:.3f}, sole speed {right['foot_speed']:.2f} m/s, max joint speed "
                 f"{right['max_joint_speed']:.2f} rad/s, ends {right['end_error']:.1e} rad from stand; stand "
                 f"asymmetry {np.abs(stand - mirror_joints(stand, signs)).max():.1e} rad; mirrored vs placo's own "
                 f"left kick: max {asym:.4f} rad")
    ball = np.stack([right["ball"], right["ball"] * [1.0, -1.0]])
    f32 = lambda a: np.asarray(a, dtype=np.float32)
    settings = {"kick": dataclasses.asdict(config), "walk": dataclasses.asdict(wc), "sides": list(SIDES),
                "mirror_signs": signs.tolist(), "mirror_vs_direct_max": asym}
    return {"targets": f32(np.stack([right["targets"], left])), "duration": f32(right["duration"]),
            "ctrl_dt": f32(right["ctrl_dt"]), "stand": f32(stand), "ball": f32(ball),
            "contact_phase": f32(right["contact_phase"]), "joint_names": np.array(OP3.joint_names),
            "config_json": np.array(json.dumps(settings))}


def main(argv=None):
    """Build and save the kick table; optionally kick a ball with it in native MuJoCo."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(KICK_PATH), help="output .npz")
    parser.add_argument("--test", action="store_true", help="kick a ball in native MuJoCo (both sides)")
    args = parser.parse_args(argv)
    data = build_kick_table()
    path = save_arrays(args.out, data)
    print(f"wrote {path}: targets {data['targets'].shape}, duration {float(data['duration']):.2f} s, "
          f"ball at {np.round(data['ball'], 3).tolist()}")
    if args.test:
        table = load_kick_table(path, xp=np)
        for side in (0, 1):
            print(kick_ball_in_mujoco(table, side))
        print(walk_kick_walk_in_mujoco(kick=table))


if __name__ == "__main__":
    main()
