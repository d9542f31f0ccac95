"""Body-pose path planning with OMPL through a confined space.

State space: the body pose as a 6-D real vector (x, y, h, roll, pitch, yaw), a reduction of SE(3):
- h is the body centre's height above the floor beneath it (z = floor(x, y) + h). The legs keep the
  body within a band about 0.1 m thick above the floor, so sampling z freely would waste nearly every
  sample; sampling h within the leg-reach band loses no reachable pose.
- roll and pitch are bounded well inside +-90 degrees, where z-y-x Euler angles are a singularity-free
  chart of SO(3); yaw spans the start-to-goal heading +-pi, so no angle ever wraps.
Angles are scaled by `angle_weight` (metres per radian) so that path length, and hence what optimal
planners minimise, counts a turn as well as a shift. Validity is `BodyChecker` (body box against
floor and ceiling with roll and pitch, and leg reach).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from legged.robots import GO1
from legged.robots.spec import RobotSpec
from planners.body_check import BodyCheckConfig, BodyChecker
from planners.box_space import BoxSpace
from planners.headings import face_travel
from planners.lattice import lattice_path, shortcut
from planners.pose_band import ProjectedSpace
from legged.worlds.maps import HeightMaps

ou.setLogLevel(ou.LOG_ERROR)

PLANNERS = {
    "rrtconnect": og.RRTConnect,
    "rrt": og.RRT,
    "rrtstar": og.RRTstar,
    "informedrrtstar": og.InformedRRTstar,
    "bitstar": og.BITstar,
    "aorrtc": og.AORRTC,
    "prmstar": og.PRMstar,
}
"""OMPL planners by name; all but rrtconnect and rrt are asymptotically optimal and use the whole time limit."""


class PlanningError(ValueError):
    """No plan: the start or goal is invalid or off the map, or no path was found in time. Says which."""


LATTICE, AUTO = "lattice", "auto"
"""Not OMPL: the complete (x, y, yaw) grid search of planners.lattice (narrow corridors), and the default:
RRTConnect for `PlannerConfig.quick_checks` motion checks, then the lattice search."""


def planner_key(name: str) -> str:
    """Canonical planner name: 'RRT*' -> 'rrtstar', 'BIT*' -> 'bitstar', 'RRTConnect' -> 'rrtconnect'."""
    key = name.lower().replace("*", "star").replace("-", "").replace("_", "").replace(" ", "")
    if key not in PLANNERS and key not in (LATTICE, AUTO):
        raise PlanningError(f"unknown planner {name!r}; choose one of {', '.join([AUTO, LATTICE, *PLANNERS])}")
    return key


@dataclasses.dataclass(frozen=True)
class PlannerConfig:
    """Settings of one planning query."""

    planner: str = "auto"
    """auto (RRTConnect briefly, then the lattice search), lattice, or an OMPL planner (see PLANNERS; 'RRT*',
    'BIT*', 'AORRTC' style names are accepted)."""
    time_limit: float = 5.0
    """Seconds an OMPL planner may search (optimal planners use all of it; the lattice search is complete)."""
    quick_checks: int = 60
    """auto: motion checks RRTConnect may spend before the lattice search takes over (a count, not seconds, so
    that the same query takes the same route on every machine)."""
    max_checks: int = 0
    """OMPL planners: stop after this many motion checks, or at the time limit if sooner (0: the time limit
    alone). A count makes an optimal planner's search the same on a slow or busy machine as on a fast one."""
    seed: int = 0
    """Seed of OMPL's random sampling; the same seed gives the same path (for planners that stop early)."""
    simplify: bool = True
    """Shortcut and smooth the raw path (OMPL's PathSimplifier, bounded and deterministic)."""
    spacing: float = 0.5
    """Largest distance between consecutive waypoints, metres (in position and in the scaled state space)."""
    max_roll: float = math.radians(15.0)
    """Largest body roll a waypoint may ask for, radians."""
    max_pitch: float = math.radians(15.0)
    """Largest body pitch a waypoint may ask for, radians."""
    angle_weight: float = 0.3
    """Metres of path length one radian of rotation counts as."""
    max_step: float = 0.2
    """Longest edge a tree planner adds in one extension (OMPL's `range`), state-space metres."""
    check_step: float = 0.02
    """Largest state-space step between collision checks along a motion, metres."""
    body: BodyCheckConfig = BodyCheckConfig()
    """Body-box margin and leg-reach check."""
    crouch_speed: float | None = None
    """Speed limit at waypoints where the body must crouch (where the ceiling, less the body-box margin, leaves its
    centre less than the robot's standing height above the floor: under a bar or a low roof), m/s; the plan's
    `speeds` hand it to the follower (None: no limit of the plan's own)."""
    turn_accel: float | None = None
    """Largest sideways acceleration the plan asks of the body in its turns, m/s^2: where the path turns with curvature
    k (a waypoint's turn angle over the mean length of the segments beside it), the speed limit there and at the next
    waypoint is sqrt(turn_accel / k); the plan's `speeds` hand it to the follower (None: no limit of the plan's
    own)."""
    face_travel: bool | None = None
    """True: turn each waypoint after the start to the direction the path travels around it (over `travel_window`),
    where the body fits that way (planners.headings); False: the search's headings, which turn the body as little as
    they can; None: as False, unless navigation sets a follower's own choice (planners.follower_planner)."""
    travel_window: float = 1.5
    """With `face_travel`, the length of path (m) whose direction a waypoint faces, centred on it: a few body lengths,
    so a turn is faced gradually and a short sidestep is walked sideways (planners.headings.travel_headings)."""
    space: str = "projected"
    """projected: search x, y, yaw, with height, roll and pitch put in the middle of the feasible band
    (planners.pose_band; narrow height bands cost nothing); full: sample all six (the earlier planner)."""

    def validate(self) -> None:
        """Raise PlanningError on values that cannot work."""
        planner_key(self.planner)
        if self.space not in ("projected", "full"):
            raise PlanningError(f"space must be 'projected' or 'full', got {self.space!r}")
        for name in ("time_limit", "quick_checks", "spacing", "angle_weight", "max_step", "check_step",
                     "travel_window"):
            if getattr(self, name) <= 0:
                raise PlanningError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.crouch_speed is not None and not 0 < self.crouch_speed < math.inf:
            raise PlanningError(f"crouch_speed must be a positive speed in m/s, got {self.crouch_speed}")
        if self.turn_accel is not None and not 0 < self.turn_accel < math.inf:
            raise PlanningError(f"turn_accel must be a positive acceleration in m/s^2, got {self.turn_accel}")
        if self.max_checks < 0:
            raise PlanningError(f"max_checks must be >= 0 (0: the time limit alone), got {self.max_checks}")
        if not (0 <= self.max_roll < math.pi / 2 and 0 <= self.max_pitch < math.pi / 2):
            raise PlanningError("max_roll and max_pitch must lie in [0, pi/2)")


@dataclasses.dataclass(frozen=True)
class Plan:
    """A planned path of body poses."""

    waypoints: np.ndarray
    """(n, 6) body poses x, y, z, roll, pitch, yaw (body centre, world frame, radians); start and goal included."""
    length_m: float
    """Length of the body-centre path, metres."""
    plan_time_s: float
    """Time the planner searched (simplification excluded), seconds."""
    planner: str
    """Canonical name of the planner used."""
    speeds: np.ndarray | None = None
    """Speed limit per waypoint, m/s (NaN: none of the plan's own), or None (`PlannerConfig.crouch_speed` and
    `turn_accel` unset)."""

    def to_json(self) -> dict:
        """The plan as a JSON-friendly dict (waypoints rounded to 0.1 mm / 0.1 mrad)."""
        out = {"waypoints": np.round(self.waypoints, 4).tolist(), "length_m": round(self.length_m, 4),
               "plan_time_s": round(self.plan_time_s, 4), "planner": self.planner}
        if self.speeds is not None:  # JSON has no NaN: null where the plan sets no limit
            out["speeds"] = [None if np.isnan(v) else round(float(v), 4) for v in self.speeds]
        return out


def as_pose(point, yaw: float) -> np.ndarray:
    """A 6-D pose from a pose, or from a position x, y, z (then level, heading `yaw`)."""
    point = np.asarray(point, float)
    if point.shape == (6,):
        return point
    if point.shape != (3,):
        raise PlanningError(f"expected x, y, z or a 6-D pose, got shape {point.shape}")
    return np.array([*point, 0.0, 0.0, yaw])


def path_length(waypoints: np.ndarray) -> float:
    """Length of the body-centre polyline, metres."""
    return float(np.linalg.norm(np.diff(waypoints[:, :3], axis=0), axis=1).sum())


class _Space(BoxSpace):
    """Conversions between poses and the scaled (x, y, h, roll, pitch, yaw) OMPL state, plus the space."""

    def __init__(self, maps: HeightMaps, robot: RobotSpec, config: PlannerConfig, heading: float,
                 checker: BodyChecker):
        self.maps, self.heading, self.w, self.checker = maps, heading, config.angle_weight, checker
        lo_h, hi_h = robot.body_height_range
        super().__init__([maps.origin[0], maps.origin[1], lo_h - 0.05,
                          -self.w * config.max_roll, -self.w * config.max_pitch, -self.w * math.pi],
                         [maps.upper[0], maps.upper[1], hi_h + 0.05,
                          self.w * config.max_roll, self.w * config.max_pitch, self.w * math.pi])

    def to_poses(self, vectors: np.ndarray) -> np.ndarray:
        """Scaled states (n, 6) -> poses (n, 6)."""
        v = np.atleast_2d(vectors)
        yaw = (v[:, 5] / self.w + self.heading + math.pi) % (2 * math.pi) - math.pi
        z = v[:, 2] + self.maps.lookup(v[:, :2])
        return np.stack([v[:, 0], v[:, 1], z, v[:, 3] / self.w, v[:, 4] / self.w, yaw], 1)

    def valid(self, vectors: np.ndarray) -> np.ndarray:
        """Whether each state's pose passes the body check."""
        return self.checker.valid(self.to_poses(vectors))

    def to_vector(self, pose) -> np.ndarray:
        """One pose (6,) -> scaled state (6,)."""
        rel_yaw = (pose[5] - self.heading + math.pi) % (2 * math.pi) - math.pi
        h = pose[2] - float(self.maps.lookup(np.asarray(pose[None, :2], float))[0])
        return np.array([pose[0], pose[1], h, self.w * pose[3], self.w * pose[4], self.w * rel_yaw])


def _values(state, dim: int) -> np.ndarray:
    return np.array([state[k] for k in range(dim)])


class _BatchMotionValidator(ob.MotionValidator):
    """Checks all states along a motion in one vectorised call (OMPL's default checks one at a time)."""

    def __init__(self, info, space, step: float):
        super().__init__(info)
        self.space, self.step, self.calls = space, step, 0

    def checkMotion(self, a, b, *unused) -> bool:  # noqa: N802 (OMPL's name)
        self.calls += 1
        return self.checkMotion_values(_values(a, self.space.dim), _values(b, self.space.dim))

    def checkMotion_values(self, va: np.ndarray, vb: np.ndarray) -> bool:  # noqa: N802
        """The straight motion between two state vectors is valid (its start is assumed valid)."""
        n = max(int(math.ceil(np.linalg.norm(vb - va) / self.step)), 1)
        states = va + np.linspace(0.0, 1.0, n + 1)[1:, None] * (vb - va)  # a is valid by OMPL's convention
        return bool(self.space.valid(states).all())


def _seed_ompl(seed: int) -> None:
    """Seed OMPL's global generator (it complains when reseeded in one process, but obeys)."""
    ou.noOutputHandler()
    try:
        ou.RNG.setSeed(int(seed) % (2**31 - 2) + 1)
    finally:
        ou.restorePreviousOutputHandler()


def _check_endpoint(name: str, pose: np.ndarray, checker: BodyChecker, space: _Space, config: PlannerConfig):
    if not checker.maps.contains(pose[:2]):
        raise PlanningError(f"the {name} ({pose[0]:.3f}, {pose[1]:.3f}) lies outside the map "
                            f"({checker.maps.describe_bounds()})")
    if abs(pose[3]) > config.max_roll + 1e-9 or abs(pose[4]) > config.max_pitch + 1e-9:
        raise PlanningError(f"the {name} pose has roll/pitch ({pose[3]:.3f}, {pose[4]:.3f}) beyond the limits "
                            f"({config.max_roll:.3f}, {config.max_pitch:.3f}) rad")
    reason = checker.violation(pose)
    if reason:
        raise PlanningError(f"the {name} pose {np.round(pose, 3).tolist()} is in collision or unreachable: {reason}")
    state = space.to_vector(pose)
    if np.any(state < space.low - 1e-9) or np.any(state > space.high + 1e-9):
        raise PlanningError(f"the {name} pose {np.round(pose, 3).tolist()} lies outside the planning bounds "
                            f"{np.round(space.low, 3).tolist()}..{np.round(space.high, 3).tolist()} (x, y, h, angles)")
    if not space.valid(state)[0]:
        raise PlanningError(f"the {name} pose {np.round(pose, 3).tolist()} is valid, but no level or floor-parallel "
                            "body fits at its x, y and heading (plan with --space full to keep its own tilt)")


def _subdivide(vertices: np.ndarray, spacing: float, space, check_step: float) -> np.ndarray:
    """Poses along a state-space polyline: every segment split so that consecutive poses are at most `spacing` apart,
    both in state space and in body-centre position. The split points are states the motion check visited (every
    `check_step`), so each has a feasible pose even where the free band is narrower than the step between checks."""
    out = [space.to_poses(vertices[:1])]
    for a, b in zip(vertices[:-1], vertices[1:]):
        checked = max(int(math.ceil(np.linalg.norm(b - a) / check_step)), 1)  # as the motion validators sample
        n = min(max(int(math.ceil(np.linalg.norm(b - a) / spacing - 1e-9)), 1), checked)
        while True:  # z follows the floor, so positions can be farther apart than states
            t = np.rint(np.linspace(0.0, checked, n + 1)) / checked
            poses = space.to_poses(a + t[:, None] * (b - a))
            if np.isnan(poses).any():
                raise PlanningError("internal: a waypoint between validated states has no feasible body pose")
            if n >= checked or np.linalg.norm(np.diff(poses[:, :3], axis=0), axis=1).max() <= spacing + 1e-9:
                break
            n += 1
        out.append(poses[1:])
    return np.concatenate(out)


def plan_path(maps: HeightMaps, start, goal, robot: RobotSpec = GO1, config: PlannerConfig = PlannerConfig(),
              checker: BodyChecker | None = None) -> Plan:
    """Plan body-pose waypoints from start to goal (each x, y, z or a full 6-D pose); raise PlanningError."""
    config.validate()
    checker = checker or BodyChecker(maps, robot, config.body)
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    heading = math.atan2(goal[1] - start[1], goal[0] - start[0])
    start_pose, goal_pose = as_pose(start, heading), as_pose(goal, heading)
    name = planner_key(config.planner)
    if name in (LATTICE, AUTO) and config.space != "projected":
        raise PlanningError(f"the {name} planner searches the projected space: use space='projected'")
    if config.space == "projected":
        space = ProjectedSpace(checker.maps, checker, config, heading)
    else:
        space = _Space(checker.maps, robot, config, heading, checker)
    _check_endpoint("start", start_pose, checker, space, config)
    _check_endpoint("goal", goal_pose, checker, space, config)

    if name == LATTICE:
        plan = _lattice_plan(space, checker, start_pose, goal_pose, config)
    elif name == AUTO:
        began = time.perf_counter()
        try:
            quick = dataclasses.replace(config, planner="rrtconnect")
            plan = _ompl_plan(space, checker, start_pose, goal_pose, quick, max_checks=config.quick_checks)
        except PlanningError:
            plan = _lattice_plan(space, checker, start_pose, goal_pose, config)
            plan = dataclasses.replace(plan, plan_time_s=time.perf_counter() - began)
    else:
        plan = _ompl_plan(space, checker, start_pose, goal_pose, config, max_checks=config.max_checks)
    if not config.face_travel:
        return plan
    keep_goal = goal.shape == (6,)  # a full goal pose keeps its heading; a goal position takes the path's
    waypoints = face_travel(plan.waypoints, space, checker, config.check_step, keep_goal, config.travel_window)
    return dataclasses.replace(plan, waypoints=waypoints, speeds=_plan_speeds(waypoints, checker, config))


def _ompl_plan(space, checker, start_pose, goal_pose, config: PlannerConfig, max_checks: int = 0) -> Plan:
    """Plan with the OMPL planner of `config` (stopping after `max_checks` motion checks if > 0)."""
    name = planner_key(config.planner)
    _seed_ompl(config.seed)
    setup = og.SimpleSetup(space.space)
    setup.setStateValidityChecker(lambda s: bool(space.valid(_values(s, space.dim))[0]))
    info = setup.getSpaceInformation()
    motions = _BatchMotionValidator(info, space, config.check_step)
    info.setMotionValidator(motions)
    setup.setStartAndGoalStates(space.state(start_pose), space.state(goal_pose))
    setup.setOptimizationObjective(ob.PathLengthOptimizationObjective(info))
    planner = PLANNERS[name](info)
    if hasattr(planner, "setRange"):
        planner.setRange(config.max_step)
    setup.setPlanner(planner)
    if max_checks > 0:
        setup.solve(ob.plannerOrTerminationCondition(
            ob.timedPlannerTerminationCondition(config.time_limit),
            ob.PlannerTerminationCondition(lambda: motions.calls >= max_checks)))
    else:
        setup.solve(config.time_limit)
    plan_time = setup.getLastPlanComputationTime()
    if not setup.haveExactSolutionPath():
        limit = f"{config.time_limit} s" + (f" or {max_checks} motion checks" if max_checks > 0 else "")
        raise PlanningError(
            f"no collision-free path from start {np.round(start_pose[:3], 3).tolist()} to goal "
            f"{np.round(goal_pose[:3], 3).tolist()} found by {name} within {limit} "
            f"(the space may be blocked; a longer time limit helps only if it is not){_walls_note(checker)}")
    if config.simplify and space.dim == 6:
        setup.simplifySolution(0.0)  # 0 = OMPL's bounded simplifyMax: deterministic
    path = setup.getSolutionPath()
    vertices = np.array([_values(path.getState(i), space.dim) for i in range(path.getStateCount())])
    if config.simplify and space.dim != 6:  # greedy shortcuts: far fewer (costlier) checks than OMPL's smoothing
        exact = lambda a, b: bool(motions.checkMotion_values(a, b))
        vertices = shortcut(vertices, exact, exact)
    return _finish(vertices, space, checker, start_pose, goal_pose, config, plan_time, name)


def _walls_note(checker: BodyChecker) -> str:
    """What a failure message adds when the planner's maps hold walls the world does not (`step_walls`)."""
    if not checker.walled_cells:
        return ""
    c = checker.config
    return (f"; {checker.walled_cells} cells at floor edges over {c.step_height:.2f} m (steps, the rims of gaps "
            f"wider than {2 * c.stride_slack:.2f} m) are walls to the planner")


def _lattice_plan(space, checker, start_pose, goal_pose, config: PlannerConfig) -> Plan:
    began = time.perf_counter()
    vertices = lattice_path(space, checker, start_pose, goal_pose, config.check_step, config.angle_weight)
    if vertices is None:
        raise PlanningError(
            f"no collision-free path from start {np.round(start_pose[:3], 3).tolist()} to goal "
            f"{np.round(goal_pose[:3], 3).tolist()}: the lattice search (every cell and heading) found none, so "
            f"the body does not fit through (at the map's resolution){_walls_note(checker)}")
    return _finish(vertices, space, checker, start_pose, goal_pose, config, time.perf_counter() - began, "lattice")


def _finish(vertices, space, checker, start_pose, goal_pose, config: PlannerConfig, plan_time: float,
            name: str) -> Plan:
    """The Plan of a solved state-space polyline: subdivided into waypoints and checked once more."""
    vertices[0], vertices[-1] = space.to_vector(start_pose), space.to_vector(goal_pose)
    waypoints = _subdivide(vertices, config.spacing, space, config.check_step)
    waypoints[0], waypoints[-1] = start_pose, goal_pose  # exactly as asked (a projected space re-centres them)
    bad = np.flatnonzero(~checker.valid(waypoints))
    if bad.size:  # cannot happen if every motion was validated; refuse rather than hand out a colliding path
        raise PlanningError(f"internal: waypoints {bad.tolist()} of the planned path fail the body check")
    return Plan(waypoints=waypoints, length_m=path_length(waypoints), plan_time_s=float(plan_time), planner=name,
                speeds=_plan_speeds(waypoints, checker, config))


def turn_speeds(waypoints: np.ndarray, accel: float) -> np.ndarray:
    """Speed limit per waypoint of a path (n, >= 2) from its turns, m/s (inf where it runs straight): at waypoint i,
    where the horizontal path turns by angle a between segments of mean length l, the curvature a / l allows
    sqrt(accel * l / a); the limit holds at i and at i + 1 (the body turns as it leaves i)."""
    xy = np.asarray(waypoints, float)[:, :2]
    limits = np.full(len(xy), np.inf)
    if len(xy) < 3:
        return limits
    a, b = xy[1:-1] - xy[:-2], xy[2:] - xy[1:-1]
    angle = np.abs(np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], np.sum(a * b, axis=1)))
    length = 0.5 * (np.linalg.norm(a, axis=1) + np.linalg.norm(b, axis=1))
    turning = angle > 1e-3  # a thousandth of a radian: straight (simplified paths keep such kinks)
    limits[1:-1][turning] = np.sqrt(accel * length[turning] / angle[turning])
    limits[2:] = np.minimum(limits[2:], limits[1:-1])
    return limits


def _plan_speeds(waypoints: np.ndarray, checker, config: PlannerConfig) -> np.ndarray | None:
    """The plan's own speed limit per waypoint (NaN: none): `crouch_speed` where the body must crouch, the turns'
    limits of `turn_accel`, the lower where both apply; None when the config sets neither."""
    if config.crouch_speed is None and config.turn_accel is None:
        return None
    limits = np.full(len(waypoints), np.inf)
    if config.crouch_speed is not None:
        crouched = checker.headroom(waypoints) < checker.robot.standing_height  # a standing body would not fit
        limits = np.where(crouched, config.crouch_speed, limits)
    if config.turn_accel is not None:
        limits = np.minimum(limits, turn_speeds(waypoints, config.turn_accel))
    return np.where(np.isfinite(limits), limits, np.nan)


def nearest_valid_pose(checker: BodyChecker, pose, config: PlannerConfig, search_radius: float = 0.1) -> np.ndarray:
    """The valid pose closest to a measured one: roll/pitch clipped to the limits (or levelled), the body
    moved within `search_radius` horizontally and anywhere within leg reach vertically."""
    pose = np.asarray(pose, float).copy()
    pose[3] = np.clip(pose[3], -config.max_roll, config.max_roll)
    pose[4] = np.clip(pose[4], -config.max_pitch, config.max_pitch)
    if checker.is_valid(pose):
        return pose
    shifts = np.arange(-search_radius, search_radius + 1e-9, checker.maps.resolution)
    lo, hi = checker.height_range
    floor = float(checker.maps.floor_at(pose[:2]))
    dx, dy, z, tilt = np.meshgrid(shifts, shifts, floor + np.linspace(lo, hi, 11), [1.0, 0.0], indexing="ij")
    candidates = np.stack([pose[0] + dx, pose[1] + dy, z, pose[3] * tilt, pose[4] * tilt,
                           np.full_like(z, pose[5])], -1).reshape(-1, 6)
    valid = candidates[checker.valid(candidates)]
    if not len(valid):
        raise PlanningError(f"no valid body pose within {search_radius} m of the current position "
                            f"{np.round(pose[:3], 3).tolist()}: {checker.violation(pose)}")
    turn = np.abs(valid[:, 3:5] - pose[3:5]).sum(1)
    cost = np.linalg.norm(valid[:, :3] - pose[:3], axis=1) + config.angle_weight * turn
    return valid[np.argmin(cost)]


def replan(maps: HeightMaps, pose, goal, robot: RobotSpec = GO1, config: PlannerConfig = PlannerConfig(),
           checker: BodyChecker | None = None) -> Plan:
    """Remaining waypoints from the robot's current pose to the goal (for evaluation between control ticks).

    A measured pose is rarely exactly plannable (the body sways, crouches, tilts), so the path starts at
    `nearest_valid_pose`. Raises PlanningError if there is none nearby or no path from it.
    """
    checker = checker or BodyChecker(maps, robot, config.body)
    return plan_path(maps, nearest_valid_pose(checker, pose, config), goal, robot, config, checker)
