"""A fixed set of narrow-passage scenes for the planner benchmark, written as MJCF as a user would write them.

Every scene is a box tunnel (1 m wide inside, 4 m long, roof 0.6 m up) sampled by `maps_from_scene`:
- `bar-<band>mm`: a bar across the tunnel whose underside leaves a band of feasible body heights
  `band` millimetres wide above the robot's lowest crouch;
- `gap-<width>cm`: a block from one side wall leaving a gap `width` centimetres wide at the other, 15, 13 and 11
  cm wider than the legs' rectangle (`BodyChecker.leg_rectangle`, the feet's stance; the maps' conservative
  sampling and the planner's interpolated floor take about 10 cm of it at 2.5 cm resolution);
- `bar-gap-<band>mm-<width>cm`: both, one after the other.
Bands and gaps are computed from the robot's body box, legs, margins and leg reach, so the scenes stay
narrow for the robot the planner is given.
"""

from __future__ import annotations

import dataclasses
import math

from legged.robots.spec import RobotSpec
from legged.worlds.scenes import box
from planners.body_check import BodyCheckConfig, leg_rectangle, stance_points

TUNNEL_HALF_WIDTH = 0.5
"""Half the inside width of every scene's tunnel, metres."""
START = (-1.5, 0.0)
"""Start x, y of every scene (the goal mirrors it)."""


@dataclasses.dataclass(frozen=True)
class NarrowScene:
    """One benchmark scene: its name, MJCF text, and start and goal body positions."""

    name: str
    """What is narrow and by how much."""
    xml: str
    """Standalone MJCF."""
    start: tuple[float, float, float]
    """Start body centre x, y, z."""
    goal: tuple[float, float, float]
    """Goal body centre x, y, z."""


def tunnel_xml(extra: list[str]) -> str:
    """A closed 4 m box tunnel, 1 m wide and 0.6 m high inside, plus `extra` geoms."""
    w = TUNNEL_HALF_WIDTH
    geoms = [box("ground", (0, 0, -0.05), (2.5, w + 0.1, 0.05)),
             box("wall_left", (0, w + 0.05, 0.35), (2.5, 0.05, 0.35)),
             box("wall_right", (0, -w - 0.05, 0.35), (2.5, 0.05, 0.35)),
             box("end_back", (-2.05, 0, 0.35), (0.05, w, 0.35)),
             box("end_front", (2.05, 0, 0.35), (0.05, w, 0.35)),
             box("roof", (0, 0, 0.65), (2.5, w + 0.1, 0.05))] + extra
    return "<mujoco model=\"narrow\">\n  <worldbody>\n" + "\n".join(geoms) + "\n  </worldbody>\n</mujoco>\n"


def bar(robot: RobotSpec, band: float, x: float, body: BodyCheckConfig = BodyCheckConfig()) -> str:
    """A 0.3 m deep bar across the tunnel at x whose underside leaves a `band` of body heights above the
    lowest crouch (the body's top plus margin must pass under it)."""
    top = robot.body_box_half_extents[2] + body.margin
    underside = robot.body_height_range[0] + top + band
    return box(f"bar_{x:+.1f}", (x, 0, underside + 0.1), (0.15, TUNNEL_HALF_WIDTH, 0.1))


def block(robot: RobotSpec, gap: float, x: float, side: float = 1.0) -> str:
    """A 0.3 m deep block from one side wall leaving a `gap`-wide opening at the other."""
    length = 2 * TUNNEL_HALF_WIDTH - gap
    y = side * (TUNNEL_HALF_WIDTH - length / 2)
    return box(f"block_{x:+.1f}", (x, y, 0.3), (0.15, length / 2, 0.3))


def narrow_scenes(robot: RobotSpec, body: BodyCheckConfig = BodyCheckConfig()) -> list[NarrowScene]:
    """The benchmark's fixed scenes for `robot` (bands 20 to 1 mm, gaps 15 to 11 cm wider than its legs, and
    combinations)."""
    z = sum(robot.body_height_range) / 2
    start, goal = (START[0], START[1], z), (-START[0], START[1], z)
    if body.leg_margin is None:
        width = 2 * (robot.body_box_half_extents[1] + body.margin)
    else:
        _, y0, _, y1, _ = leg_rectangle(stance_points(robot), robot, body)
        width = y1 - y0
    wide, middle, tight = (math.ceil(100 * (width + extra)) / 100 for extra in (0.15, 0.13, 0.11))
    scenes = []
    for band in (0.02, 0.01, 0.005, 0.003, 0.001):
        scenes.append(NarrowScene(f"bar-{band * 1000:g}mm", tunnel_xml([bar(robot, band, 0.0)]), start, goal))
    for gap in (wide, middle, tight):
        scenes.append(NarrowScene(f"gap-{gap * 100:.0f}cm", tunnel_xml([block(robot, gap, 0.0)]), start, goal))
    for gap in (middle, tight):
        zigzag = [block(robot, gap, -0.5, 1.0), block(robot, gap, 0.5, -1.0)]
        scenes.append(NarrowScene(f"zigzag-{gap * 100:.0f}cm", tunnel_xml(zigzag), start, goal))
    for band, gap in ((0.005, middle), (0.003, tight)):
        both = [bar(robot, band, -0.5), block(robot, gap, 0.6)]
        scenes.append(NarrowScene(f"bar-gap-{band * 1000:g}mm-{gap * 100:.0f}cm", tunnel_xml(both), start, goal))
    return scenes
