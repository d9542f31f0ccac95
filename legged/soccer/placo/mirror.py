"""The OP3's left-right mirror image of joint vectors (reflection y -> -y of the robot frame)."""

from __future__ import annotations

import mujoco
import numpy as np

from legged.robots.op3 import OP3


def mirror_name(name: str) -> str:
    """The joint's mirror twin: l_* <-> r_*; the head's joints are their own."""
    return {"l_": "r_", "r_": "l_"}[name[:2]] + name[2:] if name[:2] in ("l_", "r_") else name


def mirror_signs(model: mujoco.MjModel | None = None) -> np.ndarray:
    """Sign s_j with q_mirror[mirror(j)] = s_j q[j], from the MJCF's joint axes (reflection y -> -y: a
    rotation about axis a becomes one about -M a, M = diag(1, -1, 1)). Checks the limbs are symmetric."""
    model = model or mujoco.MjModel.from_xml_path(str(OP3.mjcf_path))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    M = np.diag([1.0, -1.0, 1.0])
    signs = []
    for name in OP3.joint_names:
        other = mirror_name(name)
        a, b = data.xaxis[model.joint(name).id], data.xaxis[model.joint(other).id]
        s = float(np.dot(b, -M @ a))
        if abs(abs(s) - 1) > 1e-6:
            raise ValueError(f"joint {name!r}: axis {a} has no mirror twin ({other!r}: {b})")
        pa, pb = data.xanchor[model.joint(name).id], data.xanchor[model.joint(other).id]
        # The limbs are left-right symmetric (the head's tilt axis sits 19 mm off-centre).
        if name != other and not np.allclose(M @ pa, pb, atol=1e-4):
            raise ValueError(f"joint {name!r} at {pa} is not the mirror image of {other!r} at {pb}")
        signs.append(s)
    return np.array(signs)


def mirror_joints(q: np.ndarray, signs: np.ndarray) -> np.ndarray:
    """The left-right mirror image of joint vector(s) q (..., 20), OP3.joint_names order."""
    idx = [OP3.joint_names.index(mirror_name(n)) for n in OP3.joint_names]
    out = np.empty_like(q)
    out[..., idx] = q * signs
    return out
