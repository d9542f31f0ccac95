"""Sizes, colours and contact settings of the soccer scene (one frozen dataclass)."""

from __future__ import annotations

import dataclasses

TEAMS = ("home", "away")
"""Team names, in agent order: home players first, then away players. Home defends the goal at -x."""


@dataclasses.dataclass(frozen=True)
class SoccerSceneConfig:
    """Everything that shapes the soccer scene; the defaults are the 1v1 OP3 pitch.

    The pitch is about 5 x 4 m, the size of the small-humanoid soccer work the OP3 game follows. Goal, ball
    and line sizes are not given there: they are chosen here (RoboCup KidSize proportions scaled to this pitch) and named as
    choices, to be randomised or tuned by the tasks.
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
