"""Is a body pose valid? The robot's body box against the floor and ceiling maps, plus leg reach.

The box (half extents plus a margin) is sampled on all six faces at no more than half the map
resolution and rotated by the full roll, pitch and yaw: the lower samples must lie above the floor,
the upper ones below the ceiling. The legs must reach the floor: at each foot's nominal stance point
the body (tilt included) must stand within the robot's `body_height_range` above the floor there, or
at one of the foot's alternative points: a little inward (a narrower stance) or a stride fore or aft
(stepping over a gap in the floor). The legs must be clear of walls: the rectangle the feet span in the
default stance, grown by a margin, is checked at the height of the knees at the robot's lowest stance
(what the trunk's box does not cover: a side block beside the body can pass the box and still stand in
the legs' way). Poses are checked in batches (all states of a motion at once),
which is what makes planning in Python fast enough.

The planner's maps are more conservative than the world (`step_walls`): a floor edge higher than the robot
steps up or down is a wall to it, except the rims of gaps narrow enough to stride over. The robot itself
walks the unaltered world.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from scipy import ndimage

from legged.robots.spec import RobotSpec
from legged.worlds.maps import HeightMaps

VALID, OFF_MAP, OUT_OF_REACH, HITS_CEILING, HITS_FLOOR, LEGS_BLOCKED = range(6)
REASONS = {OFF_MAP: "the body leaves the map", OUT_OF_REACH: "the legs cannot hold the body there",
           HITS_CEILING: "the body hits the ceiling", HITS_FLOOR: "the body hits the floor",
           LEGS_BLOCKED: "the legs hit an obstacle beside the body"}


def rotation_rpy(roll, pitch, yaw) -> np.ndarray:
    """World-from-body rotation Rz(yaw) Ry(pitch) Rx(roll) (the environments' z-y-x convention).

    Scalars give (3, 3); arrays of shape (n,) give (n, 3, 3).
    """
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw))
    rows = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]
    return np.moveaxis(np.array(rows, dtype=float), (0, 1), (-2, -1))


def quat_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of `rotation_rpy`."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rotation_rpy(roll, pitch, yaw).ravel())
    return quat


def box_surface_points(half: np.ndarray, spacing: float) -> np.ndarray:
    """Points on the surface of a box centred at 0 (all six faces, edges and corners included)."""
    axes = [np.linspace(-h, h, max(int(np.ceil(2 * h / spacing)), 1) + 1) for h in half]
    points = []
    for k in range(3):  # the two faces normal to axis k
        a, b = [axes[i] for i in range(3) if i != k]
        grid = np.stack(np.meshgrid(a, b, indexing="ij"), -1).reshape(-1, 2)
        for sign in (-1.0, 1.0):
            points.append(np.insert(grid, k, sign * half[k], axis=1))
    return np.unique(np.concatenate(points), axis=0)


def stance_points(robot: RobotSpec) -> np.ndarray:
    """Feet x, y in the body frame at the robot's default pose (read from its MJCF)."""
    model = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    data = mujoco.MjData(model)
    for name, angle in zip(robot.joint_names, robot.default_pose):
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = angle
    mujoco.mj_kinematics(model, data)
    root = model.body(robot.root_body).id
    rot, pos = data.xmat[root].reshape(3, 3), data.xpos[root]
    feet = np.array([data.site(s).xpos for s in robot.feet_sites])
    return ((feet - pos) @ rot)[:, :2]


@dataclasses.dataclass(frozen=True)
class BodyCheckConfig:
    """How conservative the body-pose check is."""

    margin: float = 0.02
    """Added to every half extent of the body box, metres."""
    check_heights: bool = True
    """Require the body to stand within the robot's leg reach above the floor under every foot."""
    stance_slack: float = 0.05
    """A foot whose nominal stance point has no floor within reach may step up to this far inward (a narrower
    stance, toward the body's centre line), metres; 0 keeps the nominal stance."""
    stride_slack: float = 0.18
    """... or this far fore or aft, metres: a foot over a gap in the floor steps across it, so gaps up to about
    twice this wide are crossed and wider ones are not (0: the feet never step fore or aft)."""
    step_height: float | None = 0.10
    """A floor edge higher than this between two free columns is a wall to the planner (its lower side turns solid
    for one cell), except the rims of gaps up to 2 * stride_slack wide, which the feet stride over; metres (None:
    no such walls)."""
    leg_margin: float | None = 0.0
    """The legs' rectangle (the bounding rectangle of the feet's stance points, grown by this much on every side) must
    be clear of the floor at `leg_height` above the feet at the lowest stance, metres; at 0 the feet's centres, and
    the interpolated maps keep about a map cell more (None: the legs are not checked, only the trunk's box and the
    feet's reach)."""
    leg_height: float = 0.11
    """Height above the feet, at the robot's lowest stance, at which the legs' rectangle is checked, metres: above
    the steps the robot climbs (`step_height`), so only walls and side obstacles stand in its way."""


def leg_rectangle(stance: np.ndarray, robot: RobotSpec, config: BodyCheckConfig) -> tuple[float, ...]:
    """The legs' rectangle (x0, y0, x1, y1, z) in the body frame: the feet's `stance` points (n, 2) bounded and grown
    by `leg_margin`, at `leg_height` above the feet of the lowest stance."""
    lo, hi = stance.min(0) - config.leg_margin, stance.max(0) + config.leg_margin
    return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]), config.leg_height - robot.body_height_range[0])


def step_walls(maps: HeightMaps, step_height: float, gap: float) -> tuple[HeightMaps, int]:
    """(maps in which the lower side of every floor edge higher than `step_height` is solid, how many cells turned
    solid). Edges are looked for between free neighbours (walls are no steps) on the floor with its gaps up to
    `gap` wide filled (a grey-scale closing by a disc of that diameter fills pits narrower than the disc and leaves
    steps as they are), so the rims of gaps the feet can stride over stay open."""
    floor, ceiling, res = np.asarray(maps.floor, float), np.asarray(maps.ceiling, float), maps.resolution
    free = ceiling - floor > 1e-6
    radius = max(int(round(gap / 2 / res)), 0)
    offsets = np.arange(-radius, radius + 1)
    disc = np.hypot(*np.meshgrid(offsets, offsets, indexing="ij")) <= radius + 1e-9
    raised = ndimage.maximum_filter(np.where(free, floor, -np.inf), footprint=disc, mode="nearest")
    filled = ndimage.minimum_filter(np.where(free, raised, np.inf), footprint=disc, mode="nearest")
    filled = np.where(free, np.maximum(filled, floor), floor)
    solid = np.zeros_like(free)
    for axis in (0, 1):
        lo, hi = [slice(None)] * 2, [slice(None)] * 2
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        a, b = filled[tuple(lo)], filled[tuple(hi)]
        both = free[tuple(lo)] & free[tuple(hi)]
        solid[tuple(lo)] |= both & (b - a > step_height)  # a is the lower side
        solid[tuple(hi)] |= both & (a - b > step_height)
    count = int(solid.sum())
    if not count:
        return maps, 0
    walled = dataclasses.replace(maps, floor=np.where(solid, ceiling, floor).astype(maps.floor.dtype))
    return walled, count


def widest_band(low, high, starts, ends) -> tuple[np.ndarray, np.ndarray]:
    """The widest interval of heights z in [low, high] at which every foot f finds a choice c with starts[..., f, c]
    <= z <= ends[..., f, c] (the union of each foot's intervals, intersected over the feet), exactly: (z_low,
    z_high), with z_low > z_high where there is none. low, high (...,); starts, ends (..., feet, choices); an
    unavailable choice has start inf."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    starts, ends = np.asarray(starts, float), np.asarray(ends, float)
    lead = low.shape
    candidates = np.concatenate([low[..., None], starts.reshape(lead + (starts.shape[-2] * starts.shape[-1],))],
                                -1)  # (..., K); lead may be empty
    s, e = starts[..., None, :, :], ends[..., None, :, :]                                # (..., 1, F, C)
    z = candidates[..., :, None, None]                                                   # (..., K, 1, 1)
    inside = (s <= z + 1e-12) & (e >= z - 1e-12)
    reach = np.max(np.where(inside, e, -np.inf), axis=-1)                                # (..., K, F)
    for _ in range(starts.shape[-1] - 1):  # a foot's intervals may overlap: follow its union upward
        reach = np.maximum(reach, np.max(np.where(s <= reach[..., None] + 1e-12, e, -np.inf), axis=-1))
    top = np.minimum(high[..., None], np.min(reach, axis=-1))                           # (..., K)
    width = np.where(candidates >= low[..., None] - 1e-12, top - candidates, -np.inf)
    best = np.argmax(width, axis=-1)[..., None]
    z_low = np.take_along_axis(candidates, best, -1)[..., 0]
    z_high = np.take_along_axis(top, best, -1)[..., 0]
    none = ~np.isfinite(np.take_along_axis(width, best, -1)[..., 0])
    return np.where(none, np.inf, z_low), np.where(none, -np.inf, z_high)


class BodyChecker:
    """Validity of body poses (x, y, z, roll, pitch, yaw) in one pair of height maps (made conservative by
    `step_walls` where the config asks)."""

    def __init__(self, maps: HeightMaps, robot: RobotSpec, config: BodyCheckConfig = BodyCheckConfig()):
        self.robot, self.config, self.walled_cells = robot, config, 0
        if config.step_height is not None:
            maps, self.walled_cells = step_walls(maps, config.step_height, 2 * config.stride_slack)
        self.maps = maps
        self.half_extents = np.asarray(robot.body_box_half_extents, float) + config.margin
        faces = box_surface_points(self.half_extents, maps.resolution / 2)
        self.bottom_points = faces[faces[:, 2] < 0]  # bottom face and the lower half of the sides
        self.top_points = faces[faces[:, 2] > 0]
        stance = stance_points(robot)
        self.stance_points = np.concatenate([stance, np.zeros((len(stance), 1))], 1)
        inward = self.stance_points.copy()
        inward[:, 1] -= np.sign(stance[:, 1]) * np.minimum(config.stance_slack, np.abs(stance[:, 1]))
        fore, aft = self.stance_points.copy(), self.stance_points.copy()
        fore[:, 0] += config.stride_slack
        aft[:, 0] -= config.stride_slack
        self.stance_choices = np.stack([self.stance_points, inward, fore, aft])
        """(choices, feet, 3): where each foot may stand, in the body frame: nominal first, then inward, fore, aft."""
        self.height_range = robot.body_height_range
        self.leg_points, self.leg_rectangle = np.zeros((0, 3)), None
        """Points of the legs' rectangle in the body frame, and the rectangle as (x0, y0, x1, y1, z) (none when the
        config does not check the legs)."""
        if config.leg_margin is not None:
            self.leg_rectangle = leg_rectangle(stance, robot, config)
            x0, y0, x1, y1, depth = self.leg_rectangle  # a flat box: its faces fill the rectangle
            flat = box_surface_points(np.array([(x1 - x0) / 2, (y1 - y0) / 2, 0.0]), maps.resolution / 2)
            self.leg_points = flat + np.array([(x0 + x1) / 2, (y0 + y1) / 2, depth])

    def _world(self, poses: np.ndarray, rot: np.ndarray, body_points: np.ndarray) -> np.ndarray:
        return poses[:, None, :3] + np.einsum("nij,pj->npi", rot, body_points)

    def _surface(self, points: np.ndarray, ceiling: bool = False) -> np.ndarray:
        n, p = points.shape[:2]
        return self.maps.lookup(points[..., :2].reshape(-1, 2), ceiling).reshape(n, p)

    def stance_heights(self, poses, rot: np.ndarray | None = None) -> np.ndarray:
        """Height of the body above the floor at each foot, shape (n, n_feet) (nan off the map): at its nominal
        stance point, or at the first alternative point (`stance_choices`) within reach where the nominal is not.

        `rot` may pass the poses' rotation matrices when the caller has them already.
        """
        poses = np.atleast_2d(np.asarray(poses, float))
        if rot is None:
            rot = rotation_rpy(poses[:, 3], poses[:, 4], poses[:, 5])
        heights = []
        for points in self.stance_choices:
            world = self._world(poses, rot, points)
            heights.append(world[..., 2] - self._surface(world))
        heights = np.stack(heights)                                   # (choices, n, feet)
        lo, hi = self.height_range
        reach = (heights >= lo - 1e-9) & (heights <= hi + 1e-9)
        first = np.where(reach.any(0), np.argmax(reach, axis=0), 0)
        return np.take_along_axis(heights, first[None], 0)[0]

    def headroom(self, poses) -> np.ndarray:
        """The highest the body centre of each pose (n, 6) may stand above the floor beneath it with its box (at its
        tilt) still below the ceiling, metres: how much room the ceiling leaves there."""
        poses = np.atleast_2d(np.asarray(poses, float))
        rot = rotation_rpy(poses[:, 3], poses[:, 4], poses[:, 5])
        top = self._world(poses, rot, self.top_points)
        room = np.min(self._surface(top, ceiling=True) - (top[..., 2] - poses[:, None, 2]), axis=1)
        return room - self.maps.floor_at(poses[:, :2])

    def codes(self, poses) -> np.ndarray:
        """Validity code of each pose in (n, 6): VALID, OFF_MAP, OUT_OF_REACH, HITS_CEILING or HITS_FLOOR."""
        poses = np.atleast_2d(np.asarray(poses, float))
        rot = rotation_rpy(poses[:, 3], poses[:, 4], poses[:, 5])
        top, bottom = self._world(poses, rot, self.top_points), self._world(poses, rot, self.bottom_points)
        ceiling, floor = self._surface(top, ceiling=True), self._surface(bottom)
        off = np.isnan(ceiling).any(1) | np.isnan(floor).any(1)
        code = np.full(len(poses), VALID)
        if self.config.check_heights:  # reported last: a collision is the more useful reason
            height = self.stance_heights(poses, rot)
            lo, hi = self.height_range
            too_low = np.nan_to_num(height, nan=lo).min(1) < lo - 1e-9
            too_high = np.nan_to_num(height, nan=hi).max(1) > hi + 1e-9
            code[too_low | too_high] = OUT_OF_REACH
        if len(self.leg_points):
            legs = self._world(poses, rot, self.leg_points)
            code[np.nan_to_num(legs[..., 2] - self._surface(legs), nan=1.0).min(1) < 0] = LEGS_BLOCKED
        code[np.nan_to_num(bottom[..., 2] - floor, nan=1.0).min(1) < 0] = HITS_FLOOR
        code[np.nan_to_num(ceiling - top[..., 2], nan=1.0).min(1) < 0] = HITS_CEILING
        code[off] = OFF_MAP
        return code

    def valid(self, poses) -> np.ndarray:
        """Boolean validity of each pose in (n, 6)."""
        return self.codes(poses) == VALID

    def violation(self, pose) -> str | None:
        """None if the pose is valid, else why not (e.g. 'the body hits the ceiling')."""
        code = int(self.codes(pose)[0])
        if code == VALID:
            return None
        if code == OFF_MAP:
            return f"{REASONS[code]} ({self.maps.describe_bounds()})"
        if code == OUT_OF_REACH:
            h = self.stance_heights(pose)[0]
            lo, hi = self.height_range
            return f"{REASONS[code]}: {h.min():.3f}-{h.max():.3f} m above the floor, reach is {lo:.2f}-{hi:.2f} m"
        return REASONS[code]

    def is_valid(self, pose) -> bool:
        """True if the body box is clear of floor and ceiling and the legs reach the floor."""
        return bool(self.codes(pose)[0] == VALID)
