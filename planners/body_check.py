"""Is a body pose valid? The robot's body box against the floor and ceiling maps, plus leg reach.

The box (half extents plus a margin) is sampled on all six faces at no more than half the map
resolution and rotated by the full roll, pitch and yaw: the lower samples must lie above the floor,
the upper ones below the ceiling. The legs must reach the floor: at each foot's nominal stance point
the body (tilt included) must stand within the robot's `body_height_range` above the floor there.
Poses are checked in batches (all states of a motion at once), which is what makes planning in
Python fast enough.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from legged.robots.spec import RobotSpec
from legged.worlds.maps import HeightMaps

VALID, OFF_MAP, OUT_OF_REACH, HITS_CEILING, HITS_FLOOR = range(5)
REASONS = {OFF_MAP: "the body leaves the map", OUT_OF_REACH: "the legs cannot hold the body there",
           HITS_CEILING: "the body hits the ceiling", HITS_FLOOR: "the body hits the floor"}


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


class BodyChecker:
    """Validity of body poses (x, y, z, roll, pitch, yaw) in one pair of height maps."""

    def __init__(self, maps: HeightMaps, robot: RobotSpec, config: BodyCheckConfig = BodyCheckConfig()):
        self.maps, self.robot, self.config = maps, robot, config
        self.half_extents = np.asarray(robot.body_box_half_extents, float) + config.margin
        faces = box_surface_points(self.half_extents, maps.resolution / 2)
        self.bottom_points = faces[faces[:, 2] < 0]  # bottom face and the lower half of the sides
        self.top_points = faces[faces[:, 2] > 0]
        stance = stance_points(robot)
        self.stance_points = np.concatenate([stance, np.zeros((len(stance), 1))], 1)
        inward = stance.copy()
        inward[:, 1] -= np.sign(stance[:, 1]) * np.minimum(config.stance_slack, np.abs(stance[:, 1]))
        self.narrow_stance_points = np.concatenate([inward, np.zeros((len(stance), 1))], 1)
        self.height_range = robot.body_height_range

    def _world(self, poses: np.ndarray, rot: np.ndarray, body_points: np.ndarray) -> np.ndarray:
        return poses[:, None, :3] + np.einsum("nij,pj->npi", rot, body_points)

    def _surface(self, points: np.ndarray, ceiling: bool = False) -> np.ndarray:
        n, p = points.shape[:2]
        return self.maps.lookup(points[..., :2].reshape(-1, 2), ceiling).reshape(n, p)

    def stance_heights(self, poses, rot: np.ndarray | None = None) -> np.ndarray:
        """Height of the body above the floor at each foot's stance point, shape (n, n_feet) (nan off the map):
        the nominal point, or the narrower one (`stance_slack`) where only that one is within reach.

        `rot` may pass the poses' rotation matrices when the caller has them already.
        """
        poses = np.atleast_2d(np.asarray(poses, float))
        if rot is None:
            rot = rotation_rpy(poses[:, 3], poses[:, 4], poses[:, 5])
        nominal, narrow = (self._world(poses, rot, p) for p in (self.stance_points, self.narrow_stance_points))
        h_nominal = nominal[..., 2] - self._surface(nominal)
        h_narrow = narrow[..., 2] - self._surface(narrow)
        lo, hi = self.height_range
        reach = lambda h: (h >= lo - 1e-9) & (h <= hi + 1e-9)
        return np.where(~reach(h_nominal) & reach(h_narrow), h_narrow, h_nominal)

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
