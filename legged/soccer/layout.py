"""Index arrays into a compiled soccer model: where each agent's state, actuators, camera and geoms live.

`SoccerLayout.from_model` reads everything from the names in the model (`home0/`, `away1/`, `ball`,
`goal_home/...`), so a layout always matches the model it was made from, whether the model came from
`build_soccer_scene` or from a saved XML file. Agent order: home players first (home0, home1), then away.
"""

from __future__ import annotations

import dataclasses
import re

import mujoco
import numpy as np

from legged.robots.op3 import OP3
from legged.robots.spec import RobotSpec

TEAMS = ("home", "away")
"""Team names, in agent order: home players first, then away players. Home defends the goal at -x."""
FLOOR_GEOM = "floor"
BALL = "ball"
"""Name of the ball's body, free joint and geom."""
_AGENT = re.compile(rf"^({'|'.join(TEAMS)})(\d+)/$")


def _ids(model: mujoco.MjModel, obj: mujoco.mjtObj, names) -> np.ndarray:
    out = []
    for name in names:
        i = mujoco.mj_name2id(model, obj, name)
        if i < 0:
            raise ValueError(f"the model has no {obj.name.removeprefix('mjOBJ_').lower()} named {name!r}")
        out.append(i)
    return np.array(out, dtype=np.int32)


def _driving(model: mujoco.MjModel, joints: np.ndarray, prefix: str, robot: RobotSpec) -> np.ndarray:
    """Ids of the actuators driving `joints` (a model's actuators are found by their joint, whatever their names)."""
    joint_actuated = (model.actuator_trntype == mujoco.mjtTrn.mjTRN_JOINT)
    out = []
    for j, name in zip(joints, robot.joint_names):
        found = np.nonzero(joint_actuated & (model.actuator_trnid[:, 0] == j))[0]
        if len(found) != 1:
            raise ValueError(f"the model has {len(found)} actuators on joint {prefix + name!r}; one is needed")
        out.append(found[0])
    return np.array(out, dtype=np.int32)


@dataclasses.dataclass(frozen=True, eq=False)
class SoccerLayout:
    """Per-agent indices into one compiled soccer model (numpy arrays: static under `jax.jit`; compared and
    hashed by identity, so a layout can be a static argument or closed over)."""

    prefixes: tuple[str, ...]
    """Name prefix of each agent ('home0/', ..., 'away0/', ...), in agent order."""
    team: np.ndarray
    """Team of each agent, [n_agents]: 0 home (defends -x), 1 away (defends +x)."""
    root_qpos_adr: np.ndarray
    """qpos address of each agent's free joint (position 3, then quaternion 4), [n_agents]."""
    root_dof_adr: np.ndarray
    """qvel address of each agent's free joint (linear 3, then angular 3, local-frame angular), [n_agents]."""
    joint_qpos_adr: np.ndarray
    """qpos addresses of the robot's joints in RobotSpec.joint_names order, [n_agents, n_joints]."""
    joint_dof_adr: np.ndarray
    """qvel addresses of the same joints, [n_agents, n_joints]."""
    actuator_ids: np.ndarray
    """Actuator ids in RobotSpec.joint_names order, [n_agents, n_joints] (ctrl indices)."""
    torso_body: np.ndarray
    """Body id of each agent's root (torso) body, [n_agents]."""
    head_camera: np.ndarray
    """Camera id of each agent's head camera, [n_agents]."""
    imu_site: np.ndarray
    """Site id of each agent's IMU, [n_agents]."""
    gyro_adr: np.ndarray
    """sensordata address of each agent's gyro (3 values), [n_agents]."""
    velocimeter_adr: np.ndarray
    """sensordata address of each agent's local linear velocity (3 values), [n_agents]."""
    feet_geoms: np.ndarray
    """Foot collision geom ids in RobotSpec.feet_geoms order, [n_agents, n_feet]."""
    geom_agent: np.ndarray
    """Agent owning each geom of the model, -1 for the world and the ball, [ngeom]."""
    ball_body: int
    """Body id of the ball."""
    ball_geom: int
    """Geom id of the ball."""
    ball_qpos_adr: int
    """qpos address of the ball's free joint."""
    ball_dof_adr: int
    """qvel address of the ball's free joint."""
    floor_geom: int
    """Geom id of the floor plane."""
    goal_geoms: np.ndarray
    """Geom ids of each goal's posts, crossbar and nets, [2, 7]: row 0 home's goal (-x), row 1 away's (+x)."""
    line_geoms: np.ndarray
    """Geom ids of the painted lines (visual only), in `pitch_lines` order."""
    wall_geoms: np.ndarray
    """Geom ids of the invisible boundary walls (planes that keep the ball in)."""
    robot_joint_names: tuple[str, ...]
    """Unprefixed joint names, the order of the per-agent joint columns."""

    @property
    def n_agents(self) -> int:
        """Robots on the pitch."""
        return len(self.prefixes)

    @property
    def players_per_team(self) -> int:
        """Robots per team."""
        return self.n_agents // 2

    @classmethod
    def from_model(cls, model: mujoco.MjModel, robot: RobotSpec = OP3) -> SoccerLayout:
        """Layout of a compiled soccer model (raises ValueError naming whatever is missing)."""
        found = []
        for j in range(model.njnt):
            name = model.joint(j).name
            if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE and name.endswith("/root"):
                match = _AGENT.match(name[: -len("root")])
                if match:
                    found.append((TEAMS.index(match.group(1)), int(match.group(2)), name[: -len("root")]))
        found.sort()
        if not found:
            raise ValueError("the model has no soccer agents (free joints named 'home0/root', 'away0/root', ...)")
        per_team = [sum(1 for t, _, _ in found if t == team) for team in range(2)]
        if per_team[0] != per_team[1]:
            raise ValueError(f"teams differ in size: home {per_team[0]}, away {per_team[1]}")
        prefixes = tuple(p for _, _, p in found)
        J, O = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj
        roots = np.stack([_ids(model, J, [p + "root"]) for p in prefixes])[:, 0]
        joints = np.stack([_ids(model, J, [p + n for n in robot.joint_names]) for p in prefixes])
        actuators = np.stack([_driving(model, row, p, robot) for p, row in zip(prefixes, joints)])
        torso = _ids(model, O.mjOBJ_BODY, [p + robot.root_body for p in prefixes])
        if robot.head_camera is None:
            raise ValueError(f"robot {robot.name!r} has no head camera")
        sensors = {s: _ids(model, O.mjOBJ_SENSOR, [p + s for p in prefixes]) for s in ("gyro", "local_linvel")}
        geom_agent = np.full(model.ngeom, -1, dtype=np.int32)
        root_of_geom = model.body_rootid[model.geom_bodyid]
        for a, body in enumerate(torso):
            geom_agent[root_of_geom == body] = a
        ball_joint = _ids(model, J, [BALL])[0]
        geom_names = [model.geom(g).name for g in range(model.ngeom)]
        goals = [[g for g, n in enumerate(geom_names) if n.startswith(f"goal_{team}/")] for team in TEAMS]
        if len(goals[0]) != len(goals[1]) or not goals[0]:
            raise ValueError(f"the model's goals are incomplete: {len(goals[0])} and {len(goals[1])} goal geoms")
        return cls(
            prefixes=prefixes,
            team=np.array([t for t, _, _ in found], dtype=np.int32),
            root_qpos_adr=model.jnt_qposadr[roots].astype(np.int32),
            root_dof_adr=model.jnt_dofadr[roots].astype(np.int32),
            joint_qpos_adr=model.jnt_qposadr[joints].astype(np.int32),
            joint_dof_adr=model.jnt_dofadr[joints].astype(np.int32),
            actuator_ids=actuators,
            torso_body=torso,
            head_camera=_ids(model, O.mjOBJ_CAMERA, [p + robot.head_camera for p in prefixes]),
            imu_site=_ids(model, O.mjOBJ_SITE, [p + robot.imu_site for p in prefixes]),
            gyro_adr=model.sensor_adr[sensors["gyro"]].astype(np.int32),
            velocimeter_adr=model.sensor_adr[sensors["local_linvel"]].astype(np.int32),
            feet_geoms=np.stack([_ids(model, O.mjOBJ_GEOM, [p + g for g in robot.feet_geoms]) for p in prefixes]),
            geom_agent=geom_agent,
            ball_body=int(_ids(model, O.mjOBJ_BODY, [BALL])[0]),
            ball_geom=int(_ids(model, O.mjOBJ_GEOM, [BALL])[0]),
            ball_qpos_adr=int(model.jnt_qposadr[ball_joint]),
            ball_dof_adr=int(model.jnt_dofadr[ball_joint]),
            floor_geom=int(_ids(model, O.mjOBJ_GEOM, [FLOOR_GEOM])[0]),
            goal_geoms=np.array(goals, dtype=np.int32),
            line_geoms=np.array([g for g, n in enumerate(geom_names) if n.startswith("line/")], dtype=np.int32),
            wall_geoms=np.array([g for g, n in enumerate(geom_names) if n.startswith("wall/")], dtype=np.int32),
            robot_joint_names=tuple(robot.joint_names),
        )

    def agent_geoms(self, agent: int) -> np.ndarray:
        """Geom ids (visual and collision) of one agent's robot."""
        return np.nonzero(self.geom_agent == agent)[0].astype(np.int32)

    def kickoff_qpos(self, model: mujoco.MjModel, poses: np.ndarray, robot: RobotSpec = OP3) -> np.ndarray:
        """Full qpos with every robot at its (x, y, yaw) pose in its default stance and the ball on the spot."""
        poses = np.asarray(poses, dtype=np.float64)
        if poses.shape != (self.n_agents, 3):
            raise ValueError(f"poses must have shape ({self.n_agents}, 3), got {poses.shape}")
        qpos = model.qpos0.copy()
        ball_r = float(model.geom_size[self.ball_geom, 0])
        qpos[self.ball_qpos_adr: self.ball_qpos_adr + 7] = (0.0, 0.0, ball_r, 1.0, 0.0, 0.0, 0.0)
        for a, (x, y, yaw) in enumerate(poses):
            adr = self.root_qpos_adr[a]
            qpos[adr: adr + 7] = (x, y, robot.standing_height, np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2))
            qpos[self.joint_qpos_adr[a]] = robot.default_pose
        return qpos

    def default_ctrl(self, model: mujoco.MjModel, robot: RobotSpec = OP3) -> np.ndarray:
        """ctrl that holds every robot at its default pose (the actuators are PD position servos)."""
        ctrl = np.zeros(model.nu)
        for a in range(self.n_agents):
            ctrl[self.actuator_ids[a]] = robot.default_pose
        return ctrl
