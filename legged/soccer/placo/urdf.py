"""A URDF of the OP3 generated from the compiled MuJoCo model, for placo (pinocchio) kinematics.

placo loads URDF robots; `placo.HumanoidRobot` needs the frames `trunk`, `left_foot` and `right_foot`.
The URDF is written from `mujoco.MjModel` of assets/robots/op3.xml, so it can never drift from the MJCF:

- one link per MuJoCo body (same name), with its mass, centre of mass (`body_ipos`) and inertia tensor
  (`body_inertia`, the principal moments, turned by `body_iquat` into the body frame);
- one revolute joint per hinge (same name as the MJCF joint), origin = the body's `body_pos` /
  `body_quat` in its parent, axis = `jnt_axis`, limits = `jnt_range`, effort = the actuator's force
  range, velocity = the servo's no-load speed; the free joint is dropped (pinocchio adds its own
  floating base on the root link `body_link`);
- massless fixed frames: `trunk` on `body_link` (identity), `left_foot` / `right_foot` on the sole
  centres (sites `l_foot` / `r_foot`: 30.5 mm below the ankle roll axis, x forward, z up), and
  `left_hip_yaw` / `right_hip_yaw` on the hip yaw bodies (placo measures the leg spacing there).

No meshes or collision geometry: placo only needs kinematics and inertia here. The file is generated
on demand into a cache directory (never committed): `op3_urdf_path()`.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from legged.files import write_atomic
from legged.robots.op3 import OP3

SERVO_VELOCITY = 4.8
"""Dynamixel XM430-W350 no-load speed at 12 V, rad/s (46 rpm): the URDF's joint velocity limit."""
FOOT_FRAMES = {"left_foot": "l_foot", "right_foot": "r_foot"}
"""placo frame -> MJCF site (the sole centres)."""
HIP_FRAMES = {"left_hip_yaw": "l_hip_yaw_link", "right_hip_yaw": "r_hip_yaw_link"}
"""placo frame -> MJCF body (placo reads the trunk-to-hip lateral distance from `left_hip_yaw`)."""
TRUNK_FRAME = "trunk"


def _quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=np.float64))
    return mat.reshape(3, 3)


def _rpy(rot: np.ndarray) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw (fixed axes x, then y, then z: R = Rz(yaw) Ry(pitch) Rx(roll)) of `rot`."""
    return tuple(float(a) for a in Rotation.from_matrix(rot).as_euler("xyz"))


def _fmt(values) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def _origin(pos, rot: np.ndarray) -> str:
    return f'<origin xyz="{_fmt(pos)}" rpy="{_fmt(_rpy(rot))}"/>'


def _link(name: str, mass: float = 0.0, com=None, inertia: np.ndarray | None = None) -> list[str]:
    if mass <= 0.0:
        return [f"  <link name={quoteattr(name)}/>"]
    i = inertia
    return [
        f"  <link name={quoteattr(name)}>",
        "    <inertial>",
        f'      <origin xyz="{_fmt(com)}" rpy="0 0 0"/>',
        f'      <mass value="{mass:.9g}"/>',
        (f'      <inertia ixx="{i[0, 0]:.9g}" ixy="{i[0, 1]:.9g}" ixz="{i[0, 2]:.9g}" '
         f'iyy="{i[1, 1]:.9g}" iyz="{i[1, 2]:.9g}" izz="{i[2, 2]:.9g}"/>'),
        "    </inertial>",
        "  </link>",
    ]


def _fixed(name: str, parent: str, child: str, pos, rot: np.ndarray) -> list[str]:
    return [
        f'  <joint name={quoteattr(name)} type="fixed">',
        f"    <parent link={quoteattr(parent)}/>",
        f"    <child link={quoteattr(child)}/>",
        f"    {_origin(pos, rot)}",
        "  </joint>",
    ]


def op3_urdf(model: mujoco.MjModel | None = None) -> str:
    """URDF text of the OP3 of `model` (default: assets/robots/op3.xml compiled alone)."""
    if model is None:
        model = mujoco.MjModel.from_xml_path(str(OP3.mjcf_path))
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, OP3.root_body)
    if root < 0:
        raise ValueError(f"no body {OP3.root_body!r} in the model")
    # Bodies of the robot: the root and its descendants (body ids are topologically sorted).
    bodies = [root]
    for b in range(root + 1, model.nbody):
        if model.body_parentid[b] in bodies:
            bodies.append(b)

    def name(obj, i):
        return mujoco.mj_id2name(model, obj, i)

    force_range = {}
    for a in range(model.nu):
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            j = model.actuator_trnid[a, 0]
            limit = model.actuator_forcerange[a] if model.actuator_forcelimited[a] else (-100.0, 100.0)
            force_range[j] = float(max(abs(limit[0]), abs(limit[1])))

    lines = ['<?xml version="1.0"?>', '<robot name="op3">']
    for b in bodies:
        rot_i = _quat_to_matrix(model.body_iquat[b])
        inertia = rot_i @ np.diag(model.body_inertia[b]) @ rot_i.T
        lines += _link(name(mujoco.mjtObj.mjOBJ_BODY, b), float(model.body_mass[b]), model.body_ipos[b], inertia)

    for b in bodies[1:]:
        joints = range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b])
        parent = name(mujoco.mjtObj.mjOBJ_BODY, model.body_parentid[b])
        child = name(mujoco.mjtObj.mjOBJ_BODY, b)
        origin = _origin(model.body_pos[b], _quat_to_matrix(model.body_quat[b]))
        if len(joints) == 0:
            lines += _fixed(f"{child}_fixed", parent, child, model.body_pos[b], _quat_to_matrix(model.body_quat[b]))
            continue
        if len(joints) > 1:
            raise ValueError(f"body {child!r} has {len(joints)} joints; the URDF takes one per body")
        j = joints[0]
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
            raise ValueError(f"joint {name(mujoco.mjtObj.mjOBJ_JOINT, j)!r} is not a hinge")
        if np.any(np.abs(model.jnt_pos[j]) > 1e-12):
            raise ValueError("hinges off the body origin are not supported (jnt_pos != 0)")
        low, high = model.jnt_range[j] if model.jnt_limited[j] else (-np.pi, np.pi)
        lines += [
            f'  <joint name={quoteattr(name(mujoco.mjtObj.mjOBJ_JOINT, j))} type="revolute">',
            f"    <parent link={quoteattr(parent)}/>",
            f"    <child link={quoteattr(child)}/>",
            f"    {origin}",
            f'    <axis xyz="{_fmt(model.jnt_axis[j])}"/>',
            (f'    <limit lower="{low:.9g}" upper="{high:.9g}" effort="{force_range.get(j, 100.0):.9g}" '
             f'velocity="{SERVO_VELOCITY:.9g}"/>'),
            "  </joint>",
        ]

    # Fixed frames placo needs.
    root_name = name(mujoco.mjtObj.mjOBJ_BODY, root)
    lines += _link(TRUNK_FRAME) + _fixed(f"{TRUNK_FRAME}_frame", root_name, TRUNK_FRAME, np.zeros(3), np.eye(3))
    for frame, site_name in FOOT_FRAMES.items():
        site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site_name)
        parent = name(mujoco.mjtObj.mjOBJ_BODY, model.site_bodyid[site])
        lines += _link(frame) + _fixed(f"{frame}_frame", parent, frame, model.site_pos[site],
                                       _quat_to_matrix(model.site_quat[site]))
    for frame, body_name in HIP_FRAMES.items():
        lines += _link(frame) + _fixed(f"{frame}_frame", body_name, frame, np.zeros(3), np.eye(3))
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def cache_dir() -> Path:
    """Directory of generated files: $LEGGED_CACHE, else $XDG_CACHE_HOME/legged, else ~/.cache/legged."""
    if os.environ.get("LEGGED_CACHE"):
        return Path(os.environ["LEGGED_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "legged"


def op3_urdf_path(model: mujoco.MjModel | None = None, directory: Path | None = None) -> Path:
    """Write the OP3 URDF (if not already there) and return its path.

    The file name carries a hash of the text, so a changed op3.xml gives a new file and stale ones
    are never read. The write goes through a temporary file and a rename (safe with parallel workers).
    """
    text = op3_urdf(model)
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    directory = Path(directory) if directory is not None else cache_dir()
    path = directory / f"op3_{digest}.urdf"
    if not path.exists():
        directory.mkdir(parents=True, exist_ok=True)
        write_atomic(path, text)
    return path
