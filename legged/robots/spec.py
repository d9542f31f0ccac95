"""Robot specifications: everything an environment needs to know about a robot, as data."""

from __future__ import annotations

import dataclasses
from pathlib import Path

ASSETS_DIR = Path(__file__).resolve().parents[2] / "assets"


@dataclasses.dataclass(frozen=True)
class RobotSpec:
    """A legged robot as the environments see it; adding a robot means adding one of these."""

    name: str
    """Short name used in task names and logs."""
    mjcf_path: Path
    """MJCF file of the robot alone (no world); the scene builder adds floor, ceiling and contacts."""
    root_body: str
    """Body carrying the free joint (the base)."""
    joint_names: tuple[str, ...]
    """Actuated joints in policy order (the order of actions and joint observations)."""
    default_pose: tuple[float, ...]
    """Joint angles of the default standing pose, radians, in `joint_names` order."""
    kp: float
    """Proportional gain of the joint PD servos, N m / rad."""
    kd: float
    """Derivative gain of the joint PD servos, N m s / rad."""
    action_scale: float
    """Joint target = default pose + action_scale * action."""
    feet_geoms: tuple[str, ...]
    """Foot collision geoms (Go1: spheres, OP3: boxes), in leg order."""
    feet_sites: tuple[str, ...]
    """Foot sites, in leg order."""
    body_geoms: tuple[str, ...]
    """Trunk collision geoms; a contact on them counts as a body collision."""
    thigh_geoms: tuple[str, ...]
    """Thigh collision geoms."""
    calf_geoms: tuple[str, ...]
    """Calf collision geoms."""
    imu_site: str
    """Site of the IMU (gyro, velocimeter) on the base."""
    body_box_half_extents: tuple[float, float, float]
    """Half sizes of the trunk box (x, y, z) used by planners and clearance checks, metres."""
    standing_height: float
    """Base height above flat ground at the default pose, metres (measured, see tests)."""
    body_height_range: tuple[float, float]
    """Lowest and highest height of the body above the floor under each foot that the legs can hold (planners)."""
    arm_geoms: tuple[str, ...] = ()
    """Arm collision geoms (humanoids; empty for quadrupeds)."""
    head_camera: str | None = None
    """MJCF camera on the head that sees what the robot's own camera sees (None: the robot has none)."""
    motor_speeds: tuple[float, ...] = ()
    """Free speed of each joint's motor at the joint, rad/s, in `joint_names` order: its torque-speed line runs from
    the actuator's force limit at rest to 0 at this speed (EnvConfig.motor_curve; empty: no curve)."""
    differences: tuple[tuple[str, str], ...] = ()
    """(quantity, reason) for each dynamics quantity in which `mjcf_path` differs from MuJoCo Menagerie's model of the
    robot: joint_damping, joint_armature, joint_frictionloss, foot_contact, body_contact, actuator_gains,
    force_limits, solver, timestep (the fidelity tests check that exactly these differ)."""
    source: str = "project"
    """Which model of the robot `mjcf_path` holds: project, a reference name or a user's file (legged.robots.models)."""
    timestep: float | None = None
    """Physics step the model needs, seconds (None: the task's `sim_dt`)."""
    body_slots: tuple[int, ...] = ()
    """For a model whose trunk has other collision geoms than the project's: the index into the project's
    `body_geoms` each of `body_geoms` stands for (empty: one each), so body contact observations keep their size."""
    body_slot_count: int = 0
    """Number of those trunk contact slots (0: one per `body_geoms`)."""
    parts: tuple[tuple[str, str], ...] = ()
    """For a model other than the project's: (geom, project geom it stands for) for each of its geoms in the part
    lists above (several may stand for one: Menagerie's OP3 has two sole boxes per foot); empty: each is its own."""

    @property
    def num_joints(self) -> int:
        """Number of actuated joints (= action size)."""
        return len(self.joint_names)

    @property
    def num_body_slots(self) -> int:
        """Trunk contact slots of the observations (the project model's trunk geoms)."""
        return self.body_slot_count or len(self.body_geoms)

    def geoms_of(self, names) -> tuple[str, ...]:
        """This model's geoms that stand for the project model's geoms `names`, in that order."""
        if not self.parts:
            return tuple(names)
        return tuple(g for name in names for g, part in self.parts if part == name)

    @property
    def collision_geoms(self) -> tuple[str, ...]:
        """All geoms whose contact with the world is a penalised collision (not the feet)."""
        return self.body_geoms + self.arm_geoms + self.thigh_geoms + self.calf_geoms
