"""A model-based walk for the OP3: placo's walk pattern generator and whole-body inverse kinematics.

`PlacoWalk` turns a velocity command (vx, vy, yaw rate; robot frame, m/s and rad/s) into joint targets
for the OP3's position servos, in `OP3.joint_names` order, one per control period (OP3_CTRL_DT, 0.025 s):

1. `FootstepsPlannerRepetitive` lays out the next `horizon_steps` footsteps, each displaced by the
   command times the step period (ss + ds duration) from the previous one, clipped to the step limits;
2. `WalkPatternGenerator` plans the centre of mass (a linear inverted pendulum whose ZMP stays in the
   support polygons) and the swing-foot trajectories through them;
3. `KinematicsSolver` + `WalkTasks` follow that plan with the whole body (soft tasks: both feet 6-D,
   CoM, trunk orientation; a joints task holds arms and head at the default pose), integrating
   `ik_substeps` IK steps per control period;
4. the servo targets are the planned joint positions plus a feedforward for the soft PD servos
   (kp 21.1): (gravity torque + kd qd + armature qdd) / kp, partly weighted (see PlacoWalkConfig).

The plan is redone once per step (at the start of each single support) and as soon as possible after
the command changes: `replan_supports` keeps the current support and the swing foot's landing and
re-lays the later steps, `replan` continues the CoM from its current position, velocity and
acceleration, so joint targets stay continuous through command changes (a new command is in effect
from the next-but-one footstep, i.e. after 1 to 2 steps).

Open loop: nothing is measured; the kinematic model (legged/soccer/placo/urdf.py, generated from
assets/robots/op3.xml) is floored on its support foot after each IK step, as in placo's examples.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import placo

from legged.robots.op3 import OP3, OP3_CTRL_DT
from legged.soccer.placo.urdf import op3_urdf_path

UPPER_JOINTS = tuple(n for n in OP3.joint_names if n.startswith("head") or n[2:] in ("sho_pitch", "sho_roll", "el"))
"""Head and arms: held at the default pose."""


@dataclasses.dataclass(frozen=True)
class PlacoWalkConfig:
    """Walk parameters for the OP3 (placo's HumanoidParameters plus the engine's own)."""

    # Timing.
    single_support_duration: float = 0.4
    """Seconds per single support (one swing)."""
    single_support_timesteps: int = 10
    """Pendulum (LIPM) time steps per single support; the other phases scale with it."""
    double_support_ratio: float = 0.2
    """Double support duration / single support duration (rounded to LIPM time steps)."""
    startend_double_support_ratio: float = 1.5
    """Duration of the first (start) double support / single support duration."""
    # Posture.
    com_height: float = 0.23
    """CoM height above the soles while walking, m (default pose: 0.241, knees bent 1.13 rad)."""
    foot_height: float = 0.03
    """Swing foot apex, m (higher or faster swings need knee speeds above the servo's 4.8 rad/s)."""
    foot_rise_ratio: float = 0.0
    """Fraction of the swing spent at the apex plateau (0: the gentlest lift)."""
    trunk_pitch: float = 0.0
    """Trunk (root body) pitch while walking, rad (+ leans forward)."""
    # Feet: the planner's footprint, centred on the sole-centre frames (sites l_foot / r_foot). The real
    # sole is 127 x 78 mm but centred 12.5 mm outboard of the site, so only +-26.5 mm of it lies on each
    # side of the site; the footprint is narrower (placo also refuses steps whose footprints, grown by
    # 1 cm, overlap: feet_spacing - dy >= foot_width + 0.02).
    foot_length: float = 0.12
    """Footprint length (x) the planner keeps the ZMP in, m."""
    foot_width: float = 0.04
    """Footprint width (y) the planner keeps the ZMP in, m."""
    feet_spacing: float = 0.08
    """Lateral distance between the sole centres, m (the default pose has 0.07)."""
    zmp_margin: float = 0.005
    """ZMP kept this far inside the footprint, m."""
    foot_zmp_target_x: float = 0.0
    """Where the ZMP reference lies in the support foot's frame during single support, x (forward), m."""
    foot_zmp_target_y: float = 0.0
    """Where the ZMP reference lies in the support foot's frame during single support, y (left), m."""
    zmp_reference_weight: float = 0.1
    """Weight of following the ZMP reference in the CoM plan (against its jerk)."""
    # Step limits (per step).
    max_dx_forward: float = 0.1
    """Longest forward step, m."""
    max_dx_backward: float = 0.04
    """Longest backward step, m."""
    max_dy: float = 0.025
    """Longest sideways step, m (beyond feet_spacing)."""
    max_dtheta: float = 0.35
    """Largest turn per step, rad."""
    dtheta_spacing: float = 0.02
    """Extra lateral spacing per radian of turn (placo's walk_dtheta_spacing)."""
    # Engine.
    horizon_steps: int = 8
    """Footsteps planned ahead (the plan is redone every step, so the walk never ends)."""
    ctrl_dt: float = OP3_CTRL_DT
    """Period of `step()`, s."""
    ik_substeps: int = 5
    """IK solves per control period (0.005 s each at the default: the physics step)."""
    velocity_limits: bool = True
    """Joint velocity limits in the IK (the URDF's servo speed, 4.8 rad/s)."""
    gravity_feedforward: float = 0.5
    """Add this fraction of the static gravity torques / kp to the servo targets (0: pure kinematics).

    The OP3's servos are soft (kp 21.1 N m/rad): a stance leg holding the body sags by ~0.05-0.1 rad.
    The static torques (placo, support foot fixed; blended between the feet in double support by the
    planned ZMP's position between them) divided by kp pre-load the position servos."""
    velocity_feedforward: float = 1.0
    """Add this fraction of kd * qd / kp (the servo's damping lag, kd / kp = 51 ms) to the targets."""
    inertia_feedforward: float = 0.5
    """Add this fraction of armature * qdd / kp (the rotor inertia, which dominates the legs' own)."""
    kp: float = OP3.kp
    """Servo stiffness the feedforward is divided by, N m/rad."""
    kd: float = OP3.kd
    """Servo damping, N m s/rad."""
    armature: float = 0.045
    """Rotor inertia of every joint in op3.xml, kg m^2."""

    @property
    def step_period(self) -> float:
        """Seconds per footstep (single + double support)."""
        dt = self.single_support_duration / self.single_support_timesteps
        return self.single_support_duration + round(self.double_support_ratio * self.single_support_timesteps) * dt


def static_torques(robot: placo.HumanoidRobot, foot_frame: str) -> np.ndarray:
    """Static joint torques holding the robot's posture on `foot_frame` alone (N m, OP3.joint_names order)."""
    tau = robot.static_gravity_compensation_torques_dict(foot_frame)
    return np.array([tau[n] for n in OP3.joint_names])


def split_static_torques(robot: placo.HumanoidRobot, point, left, right) -> np.ndarray:
    """Static joint torques in double support: the two one-foot solutions blended by where `point` (xy)
    lies between the sole centres `left` and `right` (a statically indeterminate split, approximated)."""
    axis = left[:2] - right[:2]
    w_left = float(np.clip(np.dot(point[:2] - right[:2], axis) / max(np.dot(axis, axis), 1e-9), 0.0, 1.0))
    return w_left * static_torques(robot, "left_foot") + (1 - w_left) * static_torques(robot, "right_foot")


def servo_targets(config: PlacoWalkConfig, q_before, q, q_after, gravity) -> np.ndarray:
    """Servo targets for planned joint positions q (any leading shape): q plus the feedforward a PD servo
    needs to hold them, (gravity torque + kd qd + armature qdd) / kp, each term scaled by its config
    fraction; qd and qdd are central differences over the neighbours one control period away."""
    c = config
    qd = (q_after - q_before) / (2 * c.ctrl_dt)
    qdd = (q_after - 2 * q + q_before) / c.ctrl_dt**2
    tau = (c.gravity_feedforward * gravity + c.velocity_feedforward * c.kd * qd
           + c.inertia_feedforward * c.armature * qdd)
    return q + tau / c.kp


class PlacoWalk:
    """Velocity command -> OP3 joint targets, one control period at a time (see the module doc)."""

    def __init__(self, config: PlacoWalkConfig = PlacoWalkConfig(), urdf_path=None):
        self.config = config
        self.robot = placo.HumanoidRobot(str(urdf_path or op3_urdf_path()))
        self.parameters = self._parameters(config)
        self.solver = placo.KinematicsSolver(self.robot)
        self.solver.enable_velocity_limits(config.velocity_limits)
        self.solver.dt = config.ctrl_dt / config.ik_substeps
        self.tasks = placo.WalkTasks()
        self.tasks.initialize_tasks(self.solver, self.robot)
        self.upper_task = self.solver.add_joints_task()
        default = dict(zip(OP3.joint_names, OP3.default_pose))
        self.upper_task.set_joints({n: default[n] for n in UPPER_JOINTS})
        self.upper_task.configure("upper_body", "soft", 1.0)
        self.planner = placo.FootstepsPlannerRepetitive(self.parameters)
        self.walk = placo.WalkPatternGenerator(self.robot, self.parameters)
        self.reset()

    @staticmethod
    def _parameters(c: PlacoWalkConfig) -> placo.HumanoidParameters:
        p = placo.HumanoidParameters()
        p.single_support_duration = c.single_support_duration
        p.single_support_timesteps = c.single_support_timesteps
        p.double_support_ratio = c.double_support_ratio
        p.startend_double_support_ratio = c.startend_double_support_ratio
        p.walk_com_height = c.com_height
        p.walk_foot_height = c.foot_height
        p.walk_foot_rise_ratio = c.foot_rise_ratio
        p.walk_trunk_pitch = c.trunk_pitch
        p.foot_length = c.foot_length
        p.foot_width = c.foot_width
        p.feet_spacing = c.feet_spacing
        p.zmp_margin = c.zmp_margin
        p.foot_zmp_target_x = c.foot_zmp_target_x
        p.foot_zmp_target_y = c.foot_zmp_target_y
        p.zmp_reference_weight = c.zmp_reference_weight
        p.walk_max_dx_forward = c.max_dx_forward
        p.walk_max_dx_backward = c.max_dx_backward
        p.walk_max_dy = c.max_dy
        p.walk_max_dtheta = c.max_dtheta
        p.walk_dtheta_spacing = c.dtheta_spacing
        return p

    # ------------------------------------------------------------------------------------------------
    def reset(self, command=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Stand at the walk's initial posture (feet at the origin, CoM at com_height) and plan a start.

        Returns the joint targets of that posture (OP3.joint_names order): hold them before walking.
        """
        c = self.config
        for name, q in zip(OP3.joint_names, OP3.default_pose):
            self.robot.set_joint(name, q)
        self.robot.update_kinematics()
        self.robot.ensure_on_floor()
        # Converge the IK on the initial posture (centred between the feet, trunk at trunk_pitch).
        T_world_left = np.eye(4)
        T_world_left[1, 3] = c.feet_spacing / 2
        self.tasks.reach_initial_pose(T_world_left, c.feet_spacing, c.com_height, c.trunk_pitch)
        self.t = 0.0
        self.command = np.asarray(command, dtype=float)
        self._configure_planner()
        footsteps = self.planner.plan(placo.HumanoidRobot_Side.left,
                                      placo.flatten_on_floor(self.robot.get_T_world_left()),
                                      placo.flatten_on_floor(self.robot.get_T_world_right()))
        supports = placo.FootstepsPlanner.make_supports(footsteps, self.t, True,
                                                        self.parameters.has_double_support(), True)
        self.trajectory = self.walk.plan(supports, self.robot.com_world(), self.t)
        self.last_replan = self.t
        self._replan_due = False
        self._finishing = False
        self.replans = 0
        # The IK runs one control period ahead of the targets it returns, so that joint velocity and
        # acceleration (feedforward) are central differences: buffer of (q, gravity torques).
        q, tau = self.joint_positions(), self.gravity_torques()
        self._buffer = [(q, tau)] * 3
        return self.joint_targets()

    def _configure_planner(self) -> None:
        vx, vy, wz = self.command
        T = self.config.step_period
        self.planner.configure(vx * T, vy * T, wz * T, self.config.horizon_steps)

    def set_command(self, vx: float, vy: float = 0.0, yaw_rate: float = 0.0) -> None:
        """New velocity command (robot frame); replanned at the next single support at the latest."""
        command = np.array([vx, vy, yaw_rate], dtype=float)
        if not self._finishing and not np.allclose(command, self.command):
            self.command = command
            self._configure_planner()
            self._replan_due = True

    def finish(self) -> None:
        """End the walk: replan once, as soon as possible, with no further footsteps (the swing about to
        start is cancelled) and then never again: placo's end double support brings the CoM to rest
        between the feet. `set_command` is ignored afterwards; `reset` walks again."""
        self.planner.configure(0.0, 0.0, 0.0, 0)
        self._replan_due = True
        self._finishing = True

    def _maybe_replan(self) -> None:
        due = self._replan_due or self.t - self.last_replan >= self.config.step_period - 1e-9
        if due and self.walk.can_replan_supports(self.trajectory, self.t):
            supports = self.walk.replan_supports(self.planner, self.trajectory, self.t, self.last_replan)
            self.trajectory = self.walk.replan(supports, self.trajectory, self.t)
            self.last_replan = np.inf if self._finishing else self.t
            self._replan_due = False
            self.replans += 1

    def step(self, command=None) -> np.ndarray:
        """Advance one control period (optionally with a new command); return the joint targets."""
        if command is not None:
            self.set_command(*command)
        self._maybe_replan()
        dt = self.config.ctrl_dt / self.config.ik_substeps
        for _ in range(self.config.ik_substeps):
            self.t += dt
            self.tasks.update_tasks_from_trajectory(self.trajectory, self.t)
            self.robot.update_kinematics()
            self.solver.solve(True)
            if not self.trajectory.support_is_both(self.t):
                self.robot.update_support_side(str(self.trajectory.support_side(self.t)))
                self.robot.ensure_on_floor()
        self.robot.update_kinematics()
        self._buffer = self._buffer[1:] + [(self.joint_positions(), self.gravity_torques())]
        return self.joint_targets()

    def joint_positions(self) -> np.ndarray:
        """Current joint positions of the kinematic model, OP3.joint_names order."""
        return np.array([self.robot.get_joint(n) for n in OP3.joint_names])

    def gravity_torques(self) -> np.ndarray:
        """Static joint torques holding the current posture (N m, OP3.joint_names order).

        Single support: the support foot fixed. Double support: the two one-foot solutions blended by
        where the planned ZMP lies between the feet (a statically indeterminate split, approximated).
        """
        support = self.support()
        if support != "both":
            return static_torques(self.robot, f"{support}_foot")
        point = self.trajectory.get_p_world_ZMP(self.t, np.sqrt(9.81 / self.config.com_height))
        return split_static_torques(self.robot, point, self.robot.get_T_world_left()[:3, 3],
                                    self.robot.get_T_world_right()[:3, 3])

    def joint_targets(self) -> np.ndarray:
        """Servo targets for the current control period, OP3.joint_names order.

        The planned joint positions (one period behind the IK, see `reset`) plus the feedforward that a
        PD servo needs to hold them: (gravity torque + kd qd + armature qdd) / kp, each term scaled by
        its config fraction.
        """
        (q0, _), (q1, tau1), (q2, _) = self._buffer
        return servo_targets(self.config, q0, q1, q2, tau1)

    # Diagnostics -------------------------------------------------------------------------------------
    def support(self) -> str:
        """'both', 'left' or 'right': the planned support at the current time."""
        if self.trajectory.support_is_both(self.t):
            return "both"
        return str(self.trajectory.support_side(self.t))
