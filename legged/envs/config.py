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
    push_interval_s: float = 8.0
    """Seconds between random pushes of the body (0: no pushes); every environment is pushed at the same steps
    of its episode."""
    push_velocity: float = 0.5
    """A push adds a horizontal velocity uniform in +-this per axis to the body, m/s."""


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
    randomization: RandomizationConfig = RandomizationConfig()
    """Domain randomisation."""
    noise: NoiseConfig = NoiseConfig()
    """Observation noise."""
    gyro_in_state: bool = False
    """`state` also holds the IMU's angular velocity (body frame; right after the projected gravity), as a real
    robot measures it. Off for the tasks whose shipped policies were trained without it; on for go1-rough."""
    history_steps: int = 0
    """When > 0, the observation `history` holds the last this many `state` vectors (oldest first, the current
    one last): what a deployable student remembers."""

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
