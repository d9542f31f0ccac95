"""Configuration of the soccer game, one family of frozen dataclasses: the scene's sizes, colours and contacts
(`SoccerSceneConfig`), the reward weights (`SoccerRewards`) and the environment (`SoccerConfig`: the game's rules,
what the players see, its randomisation and estimate errors, whose own dataclasses live beside the code that draws
them: legged.soccer.randomize, legged.soccer.vision.estimate_noise)."""

from __future__ import annotations

import dataclasses
from typing import Literal

from legged.envs.config import EnvConfig, PenaltyScales
from legged.robots.op3 import OP3_CTRL_DT
from legged.sensors.raycam import RayCameraConfig
from legged.soccer.randomize import SoccerRandomization
from legged.soccer.vision.estimate_noise import EstimateNoise


@dataclasses.dataclass(frozen=True)
class SoccerSceneConfig:
    """Everything that shapes the soccer scene; the defaults are the 1v1 OP3 pitch.

    The pitch is about 5 x 4 m, the size of the small-humanoid soccer work the OP3 game follows. Goal, ball
    and line sizes are not given there: they are chosen here (RoboCup KidSize proportions scaled to this pitch)
    and named as choices, to be randomised or tuned by the tasks.
    """

    players_per_team: int = 1
    """Robots per team: 1 (1v1) or 2 (2v2)."""
    field_length: float = 5.0
    """Distance between the two goal lines (along x), metres, line centre to line centre."""
    field_width: float = 4.0
    """Distance between the two touch lines (along y), metres, line centre to line centre."""
    line_width: float = 0.05
    """Width of every painted line, metres (RoboCup's 5 cm)."""
    centre_circle_radius: float = 0.5
    """Radius of the centre circle (to the line's centre), metres."""
    circle_segments: int = 32
    """Straight pieces that draw the centre circle (in the MJCF and in the analytic line list alike)."""
    goal_width: float = 0.8
    """Clear width of the goal mouth between the posts' inner faces, metres."""
    goal_height: float = 0.45
    """Clear height under the crossbar, metres (the OP3 is about 0.5 m tall)."""
    goal_depth: float = 0.3
    """Depth of the goal behind the goal line (back net position), metres."""
    post_width: float = 0.04
    """Side of the square section of posts and crossbar, metres."""
    net_thickness: float = 0.01
    """Thickness of the (solid, opaque) net boxes, metres."""
    wall_margin: float = 0.5
    """Invisible walls that keep the ball in the arena stand this far outside the lines, metres."""
    ball_radius: float = 0.07
    """Ball radius, metres: a size-1 football (circumference about 0.44 m), the RoboCup KidSize ball."""
    ball_mass: float = 0.2
    """Ball mass, kg (a light size-1 ball; a chosen value). Its inertia is a thin shell's (2/3 m r^2)."""
    ball_rolling_friction: float = 0.005
    """Rolling (and torsional) friction of ball and floor, metres: about 0.4 m/s^2 of deceleration (grass)."""
    ball_friction: float = 0.5
    """Sliding friction of the ball against floor, robots, goals and walls."""
    floor_friction: float = 0.8
    """Sliding friction of robot feet (and fallen torsos and heads) on the floor."""
    ball_robot_geoms: tuple[str, ...] = ("l_foot", "r_foot", "l_shin", "r_shin")
    """Robot collision geoms (unprefixed OP3 names) that touch the ball: what a robot kicks with."""
    robot_robot_contacts: bool = False
    """Add robot-robot pairs (torso-torso and foot-foot between every two robots); they cost MJX time."""
    limb_floor_contacts: bool = False
    """Also pair each robot's arm, thigh and shin capsules with the floor, so that a fallen robot can push
    itself up (op3-getup, and games with a get-up skill); off elsewhere: 8 more pairs per robot cost time."""
    leg_contacts: bool = False
    """Pair each robot's legs with each other (thigh, shin and foot of one leg with those of the other), as a real
    OP3's legs touch when its feet cross; for a model without self-contacts of its own (the project's: Menagerie's
    OP3 collides its meshes by itself). 9 more pairs per robot on the project's model."""
    home_rgba: tuple[float, float, float, float] = (0.15, 0.35, 0.85, 1.0)
    """Team colour of the home team (torso and head shells), RGBA."""
    away_rgba: tuple[float, float, float, float] = (0.85, 0.2, 0.15, 1.0)
    """Team colour of the away team (torso and head shells), RGBA."""
    ball_rgba: tuple[float, float, float, float] = (1.0, 0.6, 0.1, 1.0)
    """Ball colour, RGBA (orange: apart from the grass, the lines and both teams)."""
    pitch_rgba: tuple[float, float, float, float] = (0.2, 0.5, 0.2, 1.0)
    """Grass colour of the floor plane, RGBA."""
    line_rgba: tuple[float, float, float, float] = (0.95, 0.95, 0.95, 1.0)
    """Colour of the painted lines, RGBA."""
    post_rgba: tuple[float, float, float, float] = (0.95, 0.95, 0.95, 1.0)
    """Colour of the goal posts and crossbars, RGBA."""
    net_rgba: tuple[float, float, float, float] = (0.75, 0.75, 0.7, 1.0)
    """Colour of the goal nets (opaque, so both renderers agree on what lies behind them), RGBA."""
    floor_margin: float = 1.0
    """The finite floor plane reaches this far beyond the walls, metres (beyond it: sky)."""
    head_camera_tilt_deg: float = 30.0
    """How far below the horizontal every head camera looks, degrees (the MJCF's camera looks level, so that a
    standing robot sees the ground only beyond 1.1 m and never the ball at its feet; a real OP3 tilts its head to
    watch the ball). Modelled as the camera's mount: the head's joints stay where the walking skill holds them."""
    head_camera_fovy_deg: float = 0.0
    """Vertical field of view of every head camera, degrees (a wider lens sees the ball at the feet and the goals
    at once); 0: the MJCF's, 43.3 (the OP3's Logitech C920)."""
    camera_znear: float = 0.02
    """Near clipping distance of every camera, metres (hides the inside of the robot's own head)."""
    camera_zfar: float = 30.0
    """Far clipping distance of every camera, metres."""

    def __post_init__(self):
        if self.players_per_team not in (1, 2):
            raise ValueError(f"players_per_team must be 1 or 2, got {self.players_per_team!r}")
        for name in ("field_length", "field_width", "line_width", "centre_circle_radius", "goal_width",
                     "goal_height", "goal_depth", "post_width", "net_thickness", "ball_radius", "ball_mass"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if not -90.0 < self.head_camera_tilt_deg < 90.0:
            raise ValueError(f"head_camera_tilt_deg must be between -90 and 90, got {self.head_camera_tilt_deg!r}")
        if not 0.0 <= self.head_camera_fovy_deg < 180.0:
            raise ValueError(f"head_camera_fovy_deg must be 0 (the MJCF's) or between 0 and 180, got "
                             f"{self.head_camera_fovy_deg!r}")
        if self.circle_segments < 8:
            raise ValueError(f"circle_segments must be at least 8, got {self.circle_segments!r}")
        if self.wall_margin <= self.goal_depth + self.net_thickness:
            raise ValueError(f"wall_margin ({self.wall_margin}) must exceed goal_depth + net_thickness "
                             f"({self.goal_depth + self.net_thickness}): the goals stand inside the walls")
        if self.goal_width + 2 * self.post_width >= self.field_width:
            raise ValueError(f"goal_width ({self.goal_width}) does not fit in field_width ({self.field_width})")
        if 2 * self.centre_circle_radius >= min(self.field_length, self.field_width):
            raise ValueError(f"centre_circle_radius ({self.centre_circle_radius}) does not fit on the pitch")

    @property
    def n_agents(self) -> int:
        """Robots on the pitch (both teams)."""
        return 2 * self.players_per_team

    def team_rgba(self, team: int) -> tuple[float, float, float, float]:
        """Colour of team 0 (home) or 1 (away)."""
        return (self.home_rgba, self.away_rgba)[team]

    def team_net_rgba(self, team: int) -> tuple[float, float, float, float]:
        """Colour of the net of team 0's (home) or team 1's goal: `net_rgba` tinted by the team's colour."""
        team_rgba = self.team_rgba(team)
        return (*(0.7 * n + 0.3 * t for n, t in zip(self.net_rgba[:3], team_rgba[:3])), self.net_rgba[3])


@dataclasses.dataclass(frozen=True)
class SoccerRewards:
    """Per-agent reward weights: the sparse goal reward and shaping terms after dm_control's soccer statistics."""

    goal: float = 1.0
    """+1 when the agent's team scores, -1 when it concedes (times this)."""
    vel_to_ball: float = 0.05
    """Times the torso's horizontal velocity toward the ball (or the spot `approach_offset` behind it), m/s."""
    approach_offset: float = 0.0
    """vel_to_ball aims up to this far behind the ball, on the line from the opponent goal through it, metres
    (0: at the ball): the full offset for a robot beside or in front of the ball, none for one lined up behind
    it (scaled by 1 - the cosine between its bearing to the ball and the ball's direction to the goal), so that
    robots line up first and then walk the ball goalwards."""
    ball_vel_to_goal: float = 0.1
    """Times the ball's horizontal velocity toward the opponent goal, m/s (the same for both teammates)."""
    upright: float = 0.5
    """Times the z component of the torso's up axis (1 upright). The episode ends at the learner's fall, so
    this must outweigh the penalties: with 0.02 and the penalties below at 5x, a CPU run learned to fall
    at once (episodes shrank from 22 to 8 steps)."""
    fall: float = -1.0
    """On the control step the agent falls."""
    penalties: PenaltyScales = PenaltyScales(joint_acc=-2.5e-8, torques=-2e-4, collisions=0.0, action_rate=-0.002)
    """The penalties every task shares (collisions: unused, robots may touch the ball with any part)."""


@dataclasses.dataclass(frozen=True)
class SoccerConfig(EnvConfig):
    """A soccer game of OP3 teams (1v1 or 2v2) on the scene of `scene`. With `velocity_in_state` the game keeps each
    robot's torso velocity as a state estimator gives it (`info['velocity_estimate']`, noise `noise.lin_vel`) for
    walkers that read it: op3-walk's state then ends with it; the soccer players' own inputs stay as they are."""

    ctrl_dt: float = OP3_CTRL_DT
    """Policy period, seconds (40 Hz; 5 physics steps)."""
    episode_seconds: float = 20.0
    """Time limit of an episode (a truncation), seconds."""
    fall_height: float = 0.15
    """A robot whose torso origin (hip level, 0.245 m when standing) is lower than this has fallen, metres."""
    flip_up_z: float = 0.5
    """A robot whose torso up axis has a z component below this (tilted beyond 60 degrees) has fallen."""
    scene: SoccerSceneConfig = SoccerSceneConfig()
    """Pitch, goals, ball, team sizes and colours."""
    end_on_fall: Literal["agent0", "any", "never"] = "agent0"
    """Which fall ends the episode: agent 0's (the learner's in training), any robot's, or none; a fallen robot
    that does not end it lies where it fell, unless the players command a walker with a get-up skill
    (`getup`, legged.soccer.walker), which stands it up again."""
    end_on_goal: bool = False
    """End the episode at a goal; otherwise play restarts from the kick-off poses."""
    spawn_spread: float = 0.5
    """At an episode's start each robot stands up to this far (metres, per axis) from its kick-off spot."""
    spawn_yaw: float = 1.5708
    """... and turned up to +-this (radians) from facing the opponent goal."""
    random_ball: bool = True
    """Episode start: the ball anywhere on the pitch `restart_inset` inside the lines (else on the centre spot)."""
    restart_inset: float = 0.3
    """A ball that leaves the pitch is put back this far inside the line it crossed, at rest, metres."""
    vision: bool = False
    """Give every agent its head camera image (observation 'camera') and a proprioceptive-only 'state'."""
    camera: RayCameraConfig = RayCameraConfig()
    """Size and appearance of the head camera images."""
    vision_heading: bool = False
    """With `vision`: 'state' also ends with the attacking direction in the agent's heading frame (an IMU's yaw)."""
    vision_sightings: bool = False
    """With `vision`: 'state' also ends with where the head camera's image shows the ball, the own goal's net and
    the opponent goal's net (a colour-and-depth detector, legged.soccer.vision.sightings: for each seen, then x, y, z in
    the heading frame; zeros when not in view)."""
    vision_tracker: bool = False
    """With `vision`, for a player that estimates the game (command_prior=placo): its placo command reads the goals
    and the ball from a tracker (legged.soccer.vision.tracker: its pose on the pitch by odometry and the goal nets its
    camera sights, the ball where it last saw it) wherever the tracker knows them, from its own estimate
    elsewhere. The state is unchanged (see `vision_tracker_inputs`)."""
    vision_tracker_inputs: bool = False
    """With `vision_tracker`: the learner's 'state' also ends with what its tracker knows (legged.soccer.vision.tracker
    .tracker_inputs: locked on, both goals, ball fresh, the ball; heading frame, zeros where it knows nothing),
    so that its network's corrections can use it too."""
    vision_ball_memory_s: float = 1.0
    """With `vision_tracker`: how long the tracker keeps the ball where the camera last saw it (s); after that the
    player's own estimate of the ball is used."""
    vision_ball_velocity: bool = False
    """With `vision_tracker`: the tracker follows the ball's motion (a constant-velocity Kalman filter over its
    sightings, legged.soccer.vision.tracker), so the placo command also reads the ball's velocity from it while the
    ball is fresh, and a ball out of view rolls on; false: the ball is held where last seen, its velocity
    estimated."""
    vision_sighted_ball: bool = False
    """With `vision_sightings`, for a player that estimates the game (command_prior=placo): the placo command
    takes the ball's position from the sighting whenever the camera sees the ball, from the player's own
    estimate otherwise (a detector's measurement trusted over the network's regression)."""
    estimate_oracle: tuple[str, ...] = ()
    """Diagnostics only, not a deployable player: for a player that estimates the game, these parts of its
    estimate (ball, ball_vel, own_goal, opponent_goal, opponent0, ...) are replaced by the truth before the placo
    command is computed, to measure which estimate limits its play (`legged eval RUN --oracle ball`)."""
    vision_gaze: bool = False
    """With `vision`, for a player that estimates the game (command_prior=placo): its head pans toward where it
    estimates the ball to be (legged.soccer.opponents.ball_pan), keeping the ball in view; false: the walker
    holds the head."""
    estimate_noise: EstimateNoise = EstimateNoise()
    """State tasks: errors like a vision player's estimate on the game features of `state` (a state player that
    steers a vision player from its estimate, `legged eval VISION_RUN --pilot RUN`;
    legged.soccer.vision.estimate_noise)."""
    rewards: SoccerRewards = SoccerRewards()
    """Reward weights."""
    randomization: SoccerRandomization = SoccerRandomization()
    """Per-episode randomisation of ground and ball friction, ball mass, link masses and motor strength."""

    def __post_init__(self):
        self.randomization.validate()
        self.estimate_noise.validate()
        if self.estimate_noise.enabled and self.vision:
            raise ValueError("estimate_noise blurs a state player's game features; a vision player has none (it "
                             "estimates them itself): switch one off")
        if self.rewards.approach_offset < 0:
            raise ValueError(f"rewards.approach_offset must be non-negative, got {self.rewards.approach_offset}")
        if self.end_on_fall not in ("agent0", "any", "never"):
            raise ValueError(f"end_on_fall must be 'agent0', 'any' or 'never', got {self.end_on_fall!r}")
        if self.spawn_spread < 0 or self.restart_inset < 0:
            raise ValueError("spawn_spread and restart_inset must be non-negative")
        if self.vision_gaze and not self.vision:
            raise ValueError("vision_gaze turns a vision player's head toward the ball it estimates: it needs vision")
        if self.vision_sightings and not self.vision:
            raise ValueError("vision_sightings adds where the head camera sees the ball and the goals to a vision "
                             "player's state: it needs vision")
        if self.vision_tracker and not self.vision:
            raise ValueError("vision_tracker tracks a vision player's pose and the ball from its camera: it needs "
                             "vision")
        if not self.vision_ball_memory_s > 0:
            raise ValueError(f"vision_ball_memory_s must be > 0 seconds, got {self.vision_ball_memory_s}")
        if self.vision_ball_velocity and not self.vision_tracker:
            raise ValueError("vision_ball_velocity lets a vision player's tracker follow the ball's motion: it needs "
                             "vision_tracker")
        if self.vision_tracker_inputs and not self.vision_tracker:
            raise ValueError("vision_tracker_inputs gives a vision player's network what its tracker knows: it needs "
                             "vision_tracker")
        if self.vision_sighted_ball and not self.vision_sightings:
            raise ValueError("vision_sighted_ball steers by the ball the camera sees: it needs vision_sightings")
        if self.vision_heading and not self.vision:
            raise ValueError("vision_heading adds the attacking direction to a vision player's state: it needs vision")
        if 2 * self.restart_inset >= min(self.scene.field_length, self.scene.field_width):
            raise ValueError(f"restart_inset {self.restart_inset} does not fit on the pitch")
