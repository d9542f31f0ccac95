"""The soccer scene composed in code with MjSpec: pitch, lines, goals, ball and OP3 teams.

Every robot is a namespaced copy of the robot model (assets/robots/op3.xml, or another model of the OP3 that
legged.robots.models prepared: `SoccerConfig.robot_model`) attached with `MjsFrame.attach_body` (prefix 'home0/',
'away1/', ...: its joints, actuators, sensors, sites and cameras are prefixed too), tinted with its team colour and
placed at its kick-off pose. Contacts with the world are explicit `<pair>`s (the project model's geoms keep
contype = conaffinity = 0, so MJX evaluates just these; a model whose geoms collide by contype, as Menagerie's,
keeps its self-contacts, each robot on collision bits of its own, and touches the other robots only with
`robot_robot_contacts`), each the contact MuJoCo gives the robot's own geom (its condim, solref, solimp, margin:
legged.worlds.mjcf.pair_attributes) with the scene's sliding friction:

- each robot's feet, torso and head with the floor (torso and head: fallen robots lie on the floor), and
  with `limb_floor_contacts` its arms, thighs and shins too (what a robot getting up pushes with);
- the ball with the floor (condim 6: rolling friction slows it like grass), with each robot's
  `ball_robot_geoms` (feet and shins: what kicks), with every goal box and with the four walls;
- optionally (`leg_contacts`) each robot's legs with each other: thigh, shin and foot of one leg with those of the
  other (a model with self-contacts of its own, as Menagerie's OP3, keeps its own instead);
- optionally (`robot_robot_contacts`) torso-torso and foot-foot between every two robots.

Geom groups: 0 floor, goals and ball (seen and physical); 1 painted lines (thin boxes, seen only; the
ray camera draws them analytically from `pitch_lines`); 2 robot visuals (OP3 convention); 3 robot
collision geoms and the invisible walls (hidden by MuJoCo's renderer by default).
"""

from __future__ import annotations

import itertools

import mujoco
import numpy as np

from legged.robots.op3 import OP3
from legged.robots.spec import RobotSpec
from legged.soccer.config import SoccerSceneConfig
from legged.soccer.layout import BALL, FLOOR_GEOM, TEAMS, SoccerLayout
from legged.soccer.pitch import (
    goal_boxes,
    kickoff_poses,
    line_names,
    pitch_lines,
    walls,
)
from legged.worlds.mjcf import pair_attributes

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
    """Quaternion turning +z onto a horizontal unit `normal` (a wall plane's normal): `mujoco.mju_quatZ2Vec`."""
    quat = np.zeros(4)
    mujoco.mju_quatZ2Vec(quat, np.asarray(normal, dtype=np.float64))
    return quat.tolist()


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


def _team_geoms(child: mujoco.MjSpec, robot: RobotSpec) -> list:
    """The visual geoms painted in the team colour: TEAM_COLOUR_GEOMS, or on a model without them the visual geoms
    of the root body (a model's torso shell)."""
    named = [child.geom(n) for n in TEAM_COLOUR_GEOMS if child.geom(n) is not None]
    if named:
        return named
    return [g for g in child.body(robot.root_body).geoms
            if not (g.contype or g.conaffinity) and g.group != HIDDEN_GROUP]


_BITS_PER_ROBOT = 8
"""Collision bits each robot's own contype / conaffinity keep when robots do not touch (see `_own_bits`)."""


def _own_bits(child: mujoco.MjSpec, agent: int, n_agents: int) -> None:
    """Move a robot's contype / conaffinity bits (a model whose geoms collide by them, as Menagerie's) to bits of its
    own, so that it keeps its self-contacts and passes through the other robots as the scene's robots do without
    `robot_robot_contacts`. The file's bits must fit in `_BITS_PER_ROBOT` (ValueError otherwise)."""
    used = [g for g in child.geoms if g.contype or g.conaffinity]
    if not used:
        return
    widest = max(max(g.contype, g.conaffinity) for g in used)
    if widest >> _BITS_PER_ROBOT or widest << (_BITS_PER_ROBOT * (n_agents - 1)) >= 2 ** 31:
        raise ValueError(f"the robot model's contype / conaffinity bits do not fit in {_BITS_PER_ROBOT} bits for "
                         f"{n_agents} robots; set robot_robot_contacts or use a model with fewer collision bits")
    for g in used:
        g.contype, g.conaffinity = g.contype << (_BITS_PER_ROBOT * agent), g.conaffinity << (_BITS_PER_ROBOT * agent)


def _add_robot(spec: mujoco.MjSpec, config: SoccerSceneConfig, robot: RobotSpec, team: int, player: int,
               pose) -> None:
    child = mujoco.MjSpec.from_file(str(robot.mjcf_path))
    for key in list(child.keys):  # the robot's own keyframe covers one robot; the scene adds its own
        child.delete(key)
    if not config.robot_robot_contacts:
        _own_bits(child, team * config.players_per_team + player, 2 * config.players_per_team)
    for geom in _team_geoms(child, robot):
        geom.rgba, geom.material = list(config.team_rgba(team)), ""
    if robot.head_camera is not None:  # image right = the robot's right; image up tilted forward: looking down
        tilt = np.deg2rad(config.head_camera_tilt_deg)
        camera = child.camera(robot.head_camera)
        camera.alt.xyaxes = [0.0, -1.0, 0.0, float(np.sin(tilt)), 0.0, float(np.cos(tilt))]
        if config.head_camera_fovy_deg:
            camera.fovy = config.head_camera_fovy_deg
    root = child.body(robot.root_body)
    root.pos = [0.0, 0.0, _QPOS0_HEIGHT]
    x, y, yaw = (float(v) for v in pose)
    frame = spec.worldbody.add_frame(pos=[x, y, 0.0], quat=_yaw_quat(yaw))
    frame.attach_body(root, agent_prefix(team, player), "")


def _pair(spec, geom1, geom2, friction, condim=3):
    spec.add_pair(name=f"{geom1}~{geom2}", geomname1=geom1, geomname2=geom2, condim=condim,
                  friction=list(friction))


def _robot_pair(spec, alone: mujoco.MjModel, prefix: str, geom: str, other: str, friction: float):
    """The pair of robot geom `prefix + geom` with a world geom: the contact MuJoCo gives the robot model's own geom
    against a plain one (legged.worlds.mjcf.pair_attributes), with sliding `friction`."""
    spec.add_pair(name=f"{prefix + geom}~{other}", geomname1=prefix + geom, geomname2=other,
                  **pair_attributes(alone, geom, friction))


def _add_contacts(spec: mujoco.MjSpec, config: SoccerSceneConfig, robot: RobotSpec, prefixes) -> None:
    alone = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    floor = (config.floor_friction, config.floor_friction, 0.005, 0.0001, 0.0001)
    ball = (config.ball_friction, config.ball_friction, 0.005, 0.0001, 0.0001)
    limbs = robot.arm_geoms + robot.thigh_geoms + robot.calf_geoms if config.limb_floor_contacts else ()
    for p in prefixes:
        for geom in robot.feet_geoms + robot.body_geoms + limbs:
            _robot_pair(spec, alone, p, geom, FLOOR_GEOM, config.floor_friction)
    roll = config.ball_rolling_friction
    _pair(spec, BALL, FLOOR_GEOM, (config.ball_friction, config.ball_friction, roll, roll, roll), condim=6)
    for p in prefixes:
        for geom in robot.geoms_of(config.ball_robot_geoms):
            _robot_pair(spec, alone, p, geom, BALL, config.ball_friction)
    for team in range(2):
        for box in goal_boxes(config, team):
            _pair(spec, BALL, box.name, ball)
    for name, _, _ in walls(config):
        _pair(spec, BALL, name, ball)
    # a model whose geoms collide by contype / conaffinity (Menagerie's) already has its self- and robot-robot contacts
    own_contacts = bool(np.any(alone.geom_contype | alone.geom_conaffinity))
    if config.leg_contacts and not own_contacts:
        legs = [robot.geoms_of(leg) for leg in zip(OP3.thigh_geoms, OP3.calf_geoms, OP3.feet_geoms)]  # per leg
        for p in prefixes:
            for leg, other in itertools.combinations(legs, 2):
                for a, b in itertools.product(leg, other):
                    _pair(spec, p + a, p + b, floor)
    if config.robot_robot_contacts and not own_contacts:
        for i, a in enumerate(prefixes):
            for b in prefixes[i + 1:]:
                for ta in robot.geoms_of(("torso",)):
                    for tb in robot.geoms_of(("torso",)):
                        _pair(spec, a + ta, b + tb, floor)
                for fa in robot.feet_geoms:
                    for fb in robot.feet_geoms:
                        _pair(spec, a + fa, b + fb, floor)


def soccer_spec(config: SoccerSceneConfig = SoccerSceneConfig(), robot: RobotSpec = OP3) -> mujoco.MjSpec:
    """The scene as an MjSpec (not compiled; `build_soccer_scene` compiles it and adds the keyframe)."""
    spec = mujoco.MjSpec()
    n = config.players_per_team
    spec.modelname = f"soccer_{n}v{n}"
    own = mujoco.MjSpec.from_file(str(robot.mjcf_path))
    for field in ("timestep", "iterations", "ls_iterations", "cone", "integrator", "disableflags", "enableflags",
                  "noslip_iterations", "impratio", "tolerance", "ls_tolerance"):
        setattr(spec.option, field, getattr(own.option, field))  # the robot model's solver settings
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
        _add_robot(spec, config, robot, team, player, pose)
        prefixes.append(agent_prefix(team, player))
    _add_contacts(spec, config, robot, prefixes)
    return spec


def _compile(spec: mujoco.MjSpec, config: SoccerSceneConfig, robot: RobotSpec) -> mujoco.MjModel:
    model = spec.compile()
    layout = SoccerLayout.from_model(model, robot)
    spec.add_key(name=KICKOFF_KEY, qpos=list(layout.kickoff_qpos(model, kickoff_poses(config), robot)),
                 ctrl=list(layout.default_ctrl(model, robot)))
    return spec.compile()


def build_soccer_scene(config: SoccerSceneConfig = SoccerSceneConfig(), robot: RobotSpec = OP3) -> mujoco.MjModel:
    """Compiled soccer model with a 'kickoff' keyframe (robots at their kick-off poses, ball on the spot); `robot`:
    the OP3 model every player uses (legged.robots.models.robot_model prepares another than the project's)."""
    return _compile(soccer_spec(config, robot), config, robot)


def soccer_scene_xml(config: SoccerSceneConfig = SoccerSceneConfig(), robot: RobotSpec = OP3) -> str:
    """Standalone MJCF text of the scene (for viewers and saved runs; it compiles to the same model)."""
    spec = soccer_spec(config, robot)
    _compile(spec, config, robot)
    return spec.to_xml()
