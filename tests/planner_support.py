"""Test helpers: MuJoCo's own collision detection for body boxes, and a tunnel scene built from boxes."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from legged.worlds.mjcf import TERRAIN_GROUP
from planners.body_check import quat_rpy

PROBE = "probe_box"


def with_probe_box(xml: str, half_extents, surfaces: list[str] | None = None) -> mujoco.MjModel:
    """The scene plus a mocap body holding a box of `half_extents`, paired explicitly with the scene's `surfaces`
    (geom names; None: every geom of the scene that collides with anything, unnamed ones named here).

    Explicit contact pairs, because MuJoCo never collides two bodies welded to the world, and a mocap body is one.
    """
    root = ET.fromstring(xml)
    worldbody = root.find("worldbody")
    if surfaces is None:
        surfaces = []
        for k, geom in enumerate(worldbody.iter("geom")):
            if geom.get("contype") == "0" and geom.get("conaffinity") == "0":
                continue  # decorative
            geom.set("name", geom.get("name") or f"probed_{k}")
            surfaces.append(geom.get("name"))
    body = ET.SubElement(worldbody, "body", name="probe", mocap="true", pos="0 0 5")
    ET.SubElement(body, "geom", name=PROBE, type="box", size=" ".join(f"{h:.6f}" for h in half_extents),
                  contype="0", conaffinity="0", margin="0")
    contact = root.find("contact") if root.find("contact") is not None else ET.SubElement(root, "contact")
    for surface in surfaces:
        ET.SubElement(contact, "pair", geom1=PROBE, geom2=surface)
    return mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))


def probe_penetration(model: mujoco.MjModel, data: mujoco.MjData, pose) -> float:
    """Deepest penetration (metres, >= 0) of the probe box at `pose` into anything, by mj_collision."""
    data.mocap_pos[0] = pose[:3]
    data.mocap_quat[0] = quat_rpy(*pose[3:6])
    mujoco.mj_kinematics(model, data)
    mujoco.mj_collision(model, data)
    probe = model.geom(PROBE).id
    depth = 0.0
    for c in data.contact[:data.ncon]:
        if probe in (c.geom1, c.geom2):
            depth = max(depth, -float(c.dist))
    return depth


BOX_TUNNEL = """
<mujoco model="box_tunnel">
  <asset>
    <mesh name="slab" vertex="-0.15 -0.6 0  0.15 -0.6 0  -0.15 0.6 0  0.15 0.6 0
                              -0.15 -0.6 0.2  0.15 -0.6 0.2  -0.15 0.6 0.2  0.15 0.6 0.2"/>
  </asset>
  <worldbody>
    <geom name="ground" type="box" pos="0 0 -0.05" size="2.5 1.0 0.05"/>
    <geom name="wall_left" type="box" pos="0 0.55 0.4" size="2.5 0.05 0.4"/>
    <geom name="wall_right" type="box" pos="0 -0.55 0.4" size="2.5 0.05 0.4"/>
    <geom name="roof" type="box" pos="0 0 0.65" size="2.5 0.6 0.05"/>
    <geom name="beam" type="box" pos="0.3 0 0.49" size="0.15 0.6 0.15"/>
    <geom name="step" type="box" pos="-0.8 0.25 0.02" size="0.2 0.25 0.02"/>
    <geom name="slab" type="mesh" mesh="slab" pos="1.5 0 0.42"/>
    <geom name="deco" type="sphere" pos="1.0 0 0.3" size="0.05" contype="0" conaffinity="0"/>
  </worldbody>
</mujoco>
"""
"""A 5 m tunnel of boxes: 0.6 m roof, a beam whose underside is 0.34 m above the ground at x = 0.3,
a 4 cm step on one side, a mesh slab hanging to 0.42 m at x = 1.5, and a decorative (non-colliding)
sphere the planner must ignore."""


def ray_heights(model, data, xy, z_from):
    """Floor below and ceiling above (x, y, z_from) by MuJoCo's mj_ray, terrain geoms only."""
    group = np.zeros(6, np.uint8)
    group[TERRAIN_GROUP] = 1
    geom = np.zeros(1, np.int32)
    start = np.array([xy[0], xy[1], z_from])
    down = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, -1.0]), group, 1, -1, geom)
    up = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, 1.0]), group, 1, -1, geom)
    return z_from - down, z_from + up
