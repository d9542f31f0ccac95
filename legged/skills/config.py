"""Configuration of the OP3 skill tasks (legged.skills.env): op3-walk and op3-getup."""

from __future__ import annotations

import dataclasses

from legged.soccer.config import SoccerConfig, SoccerSceneConfig
from legged.soccer.randomize import SoccerRandomization

LEG_JOINTS = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ank_pitch", "ank_roll")
"""The OP3's leg joints (without their l_ / r_ prefix): the joints the imitation reward compares."""


@dataclasses.dataclass(frozen=True)
class SkillPenalties:
    """Penalties every skill shares (per control step)."""

    action_rate: float = -0.002
    """Times the squared change of the action between control steps (the soccer game's weight)."""
    torques: float = -2e-4
    """Times the sum of squared actuator torques, (N m)^2."""


@dataclasses.dataclass(frozen=True)
class SkillConfig(SoccerConfig):
    """A skill: the soccer game's physics (its domain randomisation on by default) with a drill's setting."""

    skill_penalties: SkillPenalties = SkillPenalties()
    """The shared penalties (the game's own `rewards` are not used by skills)."""
    randomization: SoccerRandomization = SoccerRandomization(enabled=True)
    """The soccer game's domain randomisation, on by default for skills (their tasks add the ranges that cover the
    reference models: legged.tasks)."""


@dataclasses.dataclass(frozen=True)
class WalkRewards:
    """Reward weights and kernel widths of the walking skill (per control step)."""

    tracking_lin_vel: float = 1.0
    """Times exp(-|v_cmd - v_xy|^2 / lin_vel_sigma^2), planar torso velocity in the heading frame low-pass
    filtered over the drill's `velocity_filter_s` (the instantaneous one sways within each step: tracking it
    would pay standing still more than walking)."""
    tracking_yaw_rate: float = 0.5
    """Times exp(-(w_cmd - w_z)^2 / yaw_rate_sigma^2), w_z the torso's yaw rate, filtered the same way."""
    imitation: float = 0.5
    """Times exp(-mean over leg joints of (q - q_ref)^2 / imitation_sigma^2), q_ref the placo gait's targets
    (half the tracking weight: placo's plan falls short of combined commands, which tracking must fix)."""
    upright: float = 0.3
    """Times the z component of the torso's up axis (1 upright): staying up is worth more than any penalty."""
    fall: float = -2.0
    """On the control step the robot falls (the episode ends there)."""
    lin_vel_sigma: float = 0.1
    """Width of the velocity kernel, m/s (the commands are at most 0.2 m/s)."""
    yaw_rate_sigma: float = 0.3
    """Width of the yaw-rate kernel, rad/s."""
    imitation_sigma: float = 0.15
    """Width of the imitation kernel, rad (root mean square joint error)."""


@dataclasses.dataclass(frozen=True)
class WalkSkillConfig(SkillConfig):
    """op3-walk: the walk drill's random commands, the walking skill's rewards."""

    command_seconds: float = 5.0
    """Seconds between new random commands."""
    command_low: tuple[float, float, float] = (-0.08, -0.04, -0.56)
    """Lower bounds of the random (vx, vy, yaw rate) commands, m/s, m/s, rad/s (the placo gait's range)."""
    command_high: tuple[float, float, float] = (0.2, 0.04, 0.56)
    """Upper bounds of the random commands."""
    walk_rewards: WalkRewards = WalkRewards()
    """Reward weights of the walking skill."""
    scene: SoccerSceneConfig = SoccerSceneConfig(leg_contacts=True)
    """The pitch, with each robot's legs touching each other, as a real OP3's do (walkers fine-tuned on the
    randomised project model without them put their feet closer and tripped on Menagerie's OP3, whose legs collide)."""
    residual: bool = True
    """The policy's action is added to the reference's (the placo gait's targets at the clock and filtered
    command, as actions): it starts out walking open loop and learns the corrections, which takes far fewer
    samples than finding a gait from the imitation reward alone."""

    def __post_init__(self):
        super().__post_init__()
        if not self.command_seconds > 0:
            raise ValueError(f"command_seconds must be positive, got {self.command_seconds}")
        if len(self.command_low) != 3 or len(self.command_high) != 3 or \
                any(lo > hi for lo, hi in zip(self.command_low, self.command_high)):
            raise ValueError(f"command_low {self.command_low} and command_high {self.command_high} must be three "
                             f"(vx, vy, yaw rate) bounds with low <= high")


@dataclasses.dataclass(frozen=True)
class GetUpRewards:
    """Reward weights of the get-up skill (per control step)."""

    height: float = 1.0
    """Times the torso origin's height between lying and standing, scaled to [0, 1]."""
    upright: float = 0.5
    """Times the z component of the torso's up axis, when positive."""
    standing: float = 1.0
    """While the robot stands (the getup drill's criterion)."""
    posture: float = 0.5
    """Times uprightness x exp(-mean (q - default pose)^2 / posture_sigma^2): stand in the default pose."""
    still: float = -1.0
    """Times the torso's squared horizontal speed while standing (stand still, do not stagger)."""
    lying_height: float = 0.06
    """Torso-origin height that counts as lying flat (0 of the height term), m."""
    posture_sigma: float = 0.3
    """Width of the posture kernel, rad (root mean square joint error)."""


@dataclasses.dataclass(frozen=True)
class GetUpConfig(SkillConfig):
    """op3-getup: the getup drill's lying starts, the get-up skill's rewards."""

    episode_seconds: float = 6.0
    """Length of an episode, seconds (falls do not end it)."""
    scene: SoccerSceneConfig = SoccerSceneConfig(limb_floor_contacts=True)
    """The pitch, with arms, thighs and shins touching the floor (what a robot getting up pushes with)."""
    getup_rewards: GetUpRewards = GetUpRewards()
    """Reward weights of the get-up skill."""
    residual: bool = True
    """The policy's action is added to the reference's (ROBOTIS' scripted get-up from the front or the back,
    legged.soccer.getup_motion): it starts out playing the script and learns the corrections."""
