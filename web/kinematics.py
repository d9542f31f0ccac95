"""Native MuJoCo look-ups for playback: body poses and contact points of a recorded qpos."""

from __future__ import annotations

import mujoco
import numpy as np


class Kinematics:
    """One MjData of a model, set from recorded joint positions (no dynamics are stepped)."""

    def __init__(self, model: mujoco.MjModel):
        self.model = model
        self.data = mujoco.MjData(model)

    def set_qpos(self, qpos: np.ndarray, collide: bool = False) -> mujoco.MjData:
        """Forward kinematics at `qpos`; with `collide`, also MuJoCo's collision detection."""
        self.data.qpos[:] = qpos
        mujoco.mj_kinematics(self.model, self.data)
        if collide:
            mujoco.mj_collision(self.model, self.data)
        return self.data

    @property
    def xpos(self) -> np.ndarray:
        """Body positions (nbody, 3) after the last `set_qpos`."""
        return self.data.xpos

    @property
    def xquat(self) -> np.ndarray:
        """Body quaternions (nbody, 4), w first."""
        return self.data.xquat

    def contact_points(self) -> np.ndarray:
        """World positions (k, 3) of the contacts found by the last `set_qpos(..., collide=True)`."""
        return self.data.contact.pos[: self.data.ncon].copy()
