"""Open-loop checks of the OP3's motion tables in native MuJoCo: the robot on a flat floor (optionally
with the soccer ball) driven by servo targets at the control rate, with nothing measured or fed back.

`TableWalker` plays a gait table as a JAX player would (its memory in numpy); `walk_table_in_mujoco`,
`kick_ball_in_mujoco` and `walk_kick_walk_in_mujoco` measure what the tables do to the robot and the
ball; `compare_table_to_solver` sets the table against the live `PlacoWalk` (that one needs placo).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from legged.robots.op3 import OP3, OP3_CTRL_DT
from legged.soccer.config import SoccerSceneConfig
from legged.soccer.placo.gait_table import (GaitTable, advance_phase, filter_command, gait_targets, load_gait_table,
                                            planned_speed)
from legged.soccer.placo.kick_table import SIDES, KickTable, load_kick_table

BALL_RADIUS = SoccerSceneConfig().ball_radius
"""Radius of the soccer ball, m."""


def op3_floor_scene(ball: bool = False) -> mujoco.MjModel:
    """Native MuJoCo model of one OP3 on a flat floor (the soccer scene's contact pairs and frictions),
    optionally with the soccer ball (free body `ball`, geom `ball`) 1 m ahead of the origin."""
    cfg = SoccerSceneConfig()
    spec = mujoco.MjSpec.from_file(str(OP3.mjcf_path))
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[20, 20, 0.05])
    floor = [cfg.floor_friction, cfg.floor_friction, 0.005, 1e-4, 1e-4]
    for g in OP3.feet_geoms + OP3.body_geoms:
        spec.add_pair(geomname1=g, geomname2="floor", condim=3, friction=floor)
    if ball:
        body = spec.worldbody.add_body(name="ball", pos=[1.0, 0.0, cfg.ball_radius])
        body.add_freejoint(name="ball")
        geom = body.add_geom(name="ball", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[cfg.ball_radius, 0, 0],
                             rgba=list(cfg.ball_rgba))
        geom.mass = cfg.ball_mass
        geom.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL
        r = cfg.ball_rolling_friction
        spec.add_pair(geomname1="ball", geomname2="floor", condim=6,
                      friction=[cfg.ball_friction, cfg.ball_friction, r, r, r])
        for g in cfg.ball_robot_geoms:
            spec.add_pair(geomname1="ball", geomname2=g, condim=3,
                          friction=[cfg.ball_friction, cfg.ball_friction, 0.005, 1e-4, 1e-4])
    return spec.compile()


class OP3Sim:
    """Native MuJoCo OP3 driven by servo targets, one control period (OP3_CTRL_DT) per `step`."""

    def __init__(self, ball: bool = False):
        self.model = op3_floor_scene(ball)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.jq = np.array([m.jnt_qposadr[m.joint(n).id] for n in OP3.joint_names])
        self.act = np.array([m.actuator(n).id for n in OP3.joint_names])
        self.nsub = round(OP3_CTRL_DT / m.opt.timestep)
        self.dt = self.nsub * m.opt.timestep
        self.t = 0.0
        self.fell_at: float | None = None
        """Sim time of the first `step` after which the robot was down (None: never)."""

    def place(self, q, settle: float = 1.0):
        """Put the robot at the origin in pose q, soles on the floor, and hold q for `settle` s."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[self.jq] = q
        d.qpos[2] = 0.3
        mujoco.mj_forward(m, d)
        d.qpos[2] -= min(d.site(s).xpos[2] for s in OP3.feet_sites) - 0.0005
        mujoco.mj_forward(m, d)
        self.hold(q, settle)
        self.t, self.fell_at = 0.0, None

    def hold(self, q, duration: float):
        """Physics steps for `duration` s with the servos at q (no clock, no fall check)."""
        self.data.ctrl[self.act] = q
        for _ in range(round(duration / self.model.opt.timestep)):
            mujoco.mj_step(self.model, self.data)

    def step(self, q):
        """One control period with servo targets q."""
        self.data.ctrl[self.act] = q
        for _ in range(self.nsub):
            mujoco.mj_step(self.model, self.data)
        self.t += self.dt
        if self.fell_at is None and self.fallen():
            self.fell_at = round(self.t, 3)

    def pose(self) -> tuple[np.ndarray, float, float, float]:
        """(root xy, yaw, root height, torso up-vector z)."""
        d = self.data
        w, x, y, z = d.qpos[3:7]
        up = d.body(OP3.root_body).xmat.reshape(3, 3)[2, 2]
        yaw = float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
        return d.qpos[:2].copy(), yaw, float(d.qpos[2]), float(up)

    def fallen(self) -> bool:
        """Root below 0.15 m or torso tilted more than 60 degrees."""
        _, _, h, up = self.pose()
        return h < 0.15 or up < 0.5


_targets_jit = jax.jit(gait_targets)
_filter_jit = jax.jit(filter_command)


class TableWalker:
    """Open-loop player of a gait table, one control period per `step` (what a JAX player does, in numpy):
    `stand` -> `start` -> gait with the command low-pass filtered (mode 'filter') or switched when the
    phase wraps (mode 'stride'); `stop()` zeroes the command and plays `stop` from the first
    `stop_phase` at which the filtered command is below `stop_tolerance` of the grid's extent (the stop
    sequence was recorded at zero command)."""

    stop_tolerance = 0.15

    def __init__(self, table: GaitTable, mode: str = "filter", tau=None):
        self.table, self.mode = GaitTable(*(jnp.asarray(a) for a in table)), mode
        self.tau = float(table.command_tau if tau is None else tau)
        self.dt = float(table.ctrl_dt)
        self.reset()

    def reset(self) -> np.ndarray:
        """Back to standing (before `start`); returns the standing pose."""
        self.state, self.index, self.phase = "start", 0, float(self.table.start_phase)
        self.command = np.zeros(3)
        self.request = np.zeros(3)
        self.stopping = False
        return np.asarray(self.table.stand)

    def step(self, command=None) -> np.ndarray:
        """Targets for the next control period (the first call returns start[1])."""
        t = self.table
        if command is not None:
            self.request = np.clip(np.asarray(command, float), np.asarray(t.command_low), np.asarray(t.command_high))
        if self.state == "start":
            self.index += 1
            if self.index < len(t.start):
                return np.asarray(t.start[self.index])
            self.state = "walk"
        if self.state == "stop":
            self.index += 1
            return np.asarray(t.stop[min(self.index, len(t.stop) - 1)])
        if self.index >= len(t.start):  # first gait sample: phase start_phase, nothing to advance
            self.index = -1
        else:
            old = self.phase
            self.phase = float(advance_phase(self.phase, self.dt, t))
            if self.mode == "stride" and self.phase < old:  # wrapped: switch at the stride boundary
                self.command = self.request.copy()
            settled = np.max(np.abs(self.command) / np.asarray(t.command_high)) < self.stop_tolerance
            crossed = (self.phase - float(t.stop_phase)) % 1.0 < self.dt / float(t.period) - 1e-6
            if self.stopping and settled and crossed:
                self.state, self.index = "stop", 0
                return np.asarray(t.stop[0])
        if self.mode == "filter":
            self.command = np.asarray(_filter_jit(self.command, self.request, self.dt, t, self.tau))
        if self.stopping:
            self.request = np.zeros(3)
        return np.asarray(_targets_jit(t, self.phase, self.command))

    def stop(self):
        """Zero the command and stop (standing) as soon as the gait allows."""
        self.stopping = True
        self.request = np.zeros(3)

    def done_stopping(self) -> bool:
        """Whether the stop sequence has been played to its end (the robot stands)."""
        return self.state == "stop" and self.index >= len(self.table.stop) - 1


def random_commands(table: GaitTable, duration=20.0, change_every=2.0, seed=0) -> list[tuple[float, tuple]]:
    """Piecewise-constant commands drawn uniformly in the grid's box: [(start time, command), ...]."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(table.command_low, float), np.asarray(table.command_high, float)
    return [(k * change_every, tuple(rng.uniform(lo, hi))) for k in range(int(np.ceil(duration / change_every)))]


def _command_at(schedule, t):
    return [c for t0, c in schedule if t0 <= t + 1e-9][-1]


def _body_velocity(poses, dt):
    """Mean (forward, lateral, yaw rate) in the heading frame from a list of (xy, yaw) samples."""
    xy = np.array([p[0] for p in poses])
    yaw = np.unwrap([p[1] for p in poses])
    d = np.diff(xy, axis=0)
    h = (yaw[1:] + yaw[:-1]) / 2
    fwd = np.cos(h) * d[:, 0] + np.sin(h) * d[:, 1]
    lat = -np.sin(h) * d[:, 0] + np.cos(h) * d[:, 1]
    return fwd.mean() / dt, lat.mean() / dt, (yaw[-1] - yaw[0]) / (dt * (len(yaw) - 1))


def _rounded(values, digits=4) -> tuple:
    return tuple(round(float(v), digits) for v in values)


def walk_table_in_mujoco(table: GaitTable, commands, duration=8.0, measure_last=4.0, mode="filter",
                         tau=None) -> list[dict]:
    """For each command: stand 1 s, start, walk `duration` s with the table (open loop, native MuJoCo);
    speed over the last `measure_last` s (heading frame), root displacement and when the robot fell."""
    sim, out = OP3Sim(), []
    for cmd in commands:
        walker = TableWalker(table, mode, tau)
        sim.place(walker.reset())
        xy0 = sim.pose()[0]
        n = len(table.start) - 1 + round(duration / walker.dt)
        poses = []
        for k in range(n):
            sim.step(walker.step(cmd))
            if k >= n - round(measure_last / walker.dt) - 1:
                poses.append(sim.pose()[:2])
        out.append({"command": tuple(float(c) for c in cmd), "speed": _rounded(_body_velocity(poses, walker.dt)),
                    "planned": _rounded(np.asarray(planned_speed(table, cmd))),
                    "displacement": _rounded(sim.pose()[0] - xy0), "fell": sim.fell_at})
    return out


def _play(sequence) -> dict:
    """Stand at sequence[0] for 1 s, then play the rest in native MuJoCo: falls, distance, final pose."""
    sim = OP3Sim()
    sim.place(sequence[0])
    xy0 = sim.pose()[0]
    for q in sequence[1:]:
        sim.step(q)
    xy1, yaw1 = sim.pose()[:2]
    return {"fell": sim.fell_at, "distance": round(float(np.linalg.norm(xy1 - xy0)), 3),
            "final_xy_yaw": (*_rounded(xy1, 3), round(yaw1, 3))}


def compare_table_to_solver(table: GaitTable | None = None, duration=20.0, change_every=2.0, seed=0, mode="filter",
                            tau=None, simulate=True, grid_speeds=True, config=None) -> dict:
    """Table vs live `PlacoWalk` (needs placo) on a random piecewise-constant command sequence.

    Both start standing; the live walk gets the command every control period; the table plays `start`
    then the gait at phase (t - t_first_swing) / period, its command low-pass filtered (mode 'filter',
    time constant `tau`) or switched when the phase wraps (mode 'stride'). Returns the RMS / max
    difference of the servo targets (rad; whole run, and leg joints), and with `simulate` the same
    sequence walked open loop in native MuJoCo by both (distance, falls); with `grid_speeds` the speed
    the table achieves in MuJoCo for every grid command."""
    from legged.soccer.placo.walk import PlacoWalk, PlacoWalkConfig  # placo, the solver, loads for this comparison only

    table = table if table is not None else load_gait_table(xp=np)
    walk = PlacoWalk(config or PlacoWalkConfig())
    dt = walk.config.ctrl_dt
    schedule = random_commands(table, duration, change_every, seed)
    walker = TableWalker(table, mode, tau)
    live, tab = [walk.reset((0.0, 0.0, 0.0))], [walker.reset()]
    for k in range(1, round(duration / dt)):
        cmd = _command_at(schedule, (k - 1) * dt)
        live.append(walk.step(cmd))
        tab.append(walker.step(cmd))
    live, tab = np.array(live), np.array(tab)
    diff = tab - live
    legs = slice(8, 20)
    after = round(3.0 / dt)
    result = {
        "mode": mode, "tau": walker.tau, "duration": duration, "change_every": change_every, "seed": seed,
        "schedule": [(t, _rounded(cmd)) for t, cmd in schedule],
        "rms": float(np.sqrt((diff**2).mean())), "max": float(np.abs(diff).max()),
        "rms_legs": float(np.sqrt((diff[:, legs] ** 2).mean())),
        "rms_per_joint": {nm: round(float(v), 4) for nm, v in zip(OP3.joint_names, np.sqrt((diff**2).mean(0)))},
        "rms_after_3s": float(np.sqrt((diff[after:] ** 2).mean())),
        "p99_abs": float(np.percentile(np.abs(diff[:, legs]), 99)),
        "max_step_change_table": float(np.abs(np.diff(tab, axis=0)).max()),
        "max_step_change_live": float(np.abs(np.diff(live, axis=0)).max()),
    }
    if simulate:
        result["sim_live"], result["sim_table"] = _play(live), _play(tab)
    if grid_speeds:
        commands = [(float(a), float(b), float(c)) for a in np.asarray(table.vx) for b in np.asarray(table.vy)
                    for c in np.asarray(table.yaw_rate)]
        result["grid_speeds"] = walk_table_in_mujoco(table, commands, mode=mode, tau=tau)
    return result


def kick_ball_in_mujoco(table: KickTable, side: int = 0, ball_shift=(0.0, 0.0), after=2.0) -> dict:
    """Open-loop kick in native MuJoCo: stand 1 s with the ball at `table.ball[side]` (+ `ball_shift`),
    play the kick, hold `stand` for `after` s. Ball speed just after the kick, where it went, falls."""
    sim = OP3Sim(ball=True)
    m, d = sim.model, sim.data
    stand = np.asarray(table.stand, dtype=float)
    sim.place(stand, settle=0.0)
    ball_q = m.jnt_qposadr[m.joint("ball").id]
    ball_v = m.jnt_dofadr[m.joint("ball").id]
    # Robot frame: midway between the soles, x forward (normal to the line from the right sole to the left).
    xy_l, xy_r = d.site(OP3.feet_sites[0]).xpos[:2], d.site(OP3.feet_sites[1]).xpos[:2]
    centre = (xy_l + xy_r) / 2
    fwd = np.array([xy_l[1] - xy_r[1], -(xy_l[0] - xy_r[0])])
    fwd /= np.linalg.norm(fwd)
    left = np.array([-fwd[1], fwd[0]])
    # Put the ball in place before settling (it rests on the floor in front of the foot).
    b = np.asarray(table.ball[side], dtype=float) + np.asarray(ball_shift)
    d.qpos[ball_q:ball_q + 3] = [*(centre + b[0] * fwd + b[1] * left), BALL_RADIUS]
    mujoco.mj_forward(m, d)
    sim.hold(stand, 1.0)
    start_ball = d.qpos[ball_q:ball_q + 2].copy()
    seq = np.asarray(table.targets[side], dtype=float)
    n = len(seq)
    speeds, touch = [], None
    for k in range(n + round(after / sim.dt)):
        sim.step(seq[min(k, n - 1)])
        speeds.append(float(np.linalg.norm(d.qvel[ball_v:ball_v + 2])))
        if touch is None and speeds[-1] > 0.05:
            touch = k
    later = touch + round(0.2 / sim.dt) if touch is not None else None
    moved = d.qpos[ball_q:ball_q + 2] - start_ball
    return {"side": SIDES[side], "ball_speed_max": round(max(speeds), 3),
            "ball_speed_after_0.2s": round(speeds[later], 3) if later is not None and later < len(speeds) else None,
            "contact_phase": round(touch / (n - 1), 3) if touch is not None else None,
            "ball_travel": round(float(np.linalg.norm(moved)), 3),
            "ball_forward": round(float(moved @ fwd), 3),
            "ball_direction_deg": round(float(np.degrees(np.arctan2(moved @ left, moved @ fwd))), 1),
            "fell": sim.fell_at}


def walk_kick_walk_in_mujoco(gait: GaitTable | None = None, kick: KickTable | None = None, side=0,
                             walk_command=(0.1, 0.0, 0.0), walk_seconds=4.0) -> dict:
    """Open-loop chain in native MuJoCo (no ball): walk, stop, kick, start, walk. Falls?"""
    gait = gait if gait is not None else load_gait_table(xp=np)
    kick = kick if kick is not None else load_kick_table(xp=np)
    sim, walker = OP3Sim(), TableWalker(gait)
    sim.place(walker.reset())
    for _ in range(round(walk_seconds / sim.dt)):
        sim.step(walker.step(walk_command))
    walker.stop()
    steps = 0
    while not walker.done_stopping():
        sim.step(walker.step())
        steps += 1
    jump = float(np.abs(np.asarray(kick.targets[side, 0]) - np.asarray(gait.stop[-1])).max())
    for q in np.asarray(kick.targets[side]):
        sim.step(q)
    walker.reset()
    for _ in range(round(walk_seconds / sim.dt)):
        sim.step(walker.step(walk_command))
    return {"fell": sim.fell_at, "stop_seconds": round(steps * sim.dt, 3), "stop_to_kick_jump": jump,
            "final_xy": _rounded(sim.pose()[0], 3)}
