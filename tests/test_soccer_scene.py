"""The soccer scene composed in code: names, contacts, kick-off, native physics and one MJX step."""

import mujoco
import numpy as np
import pytest

from legged.robots.op3 import OP3
from legged.soccer import (
    KICKOFF_KEY,
    SoccerLayout,
    SoccerSceneConfig,
    build_soccer_scene,
    goal_boxes,
    pitch_lines,
    soccer_scene_xml,
)
from legged.soccer.pitch import line_names


@pytest.fixture(scope="module", params=[1, 2], ids=["1v1", "2v2"])
def scene(request):
    config = SoccerSceneConfig(players_per_team=request.param)
    model = build_soccer_scene(config)
    return config, model, SoccerLayout.from_model(model)


def _kickoff(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(KICKOFF_KEY).id)
    mujoco.mj_forward(model, data)
    return data


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="players_per_team"):
        SoccerSceneConfig(players_per_team=3)
    with pytest.raises(ValueError, match="wall_margin"):
        SoccerSceneConfig(wall_margin=0.2)
    with pytest.raises(ValueError, match="ball_radius"):
        SoccerSceneConfig(ball_radius=0.0)
    with pytest.raises(ValueError, match="head_camera_tilt_deg"):
        SoccerSceneConfig(head_camera_tilt_deg=90.0)
    with pytest.raises(ValueError, match="head_camera_fovy_deg"):
        SoccerSceneConfig(head_camera_fovy_deg=-10.0)


def test_the_head_cameras_lens_is_the_mjcfs_unless_set():
    cameras = lambda model: [c for c in range(model.ncam) if model.camera(c).name.endswith(OP3.head_camera)]
    plain, wide = build_soccer_scene(SoccerSceneConfig()), build_soccer_scene(SoccerSceneConfig(head_camera_fovy_deg=70))
    assert len(cameras(wide)) == 2 and all(plain.cam_fovy[c] == pytest.approx(43.3) for c in cameras(plain))
    assert all(wide.cam_fovy[c] == pytest.approx(70.0) for c in cameras(wide))


def test_compiles_with_namespaced_robots(scene):
    config, model, layout = scene
    n = config.n_agents
    assert layout.n_agents == n and model.nu == OP3.num_joints * n
    expected = [f"{t}{i}/" for t in ("home", "away") for i in range(config.players_per_team)]
    assert list(layout.prefixes) == expected
    for a, prefix in enumerate(expected):
        names = [model.actuator(i).name for i in layout.actuator_ids[a]]
        assert names == [prefix + j for j in OP3.joint_names]
        assert [model.joint(model.jnt_qposadr.tolist().index(q)).name for q in layout.joint_qpos_adr[a]] \
            == [prefix + j for j in OP3.joint_names]
        assert model.camera(layout.head_camera[a]).name == prefix + OP3.head_camera
        assert model.sensor(model.sensor_adr.tolist().index(layout.gyro_adr[a])).name == prefix + "gyro"
    heads = [model.camera(c).name for c in range(model.ncam) if model.camera(c).name.endswith("/head_cam")]
    assert len(heads) == n
    # Every robot has the same number of geoms; agents own disjoint geom sets.
    counts = [layout.agent_geoms(a).size for a in range(n)]
    assert len(set(counts)) == 1 and sum(counts) == np.sum(layout.geom_agent >= 0)


def test_contacts_are_explicit_pairs_only(scene):
    config, model, layout = scene
    assert model.geom_contype.max() == 0 and model.geom_conaffinity.max() == 0
    pairs = {frozenset((model.geom(g1).name, model.geom(g2).name))
             for g1, g2 in zip(model.pair_geom1, model.pair_geom2)}  # the compiler may swap the two
    assert len(pairs) == model.npair
    assert np.all(model.pair_geom1 >= 0) and np.all(model.pair_geom2 >= 0)
    assert np.all(model.pair_geom1 < model.ngeom) and np.all(model.pair_geom2 < model.ngeom)
    for prefix in layout.prefixes:
        for geom in OP3.feet_geoms + OP3.body_geoms:
            assert {prefix + geom, "floor"} in pairs
        for geom in config.ball_robot_geoms:
            assert {"ball", prefix + geom} in pairs
    assert {"ball", "floor"} in pairs
    for team in range(2):
        for box in goal_boxes(config, team):
            assert {"ball", box.name} in pairs
    assert sum(1 for pair in pairs if any(g.startswith("wall/") for g in pair)) == 4
    robots = [pair for pair in pairs if all(g.startswith(("home", "away")) for g in pair)]
    assert not robots  # no robot-robot pairs unless asked
    n = config.n_agents
    per_agent = len(OP3.feet_geoms + OP3.body_geoms) + len(config.ball_robot_geoms)
    assert model.npair == n * per_agent + 1 + 14 + 4


def test_robot_robot_pairs_are_optional():
    model = build_soccer_scene(SoccerSceneConfig(players_per_team=2, robot_robot_contacts=True))
    names = {frozenset((model.geom(a).name, model.geom(b).name)) for a, b in zip(model.pair_geom1, model.pair_geom2)}
    assert {"home0/torso", "away1/torso"} in names and {"home1/l_foot", "away0/r_foot"} in names
    assert model.npair == build_soccer_scene(SoccerSceneConfig(players_per_team=2)).npair + 6 * 5


def test_limb_floor_pairs_are_optional():
    model = build_soccer_scene(SoccerSceneConfig(limb_floor_contacts=True))
    names = {frozenset((model.geom(a).name, model.geom(b).name)) for a, b in zip(model.pair_geom1, model.pair_geom2)}
    limbs = OP3.arm_geoms + OP3.thigh_geoms + OP3.calf_geoms
    assert all({f"{prefix}{geom}", "floor"} in names for prefix in ("home0/", "away0/") for geom in limbs)
    assert model.npair == build_soccer_scene(SoccerSceneConfig()).npair + 2 * len(limbs)


def test_leg_pairs_are_optional_and_stop_crossed_legs():
    """With leg_contacts, each robot's left thigh, shin and foot touch its right ones (3 x 3 pairs per robot); the
    same legs pass through each other without it. Crossed legs: the left hip rolled 0.3 rad inward, shins and feet
    overlap."""
    plain = build_soccer_scene(SoccerSceneConfig())
    model = build_soccer_scene(SoccerSceneConfig(leg_contacts=True))
    names = {frozenset((model.geom(a).name, model.geom(b).name)) for a, b in zip(model.pair_geom1, model.pair_geom2)}
    assert {"home0/l_foot", "home0/r_foot"} in names and {"away0/l_thigh", "away0/r_shin"} in names
    assert model.npair == plain.npair + 2 * 9

    def leg_contacts(m):
        data = _kickoff(m)
        data.qpos[m.joint("home0/l_hip_roll").qposadr[0]] += 0.3  # the left leg swings inward, under the robot
        mujoco.mj_forward(m, data)
        legs = {f"home0/{g}" for g in OP3.thigh_geoms + OP3.calf_geoms + OP3.feet_geoms}
        return [c for c in data.contact[:data.ncon]
                if {m.geom(c.geom1).name, m.geom(c.geom2).name} <= legs]

    assert leg_contacts(model) and not leg_contacts(plain)


def test_kickoff_positions_face_the_opponent_goal(scene):
    config, model, layout = scene
    data = _kickoff(model)
    for a in range(layout.n_agents):
        pos = data.xpos[layout.torso_body[a]]
        attack = 1.0 if layout.team[a] == 0 else -1.0  # home attacks +x
        assert attack * pos[0] < -config.centre_circle_radius  # own half, outside the circle
        assert abs(pos[1]) < config.field_width / 2 and abs(pos[0]) < config.field_length / 2
        assert pos[2] == pytest.approx(OP3.standing_height, abs=1e-6)
        forward = data.xmat[layout.torso_body[a]].reshape(3, 3)[:, 0]
        assert forward @ [attack, 0.0, 0.0] > 0.999
        cam = data.cam_xmat[layout.head_camera[a]].reshape(3, 3)  # cameras look along -z, image right is +x
        tilt = np.deg2rad(config.head_camera_tilt_deg)  # toward the opponent goal, looking down
        np.testing.assert_allclose(-cam[:, 2], [attack * np.cos(tilt), 0.0, -np.sin(tilt)], atol=1e-6)
        np.testing.assert_allclose(cam[:, 0], [0.0, -attack, 0.0], atol=1e-6)  # the robot's right
        assert data.qpos[layout.joint_qpos_adr[a]] == pytest.approx(OP3.default_pose)
        assert data.ctrl[layout.actuator_ids[a]] == pytest.approx(OP3.default_pose)
    ball = data.qpos[layout.ball_qpos_adr: layout.ball_qpos_adr + 3]
    assert ball == pytest.approx([0.0, 0.0, config.ball_radius])


def test_painted_lines_realise_the_line_data(scene):
    config, model, layout = scene
    lines = pitch_lines(config)
    assert lines.shape == (5 + config.circle_segments, 5)
    for name, (x0, y0, x1, y1, width) in zip(line_names(config), lines):
        g = model.geom(name)
        assert g.group[0] == 1 and g.contype[0] == 0 and g.conaffinity[0] == 0
        assert g.pos[:2] == pytest.approx([(x0 + x1) / 2, (y0 + y1) / 2], abs=1e-6)
        assert 2 * g.size[0] == pytest.approx(np.hypot(x1 - x0, y1 - y0), abs=1e-6)
        assert 2 * g.size[1] == pytest.approx(width)
    assert sorted(layout.line_geoms) == sorted(model.geom(n).id for n in line_names(config))
    # The centre circle's pieces stay within half a line width of the circle.
    r = np.hypot(lines[5:, [0, 2]], lines[5:, [1, 3]])
    assert np.all(np.abs(r - config.centre_circle_radius) < config.line_width)


def test_dropped_ball_settles_on_the_floor():
    config = SoccerSceneConfig()
    model = build_soccer_scene(config)
    layout = SoccerLayout.from_model(model)
    data = _kickoff(model)
    adr = layout.ball_qpos_adr
    data.qpos[adr + 2] = 0.5
    heights = []
    for _ in range(int(2.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        heights.append(data.qpos[adr + 2])
    assert min(heights) > config.ball_radius - 0.02  # no tunnelling through the floor
    assert heights[-1] == pytest.approx(config.ball_radius, abs=2e-3)
    assert np.abs(data.qvel[layout.ball_dof_adr: layout.ball_dof_adr + 6]).max() < 1e-2


def test_robots_hold_their_default_pose_natively(scene):
    _, model, layout = scene
    data = _kickoff(model)
    for _ in range(int(1.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    for a in range(layout.n_agents):
        body = layout.torso_body[a]
        assert data.xpos[body, 2] > 0.22  # standing: 0.245 kinematic, settles about 3 mm lower
        assert data.xmat[body, 8] > 0.98  # torso z axis still up


def test_xml_text_compiles_to_the_same_model():
    config = SoccerSceneConfig(players_per_team=2)
    model = build_soccer_scene(config)
    again = mujoco.MjModel.from_xml_string(soccer_scene_xml(config))
    assert (again.nq, again.nu, again.npair, again.ncam, again.ngeom) == \
        (model.nq, model.nu, model.npair, model.ncam, model.ngeom)
    assert np.allclose(again.key_qpos, model.key_qpos)
