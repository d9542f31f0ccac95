"""The soccer scene composed in code with MjSpec: pitch, lines, goals, ball and OP3 teams.

Every robot is a namespaced copy of assets/robots/op3.xml attached with `MjsFrame.attach_body`
(prefix 'home0/', 'away1/', ...: its joints, actuators, sensors, sites and cameras are prefixed too),
tinted with its team colour and placed at its kick-off pose. Contacts are explicit `<pair>`s only
(every geom keeps contype = conaffinity = 0) so MJX evaluates just these:

- each robot's feet, torso and head with the floor (torso and head: fallen robots lie on the floor), and
  with `limb_floor_contacts` its arms, thighs and shins too (what a robot getting up pushes with);
- the ball with the floor (condim 6: rolling friction slows it like grass), with each robot's
  `ball_robot_geoms` (feet and shins: what kicks), with every goal box and with the four walls;
- optionally (`robot_robot_contacts`) torso-torso and foot-foot between every two robots.

Geom groups: 0 floor, goals and ball (seen and physical); 1 painted lines (thin boxes, seen only; the
ray camera draws them analytically from `pitch_lines`); 2 robot visuals (OP3 convention); 3 robot
collision geoms and the invisible walls (hidden by MuJoCo's renderer by default).
"""

from __future__ import annotations

import mujoco
import numpy as np

from legged.robots.op3 import OP3
from legged.soccer.config import TEAMS, SoccerSceneConfig
from legged.soccer.layout import BALL, FLOOR_GEOM, SoccerLayout
from legged.soccer.pitch import (
    goal_boxes,
    kickoff_poses,
    line_names,
    pitch_lines,
    walls,
)

TEAM_COLOUR_GEOMS = ("torso_visual", "head_visual")
"""OP3 visual geoms painted in the team colour (the rest of the robot keeps its dark servo colour)."""
KICKOFF_KEY = "kickoff"
"""Keyframe with every robot standing at its kick-off pose and the ball on the centre spot."""
LINE_GROUP, VISUAL_GROUP, HIDDEN_GROUP = 1, 2, 3
_LINE_HALF_THICKNESS = 0.0005
_QPOS0_HEIGHT = 0.29
"""Root height in qpos0, where the OP3's legs are straight (0.279 m from sole to root): no penetration."""


def _yaw_quat(yaw: float) -> list[float]:
    return [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]


def _quat_z_to(normal: np.ndarray) -> list[float]:
    """Quaternion turning +z onto a horizontal unit `normal` (a wall plane's normal)."""
    axis = np.cross([0.0, 0.0, 1.0], normal)
    angle = np.arccos(np.clip(normal[2], -1.0, 1.0))
    axis = axis / np.linalg.norm(axis)
    return [np.cos(angle / 2), *(np.sin(angle / 2) * axis)]


def agent_prefix(team: int, player: int) -> str:
    """Name prefix of a robot: 'home0/', 'away1/', ..."""
    return f"{TEAMS[team]}{player}/"


def _static_geom(body, name, gtype, size, pos, rgba, group, quat=(1.0, 0.0, 0.0, 0.0)):
    return body.add_geom(name=name, type=gtype, size=list(size), pos=list(pos), quat=list(quat), rgba=list(rgba),
                         group=group, contype=0, conaffinity=0)


def _add_pitch(spec: mujoco.MjSpec, config: SoccerSceneConfig) -> None:
    world = spec.worldbody
    half_x = config.field_length / 2 + config.wall_margin + config.floor_margin
    half_y = config.field_width / 2 + config.wall_margin + config.floor_margin
    # A finite plane: MuJoCo's renderer and the ray camera both end the grass at its edge (then sky).
    _static_geom(world, FLOOR_GEOM, mujoco.mjtGeom.mjGEOM_PLANE, (half_x, half_y, 0.05), (0, 0, 0),
                 config.pitch_rgba, 0)
    for name, (x0, y0, x1, y1, width) in zip(line_names(config), pitch_lines(config)):
        length = float(np.hypot(x1 - x0, y1 - y0))
        yaw = float(np.arctan2(y1 - y0, x1 - x0))
        _static_geom(world, name, mujoco.mjtGeom.mjGEOM_BOX, (length / 2, width / 2, _LINE_HALF_THICKNESS),
                     ((x0 + x1) / 2, (y0 + y1) / 2, _LINE_HALF_THICKNESS), config.line_rgba, LINE_GROUP,
                     _yaw_quat(yaw))
    for team in range(2):
        net_rgba = config.team_net_rgba(team)
        for box in goal_boxes(config, team):
            rgba = config.post_rgba if box.part == "post" else net_rgba
            _static_geom(world, box.name, mujoco.mjtGeom.mjGEOM_BOX, box.half, box.pos, rgba, 0)
    for name, point, normal in walls(config):
        _static_geom(world, name, mujoco.mjtGeom.mjGEOM_PLANE, (0.0, 0.0, 0.05), point, (0.5, 0.5, 0.5, 0.0),
                     HIDDEN_GROUP, _quat_z_to(normal))


def _add_ball(spec: mujoco.MjSpec, config: SoccerSceneConfig) -> None:
    body = spec.worldbody.add_body(name=BALL, pos=[0.0, 0.0, config.ball_radius])
    body.add_freejoint(name=BALL)
    geom = _static_geom(body, BALL, mujoco.mjtGeom.mjGEOM_SPHERE, (config.ball_radius, 0, 0), (0, 0, 0),
                        config.ball_rgba, 0)
    geom.mass = config.ball_mass
    geom.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL  # a hollow ball: I = 2/3 m r^2


def _add_robot(spec: mujoco.MjSpec, config: SoccerSceneConfig, team: int, player: int, pose) -> None:
    child = mujoco.MjSpec.from_file(str(OP3.mjcf_path))
    for key in list(child.keys):  # the robot's own keyframe covers one robot; the scene adds its own
        child.delete(key)
    for name in TEAM_COLOUR_GEOMS:
        child.geom(name).rgba = list(config.team_rgba(team))
    if OP3.head_camera is not None:  # image right = the robot's right; image up tilted forward: looking down
        tilt = np.deg2rad(config.head_camera_tilt_deg)
        camera = child.camera(OP3.head_camera)
        camera.alt.xyaxes = [0.0, -1.0, 0.0, float(np.sin(tilt)), 0.0, float(np.cos(tilt))]
        if config.head_camera_fovy_deg:
            camera.fovy = config.head_camera_fovy_deg
    root = child.body(OP3.root_body)
    root.pos = [0.0, 0.0, _QPOS0_HEIGHT]
    x, y, yaw = (float(v) for v in pose)
    frame = spec.worldbody.add_frame(pos=[x, y, 0.0], quat=_yaw_quat(yaw))
    frame.attach_body(root, agent_prefix(team, player), "")


def _pair(spec, geom1, geom2, friction, condim=3):
    spec.add_pair(name=f"{geom1}~{geom2}", geomname1=geom1, geomname2=geom2, condim=condim,
                  friction=list(friction))


def _add_contacts(spec: mujoco.MjSpec, config: SoccerSceneConfig, prefixes) -> None:
    floor = (config.floor_friction, config.floor_friction, 0.005, 0.0001, 0.0001)
    ball = (config.ball_friction, config.ball_friction, 0.005, 0.0001, 0.0001)
    limbs = OP3.arm_geoms + OP3.thigh_geoms + OP3.calf_geoms if config.limb_floor_contacts else ()
    for p in prefixes:
        for geom in OP3.feet_geoms + OP3.body_geoms + limbs:
            _pair(spec, p + geom, FLOOR_GEOM, floor)
    roll = config.ball_rolling_friction
    _pair(spec, BALL, FLOOR_GEOM, (config.ball_friction, config.ball_friction, roll, roll, roll), condim=6)
    for p in prefixes:
        for geom in config.ball_robot_geoms:
            _pair(spec, BALL, p + geom, ball)
    for team in range(2):
        for box in goal_boxes(config, team):
            _pair(spec, BALL, box.name, ball)
    for name, _, _ in walls(config):
        _pair(spec, BALL, name, ball)
    if config.robot_robot_contacts:
        for i, a in enumerate(prefixes):
            for b in prefixes[i + 1:]:
                _pair(spec, a + "torso", b + "torso", floor)
                for fa in OP3.feet_geoms:
                    for fb in OP3.feet_geoms:
                        _pair(spec, a + fa, b + fb, floor)


def soccer_spec(config: SoccerSceneConfig = SoccerSceneConfig()) -> mujoco.MjSpec:
    """The scene as an MjSpec (not compiled; `build_soccer_scene` compiles it and adds the keyframe)."""
    spec = mujoco.MjSpec()
    n = config.players_per_team
    spec.modelname = f"soccer_{n}v{n}"
    robot = mujoco.MjSpec.from_file(str(OP3.mjcf_path))
    for field in ("timestep", "iterations", "ls_iterations", "cone", "integrator", "disableflags", "enableflags"):
        setattr(spec.option, field, getattr(robot.option, field))  # the robot's solver settings (MJX-tuned)
    extent = float(np.hypot(config.field_length / 2 + config.wall_margin, config.field_width / 2 + config.wall_margin))
    spec.stat.extent = extent
    spec.visual.map.znear = config.camera_znear / extent  # MuJoCo scales clip distances by the extent
    spec.visual.map.zfar = config.camera_zfar / extent
    spec.add_texture(name="sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX, builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
                     rgb1=[0.55, 0.7, 0.9], rgb2=[0.2, 0.3, 0.45], width=64, height=64)
    spec.worldbody.add_light(name="sun", pos=[0.0, 0.0, 6.0], dir=[0.0, 0.0, -1.0], diffuse=[0.6, 0.6, 0.6],
                             type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    _add_pitch(spec, config)
    _add_ball(spec, config)
    prefixes = []
    for a, pose in enumerate(kickoff_poses(config)):
        team, player = divmod(a, n)
        _add_robot(spec, config, team, player, pose)
        prefixes.append(agent_prefix(team, player))
    _add_contacts(spec, config, prefixes)
    return spec


def _compile(spec: mujoco.MjSpec, config: SoccerSceneConfig) -> mujoco.MjModel:
    model = spec.compile()
    layout = SoccerLayout.from_model(model)
    spec.add_key(name=KICKOFF_KEY, qpos=list(layout.kickoff_qpos(model, kickoff_poses(config))),
                 ctrl=list(layout.default_ctrl(model)))
    return spec.compile()


def build_soccer_scene(config: SoccerSceneConfig = SoccerSceneConfig()) -> mujoco.MjModel:
    """Compiled soccer model with a 'kickoff' keyframe (robots at their kick-off poses, ball on the spot)."""
    return _compile(soccer_spec(config), config)


def soccer_scene_xml(config: SoccerSceneConfig = SoccerSceneConfig()) -> str:
    """Standalone MJCF text of the scene (for viewers and saved runs; it compiles to the same model)."""
    spec = soccer_spec(config)
    _compile(spec, config)
    return spec.to_xml()
