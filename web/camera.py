"""An egocentric depth image cast with MuJoCo rays from the front of the robot, colour-mapped for display.

Tasks that observe camera images record them in the trajectory (`Trajectory.camera`); for the others
the dashboard shows this depth image, computed at playback time from the recorded pose.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from legged.sensors.raycam import pixel_directions

COLOUR_STOPS = np.array([[255, 235, 80], [245, 120, 40], [200, 40, 80], [90, 30, 130], [20, 20, 60]], np.float64)
"""Near-to-far colours of the depth map (yellow, orange, red, purple, dark blue)."""


@dataclasses.dataclass(frozen=True)
class DepthCameraConfig:
    """Where the depth camera sits and what it sees."""

    width: int = 48
    """Image width, pixels (one ray each)."""
    height: int = 36
    """Image height, pixels."""
    fovy_deg: float = 74.0
    """Vertical field of view, degrees (square pixels; 74 at 48 x 36 is about 90 horizontally)."""
    max_depth: float = 3.0
    """Distances beyond this (and misses) are drawn as the farthest colour, metres."""
    body: str | None = None
    """Body carrying the camera (default: the first body below the world, the robot's base)."""
    offset: tuple[float, float, float] = (0.28, 0.0, 0.05)
    """Camera position in the body frame (Go1: just in front of the head), metres."""
    pitch_deg: float = 15.0
    """Downward tilt of the view, degrees."""


def colour_map(depth: np.ndarray, max_depth: float) -> np.ndarray:
    """Depths (H, W) in metres (negative = no hit) -> (H, W, 3) uint8 colours."""
    t = np.where(depth < 0, 1.0, np.clip(depth / max_depth, 0.0, 1.0)) * (len(COLOUR_STOPS) - 1)
    low = np.minimum(np.floor(t).astype(int), len(COLOUR_STOPS) - 2)
    frac = (t - low)[..., None]
    return ((1 - frac) * COLOUR_STOPS[low] + frac * COLOUR_STOPS[low + 1]).astype(np.uint8)


class DepthCamera:
    """Casts one ray per pixel with `mujoco.mj_multiRay`, ignoring the robot's own geoms where possible."""

    def __init__(self, model: mujoco.MjModel, config: DepthCameraConfig = DepthCameraConfig()):
        if model.nbody < 2:
            raise ValueError("the model has no body to carry a camera")
        self.model, self.config = model, config
        self.body = model.body(config.body).id if config.body else 1
        root = model.body_rootid[self.body]
        own = model.body_rootid[model.geom_bodyid] == root
        # See every group that holds some geom of the rest of the scene; groups only the robot uses are skipped.
        self.geomgroup = np.zeros(6, np.uint8)
        self.geomgroup[np.unique(model.geom_group[~own])] = 1
        # The shared pinhole model (camera frame: x right, y up, looking along -z) turned into the body
        # frame (x forward, y left, z up).
        cam = pixel_directions(config.fovy_deg, config.width, config.height).astype(np.float64)
        dirs = np.stack([-cam[:, 2], -cam[:, 0], cam[:, 1]], -1)
        pitch = np.radians(config.pitch_deg)
        tilt = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
        self._dirs = dirs @ tilt.T
        self._geomid = np.zeros(len(self._dirs), np.int32)
        self._dist = np.zeros(len(self._dirs), np.float64)

    def depth(self, data: mujoco.MjData) -> np.ndarray:
        """Depth image (H, W) in metres, -1 where a ray hits nothing; `data` needs current kinematics."""
        rot = data.xmat[self.body].reshape(3, 3)
        origin = data.xpos[self.body] + rot @ np.asarray(self.config.offset)
        vec = np.ascontiguousarray((self._dirs @ rot.T).ravel())
        mujoco.mj_multiRay(self.model, data, origin, vec, self.geomgroup, 1, self.body, self._geomid, self._dist,
                           None, len(self._dirs), self.config.max_depth * 4)
        return self._dist.reshape(self.config.height, self.config.width).copy()

    def render(self, data: mujoco.MjData) -> np.ndarray:
        """The colour-mapped depth image (H, W, 3) uint8."""
        return colour_map(self.depth(data), self.config.max_depth)
