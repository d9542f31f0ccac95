"""Pitch geometry as data: painted lines, goal boxes, boundary walls and kick-off poses.

The scene builder (legged/soccer/scene.py) realises these in MJCF; the ray camera draws the same lines
analytically on the ground; environments read goals and kick-off poses from here. Frame: the pitch centre
is the origin, x runs from the home goal (-x) to the away goal (+x), z is up.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from legged.soccer.config import SoccerSceneConfig
from legged.soccer.layout import TEAMS


@dataclasses.dataclass(frozen=True)
class Box:
    """A static box of the scene (a goal part)."""

    name: str
    """Geom name in the compiled model."""
    pos: tuple[float, float, float]
    """Centre in the world frame, metres."""
    half: tuple[float, float, float]
    """Half sizes along x, y, z (axis-aligned), metres."""
    part: str
    """'post', 'crossbar' or 'net' (for colours)."""


def pitch_lines(config: SoccerSceneConfig) -> np.ndarray:
    """Painted lines as rectangles on the ground, shape [n, 5]: x0, y0, x1, y1, width.

    Each row is the centre line of a rectangle (from (x0, y0) to (x1, y1), square ends) and its full
    width. Rows: two touch lines, two goal lines, the halfway line, then the centre circle as
    `circle_segments` chords, each lengthened so that neighbouring pieces meet on the outer edge.
    """
    half_l, half_w, w = config.field_length / 2, config.field_width / 2, config.line_width
    rows = [
        (-half_l - w / 2, -half_w, half_l + w / 2, -half_w, w),  # touch lines close the corners
        (-half_l - w / 2, half_w, half_l + w / 2, half_w, w),
        (-half_l, -half_w, -half_l, half_w, w),
        (half_l, -half_w, half_l, half_w, w),
        (0.0, -half_w, 0.0, half_w, w),
    ]
    n, r = config.circle_segments, config.centre_circle_radius
    step = 2 * np.pi / n
    extra = (w / 2) * np.tan(step / 2)  # the outer corners of neighbouring chords then touch
    for k in range(n):
        a0, a1 = k * step, (k + 1) * step
        p0, p1 = r * np.array([np.cos(a0), np.sin(a0)]), r * np.array([np.cos(a1), np.sin(a1)])
        u = (p1 - p0) / np.linalg.norm(p1 - p0)
        p0, p1 = p0 - extra * u, p1 + extra * u
        rows.append((p0[0], p0[1], p1[0], p1[1], w))
    return np.array(rows, dtype=np.float64)


def line_names(config: SoccerSceneConfig) -> tuple[str, ...]:
    """Geom names of the rows of `pitch_lines`, in order."""
    fixed = ("line/touch_right", "line/touch_left", "line/goal_home", "line/goal_away", "line/halfway")
    return fixed + tuple(f"line/circle{k:02d}" for k in range(config.circle_segments))


def goal_boxes(config: SoccerSceneConfig, team: int) -> tuple[Box, ...]:
    """Posts, crossbar and nets of the goal that `team` (0 home, 1 away) defends; home's is at -x."""
    s = -1.0 if team == 0 else 1.0
    x_line, pw, nt = config.field_length / 2, config.post_width, config.net_thickness
    gw, gh, depth = config.goal_width, config.goal_height, config.goal_depth
    prefix = f"goal_{TEAMS[team]}/"
    x_post = s * (x_line + pw / 2)  # posts stand just behind the goal line
    inner = depth - pw  # net length behind the posts
    x_mid = s * (x_line + pw + inner / 2)
    y_side = gw / 2 + pw / 2
    return (
        Box(prefix + "post_right", (x_post, -y_side, gh / 2), (pw / 2, pw / 2, gh / 2), "post"),
        Box(prefix + "post_left", (x_post, y_side, gh / 2), (pw / 2, pw / 2, gh / 2), "post"),
        Box(prefix + "crossbar", (x_post, 0.0, gh + pw / 2), (pw / 2, gw / 2 + pw, pw / 2), "post"),
        Box(prefix + "net_back", (s * (x_line + depth + nt / 2), 0.0, gh / 2), (nt / 2, gw / 2 + pw, gh / 2), "net"),
        Box(prefix + "net_right", (x_mid, -y_side, gh / 2), (inner / 2, nt / 2, gh / 2), "net"),
        Box(prefix + "net_left", (x_mid, y_side, gh / 2), (inner / 2, nt / 2, gh / 2), "net"),
        Box(prefix + "net_top", (x_mid, 0.0, gh + nt / 2), (inner / 2, gw / 2 + pw, nt / 2), "net"),
    )


def goal_centres(config: SoccerSceneConfig) -> np.ndarray:
    """Centre of each goal mouth on its goal line at the ground, [2, 3]: home's goal (-x), away's goal (+x)."""
    x = config.field_length / 2
    return np.array([[-x, 0.0, 0.0], [x, 0.0, 0.0]])


def walls(config: SoccerSceneConfig) -> tuple[tuple[str, np.ndarray, np.ndarray], ...]:
    """Boundary walls as (name, point, inward normal): planes `wall_margin` outside the lines."""
    x = config.field_length / 2 + config.wall_margin
    y = config.field_width / 2 + config.wall_margin
    return (
        ("wall/home_end", np.array([-x, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])),
        ("wall/away_end", np.array([x, 0.0, 0.0]), np.array([-1.0, 0.0, 0.0])),
        ("wall/right", np.array([0.0, -y, 0.0]), np.array([0.0, 1.0, 0.0])),
        ("wall/left", np.array([0.0, y, 0.0]), np.array([0.0, -1.0, 0.0])),
    )


def kickoff_poses(config: SoccerSceneConfig) -> np.ndarray:
    """Kick-off ground poses (x, y, yaw) of every agent, [n_agents, 3]: home players first, then away.

    Each team stands in its own half outside the centre circle, facing the opponent goal; away poses are
    home's turned by 180 degrees about the centre spot.
    """
    length, width = config.field_length, config.field_width
    if config.players_per_team == 1:
        home = [(-0.2 * length, 0.0)]
    else:  # a forward on the left, a back on the right
        home = [(-0.2 * length, 0.15 * width), (-0.36 * length, -0.15 * width)]
    poses = [(x, y, 0.0) for x, y in home] + [(-x, -y, np.pi) for x, y in home]
    return np.array(poses, dtype=np.float64)
