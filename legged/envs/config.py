"""Configuration dataclasses shared by all environments."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class RandomizationConfig:
    """Per-episode domain randomisation of the dynamics (sampled at reset, fixed for the episode)."""

    enabled: bool = False
    """Switch for the whole group."""
    friction: tuple[float, float] = (0.4, 1.25)
    """Range of the sliding friction of every contact pair."""
    link_mass_scale: tuple[float, float] = (0.9, 1.1)
    """Range of the scale applied to each link mass independently."""
    base_mass_offset: tuple[float, float] = (-1.0, 2.0)
    """Range of the mass added to the trunk, kg (payload)."""
    com_offset: float = 0.03
    """Trunk centre-of-mass shift, uniform in +-this per axis, metres."""
    motor_strength: tuple[float, float] = (0.9, 1.1)
    """Range of the scale of each motor's torque (gain and bias of its PD servo)."""
    kp_scale: tuple[float, float] = (0.9, 1.1)
    """Range of the scale of the proportional gain (all joints together)."""
    kd_scale: tuple[float, float] = (0.75, 1.25)
    """Range of the scale of the derivative gain (all joints together)."""
    joint_damping: tuple[float, float] | None = None
    """Range of each actuated joint's passive damping, N m s/rad, drawn per joint (None: the model's own)."""
    joint_armature: tuple[float, float] | None = None
    """Range of each actuated joint's armature (rotor inertia), kg m^2, drawn per joint (None: the model's own)."""
    joint_frictionloss: tuple[float, float] | None = None
    """Range of each actuated joint's dry friction, N m, drawn per joint (None: the model's own)."""
    joint_spread: float | None = None
    """How the joint ranges above are drawn: None draws each joint on its own; a number draws one value per robot
    from the range and spreads it over the joints by a factor uniform in 1 +- this (clipped to the range), so that
    robots whose joints are all low (or all high) are drawn, as real and reference models are."""
    contact_softness: tuple[float, float] | None = None
    """Range of the feet's contact softness s: solimp = (1 - s) * MuJoCo's default + s * SOFT_SOLIMP, from the plain
    contact (0) to the soft feet of MuJoCo Menagerie's Go1 (1) (None: the model's own)."""
    contact_timeconst: tuple[float, float] | None = None
    """Range of the feet's contact time constant (solref[0]), seconds (None: the model's own)."""
    contact_margin: tuple[float, float] | None = None
    """Range of the feet's contact margin, metres (None: the model's own)."""
    contact_spin: tuple[float, float] | None = None
    """Range of the scale of the feet's torsional and rolling friction (the condim-6 terms; MuJoCo's mix for the
    robot's foot: Go1 0.02 and 0.01 m): with it set the feet's pairs with the floor are condim 6, and 0 resists no
    spin or roll, as a condim-3 contact (the project's and Playground's Go1), 1 as Menagerie's condim-6 feet; a
    static contact dimension with a drawn coefficient, so MJX keeps one model shape (None: the model's own contact)."""
    elliptic_share: float | None = None
    """Share of robots whose contacts the solver treats with elliptic friction cones instead of the model's own cone
    (MuJoCo's opt.cone: MuJoCo Menagerie's Go1 has elliptic cones, the project's and Playground's pyramidal ones),
    drawn per robot. Native physics only: MJX compiles one cone type, the model's, and draws `impratio` alone (None:
    the model's cone for every robot)."""
    impratio: tuple[float, float] | None = None
    """Range of the solver's ratio of friction to normal constraint impedance (opt.impratio), drawn log-uniformly per
    robot: 1 is MuJoCo's default, 100 Menagerie's Go1, whose elliptic cones then hardly let a foot slip, spin or roll
    (None: the model's)."""
    latency_s: tuple[float, float] | None = None
    """Range of the action latency, seconds, drawn in whole physics steps: for that long after a control step begins
    the previous joint targets still act (None: none)."""
    encoder_offset: float = 0.0
    """Each joint's angle reads off by a constant uniform in +-this for the episode, radians (0: none)."""
    imu_bias: tuple[float, float] = (0.0, 0.0)
    """Constant biases of the IMU for the episode, uniform in +-these per axis: on the projected gravity (unitless)
    and on the angular velocity (rad/s)."""
    push_interval_s: float = 8.0
    """Seconds between random pushes of the body (0: no pushes); every environment is pushed at the same steps
    of its episode."""
    push_velocity: float = 0.5
    """A push adds a horizontal velocity uniform in +-this per axis to the body, m/s."""


SOFT_SOLIMP = (0.015, 1.0, 0.023, 0.5, 2.0)
"""solimp of the feet of MuJoCo Menagerie's Go1: the soft end of `RandomizationConfig.contact_softness`."""

COVERING = dict(joint_damping=(0.3, 2.5), joint_armature=(0.004, 0.02), joint_frictionloss=(0.1, 1.2),
                contact_softness=(0.0, 1.0), contact_timeconst=(0.01, 0.03), contact_margin=(0.0, 0.002),
                contact_spin=(0.0, 1.5), joint_spread=0.6, elliptic_share=0.5, impratio=(1.0, 100.0),
                latency_s=(0.0, 0.02), encoder_offset=0.02, imu_bias=(0.03, 0.05))
"""Ranges of the model randomisation that covers every reference model of the Go1 (the project's, MuJoCo Menagerie's
and MuJoCo Playground's: damping 0.5-2, armature 0.005-0.01, friction loss 0.2-1.0, plain to soft feet with 0-1 mm of
margin, condim 3 to condim 6, pyramidal or elliptic friction cones with impratio 1-100; legged.robots.models), with
up to 20 ms of action latency and small sensor biases. The Go1 tasks train with them by default (GO1_RANDOMIZATION);
runs saved before they existed load without."""


GO1_RANDOMIZATION = RandomizationConfig(enabled=True, **COVERING)
"""The Go1 tasks' default randomisation: the earlier ranges, and the model ranges that cover the reference robots."""


@dataclasses.dataclass(frozen=True)
class NoiseConfig:
    """Uniform observation noise added to the deployable observation `state` (never to the privileged one)."""

    enabled: bool = False
    """Switch for the whole group."""
    gravity: float = 0.05
    """Noise on the projected gravity vector."""
    joint_pos: float = 0.01
    """Noise on joint positions, radians."""
    joint_vel: float = 1.5
    """Noise on joint velocities, rad/s."""
    height_scan: float = 0.02
    """Noise on height-scan values, metres."""
    gyro: float = 0.2
    """Noise on the IMU's angular velocity (with `EnvConfig.gyro_in_state`), rad/s."""
    lin_vel: float = 0.1
    """Noise on the estimated body velocity (with `EnvConfig.velocity_in_state`), m/s."""


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """Settings common to every legged environment."""

    sim_dt: float = 0.005
    """Physics time step, seconds."""
    ctrl_dt: float = 0.02
    """Policy period, seconds (50 Hz; 4 physics steps per action)."""
    episode_seconds: float = 20.0
    """Time limit; reaching it ends the episode as a truncation (info['truncation'] = 1)."""
    fall_height: float = 0.12
    """Episode ends when the base is closer than this to the floor below it, metres."""
    flip_up_z: float = 0.3
    """Episode ends when the z component of the body's up axis drops below this (fall or flip)."""
    divergence_qvel: float = 500.0
    """A state with |qvel| above this, or any NaN, counts as diverged and is reset."""
    action_clip: float = 10.0
    """Actions are clipped to +-this before scaling."""
    only_positive_rewards: bool = False
    """Clip each step's total reward at 0 (legged_gym's rule): then an early fall can never pay by ending
    a stream of penalties, and the penalties still shape what the policy does while it earns reward."""
    failure_penalty: float = 0.0
    """Reward added once, on the step an episode ends in a fall or the task's failure (the follower stalled out):
    <= 0, added after the clip of only_positive_rewards, so a failure costs this on top of the reward it forgoes."""
    randomization: RandomizationConfig = RandomizationConfig()
    """Domain randomisation (the Go1 tasks turn it on, with the ranges that cover the reference models: COVERING)."""
    noise: NoiseConfig = NoiseConfig()
    """Observation noise (the Go1 tasks turn it on)."""
    gyro_in_state: bool = False
    """`state` also holds the IMU's angular velocity (body frame; right after the projected gravity), as a real
    robot measures it. Off by default (the shipped walker was trained without it); on for go1-rough and the confined
    tasks' new runs."""
    velocity_in_state: bool = False
    """`state` also holds the body's linear velocity in its own frame (first), as a legged robot's state estimator
    (IMU and leg odometry) gives it: with it a walker can see how well it tracks its command and correct for the
    robot it walks on; without it, it can only replay a gait learned for one set of dynamics. Off by default (runs
    saved before it); on for the confined tasks' new runs."""
    motor_curve: bool = False
    """Limit each servo's torque to its motor's torque-speed line (RobotSpec.motor_speeds): the force limit at rest
    falling to 0 at the motor's free speed when torque and motion agree (braking keeps the force limit); applied to the
    joint targets at each control step from the joint velocities then. On for the Go1 tasks (legged.tasks)."""
    robot_model: str = "project"
    """Which model of the task's robot the physics runs: project (assets/robots), a reference (menagerie, playground)
    or an MJCF file of the same robot (legged.robots.models; `--robot` on eval, drill, navigate and view)."""
    history_steps: int = 0
    """When > 0, the observation `history` holds the last this many `state` vectors (oldest first, the current
    one last): what a deployable student remembers."""
    past_steps: int = 0
    """When > 0, `state` also holds the joint angles, joint velocities and actions of the last this many control
    steps as they were observed (oldest first): enough memory for a plain MLP policy to tell the robot's joint
    damping, friction and latency apart, which a memoryless one cannot (0: none)."""

    def __post_init__(self):
        if not self.failure_penalty <= 0.0:  # NaN fails here too
            raise ValueError(f"failure_penalty must be a number <= 0 (a cost), got {self.failure_penalty!r}")

    @property
    def n_substeps(self) -> int:
        """Physics steps per control step."""
        n = round(self.ctrl_dt / self.sim_dt)
        if n < 1 or abs(n * self.sim_dt - self.ctrl_dt) > 1e-9:
            raise ValueError(f"ctrl_dt {self.ctrl_dt} must be a whole multiple of sim_dt {self.sim_dt}")
        return n

    @property
    def episode_steps(self) -> int:
        """Control steps per episode."""
        return int(round(self.episode_seconds / self.ctrl_dt))


@dataclasses.dataclass(frozen=True)
class PenaltyScales:
    """Weights of the penalty terms shared by all tasks (negative numbers)."""

    joint_acc: float = -2.5e-7
    """Times the sum of squared joint accelerations (rad/s^2)."""
    torques: float = -1e-4
    """Times the sum of squared actuator torques (N m)."""
    joint_limits: float = -10.0
    """Times the summed excursion beyond 95% of each joint range (rad)."""
    collisions: float = -1.0
    """Times the number of trunk, thigh or knee contacts with floor or ceiling."""
    action_rate: float = -0.01
    """Times the squared change of the action between control steps."""
