"""Body height, roll and pitch derived from the gap over and under the body, not sampled.

For a body at (x, y, yaw) with a given roll and pitch, every constraint of `BodyChecker` bounds the body
centre's height z from one side: a point of the box's underside must stay above the floor beneath it
(z >= floor - offset; so must the legs' rectangle at knee height), a point of its top below the ceiling
above it (z <= ceiling - offset), and each foot's stance point within leg reach (lo <= z + offset - floor
<= hi). The feasible heights are therefore
one band [z_low, z_high], computed exactly in one vectorised pass. A planner that searches (x, y, yaw)
only and puts the body in the middle of its band loses no pose of those tilts, and a band a few
millimetres wide (a bar just above the robot's lowest crouch) is found as easily as a wide one.

The body is level where a level body fits; elsewhere it is tried parallel to the plane fitted to the floor
under the feet (clipped to the planner's limits).
"""

from __future__ import annotations

import math

import numpy as np
from planners.body_check import BodyChecker, rotation_rpy, widest_band
from planners.box_space import BoxSpace


class PoseBands:
    """Feasible body-height bands and centred poses for batches of (x, y, yaw)."""

    def __init__(self, checker: BodyChecker, max_roll: float, max_pitch: float):
        self.checker, self.max_roll, self.max_pitch = checker, max_roll, max_pitch
        stance = checker.stance_points[:, :2]
        # least-squares plane through the stance points: floor ~ a + b * x_body + c * y_body
        design = np.concatenate([np.ones((len(stance), 1)), stance], 1)
        self._fit = np.linalg.pinv(design)  # (3, n_feet)
        half_z = checker.half_extents[2]
        face = checker.bottom_points[np.isclose(checker.bottom_points[:, 2], -half_z)]
        self._bottom_face = np.concatenate([face, checker.leg_points])
        self._bottom = np.concatenate([checker.bottom_points, checker.leg_points])
        self._top_face = checker.top_points[np.isclose(checker.top_points[:, 2], half_z)]

    def band(self, xy_yaw: np.ndarray, roll: np.ndarray, pitch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(z_low, z_high) of the body centre for poses (n, 3) = x, y, yaw at the given tilts (n,)."""
        c = self.checker
        rot = rotation_rpy(roll, pitch, xy_yaw[:, 2])
        level = not (np.any(roll) or np.any(pitch))  # then only the bottom and top faces and the legs can touch
        def offsets(points):
            return np.einsum("nij,pj->npi", rot, points)
        def surface(off, ceiling=False):
            xy = xy_yaw[:, None, :2] + off[..., :2]
            return c.maps.lookup(xy.reshape(-1, 2), ceiling).reshape(off.shape[:2])
        bottom = offsets(self._bottom_face if level else self._bottom)
        top = offsets(self._top_face if level else c.top_points)
        low = np.max(surface(bottom) - bottom[..., 2], axis=1)
        high = np.min(surface(top, ceiling=True) - top[..., 2], axis=1)
        bad = np.isnan(low) | np.isnan(high)
        low, high = np.where(bad, np.inf, low), np.where(bad, -np.inf, high)
        if c.config.check_heights:  # each foot at its nominal point or an alternative: the widest band, exactly
            lo, hi = c.height_range
            ground = np.stack([surface(o) - o[..., 2] for o in map(offsets, c.stance_choices)], -1)
            ground = np.nan_to_num(ground, nan=np.inf)  # (n, feet, choices): off the map, never within reach
            low, high = widest_band(low, high, ground + lo, ground + hi)
        return low, high

    def floor_tilt(self, xy_yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Roll and pitch of the plane fitted to the floor under the stance points (clipped to the limits)."""
        yaw = xy_yaw[:, 2]
        cos, sin = np.cos(yaw), np.sin(yaw)
        sx, sy = self.checker.stance_points[:, 0], self.checker.stance_points[:, 1]
        wx = xy_yaw[:, None, 0] + cos[:, None] * sx - sin[:, None] * sy
        wy = xy_yaw[:, None, 1] + sin[:, None] * sx + cos[:, None] * sy
        heights = self.checker.maps.lookup(np.stack([wx, wy], -1).reshape(-1, 2)).reshape(wx.shape)
        slope = np.nan_to_num(heights) @ self._fit.T  # (n, 3): offset, d/dx_body, d/dy_body
        pitch = np.clip(-np.arctan(slope[:, 1]), -self.max_pitch, self.max_pitch)
        roll = np.clip(np.arctan(slope[:, 2]), -self.max_roll, self.max_roll)
        return roll, pitch

    @np.errstate(invalid="ignore")  # off the map a band is (inf, -inf): its middle is NaN, and unused
    def project(self, xy_yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(poses (n, 6) with the body in the middle of its band, level if it can be, whether a band exists (n,))."""
        xy_yaw = np.atleast_2d(np.asarray(xy_yaw, float))
        n = len(xy_yaw)
        poses = np.zeros((n, 6))
        poses[:, :2], poses[:, 5] = xy_yaw[:, :2], xy_yaw[:, 2]
        low, high = self.band(xy_yaw, np.zeros(n), np.zeros(n))
        best = high - low
        poses[:, 2] = 0.5 * (low + high)
        tilt = np.flatnonzero(best < 0.0)  # no level body fits: try the one parallel to the floor
        if tilt.size:
            roll, pitch = self.floor_tilt(xy_yaw[tilt])
            low, high = self.band(xy_yaw[tilt], roll, pitch)
            fits = high - low >= 0.0
            rows = tilt[fits]
            best[rows] = (high - low)[fits]
            poses[rows, 2] = 0.5 * (low + high)[fits]
            poses[rows, 3], poses[rows, 4] = roll[fits], pitch[fits]
        return poses, best >= 0.0


class ProjectedSpace(BoxSpace):
    """The planning space (x, y, scaled yaw): height, roll and pitch come from `PoseBands`."""

    def __init__(self, maps, checker: BodyChecker, config, heading: float):
        self.maps, self.heading, self.w = maps, heading, config.angle_weight
        self.bands = PoseBands(checker, config.max_roll, config.max_pitch)
        super().__init__([maps.origin[0], maps.origin[1], -self.w * math.pi],
                         [maps.upper[0], maps.upper[1], self.w * math.pi])

    def _xy_yaw(self, vectors: np.ndarray) -> np.ndarray:
        v = np.atleast_2d(vectors)
        yaw = (v[:, 2] / self.w + self.heading + math.pi) % (2 * math.pi) - math.pi
        return np.stack([v[:, 0], v[:, 1], yaw], 1)

    def to_poses(self, vectors: np.ndarray) -> np.ndarray:
        """Scaled states (n, 3) -> centred poses (n, 6) (NaN height where no band exists)."""
        poses, ok = self.bands.project(self._xy_yaw(vectors))
        poses[~ok, 2] = np.nan
        return poses

    def valid(self, vectors: np.ndarray) -> np.ndarray:
        """Whether each state has a band of feasible heights."""
        return self.bands.project(self._xy_yaw(vectors))[1]

    def to_vector(self, pose) -> np.ndarray:
        """One pose (6,) -> scaled state (3,)."""
        rel_yaw = (pose[5] - self.heading + math.pi) % (2 * math.pi) - math.pi
        return np.array([pose[0], pose[1], self.w * rel_yaw])
