"""The navigation benchmark's scenes: a fixed family built from MuJoCo primitives (legged.worlds.scenes), the kinds
of places a user brings a quadruped to.

| kind | scenes |
|---|---|
| corridors | widths 0.6-1.6 m, roofs 0.5-1.0 m and open sky |
| crawl | a roof low enough that the body must crouch (0.34 m) |
| bars | pipes and a beam across the way, undersides 0.38-0.42 m |
| side blocks | blocks from alternate walls that force sidesteps |
| pillars | a field of posts in the open to weave through |
| voids | gaps in the floor, 12 and 22 cm, 0.5 m deep |
| steps and ramps | an 8 cm step, ramps of 12-15 degrees |
| turns | an L (90 degrees), an S (two 45-degree bends), a 30-degree bend |
| course | 18 m through corridors, a bar, side blocks, open sky, a void, a step and two turns |

`legged scenes --out DIR` writes them (assets/scenes holds the committed copy, which a test keeps equal to
this code). Training never uses them: the follower learns in the generator's worlds.
"""

from __future__ import annotations

import math

import numpy as np

from legged.worlds.scenes import Scene, WALL, box, corridor, pillar, pipe, scene


def _slab(name: str, a, b, width: float, top: float = 0.0, thickness: float = 0.2) -> str:
    """A floor slab from a to b (x, y), `width` wide, its top at `top`."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    v = b - a
    c = (a + b) / 2
    return box(name, (c[0], c[1], top - thickness / 2), (float(np.linalg.norm(v)) / 2, width / 2, thickness / 2),
               math.atan2(v[1], v[0]))


def _floor_with_gaps(name: str, a, b, width: float, gaps: list[tuple[float, float]]) -> list[str]:
    """Slabs from a to b with gaps (distance along from a, gap length) between them."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    unit = (b - a) / np.linalg.norm(b - a)
    cuts, at, geoms = sorted(gaps), 0.0, []
    for k, (s, g) in enumerate(cuts + [(float(np.linalg.norm(b - a)), 0.0)]):
        if s > at:
            geoms.append(_slab(f"{name}_{k}", a + at * unit, a + s * unit, width))
        at = s + g
    return geoms


def _ramp(name: str, x0: float, z0: float, x1: float, z1: float, width: float) -> str:
    """A ramp along x whose top surface goes from (x0, z0) to (x1, z1): a 5 cm thick box, pitched."""
    pitch, t = math.atan2(z1 - z0, x1 - x0), 0.05
    length = math.hypot(x1 - x0, z1 - z0)
    cx, cz = (x0 + x1) / 2 + t * math.sin(pitch), (z0 + z1) / 2 - t * math.cos(pitch)
    return (f'    <geom name="{name}" type="box" pos="{cx:.4f} 0.0000 {cz:.4f}" '
            f'size="{length / 2:.4f} {width / 2:.4f} {t:.4f}" euler="0 {-pitch:.6f} 0"/>')


def _straight(name: str, width: float, roof: float | None, description: str, extra: list[str] = (),
              length: float = 5.0, goal_z: float | None = None) -> Scene:
    """A closed straight corridor from x = -0.6 to `length` + 0.6, start at x = 0, goal at x = `length`."""
    return scene(name, description, corridor("c", [(-0.6, 0.0), (length + 0.6, 0.0)], width, roof) + list(extra),
                 [(0.0, 0.0), (length, 0.0)], goal_z=goal_z)


def build() -> list[Scene]:
    """Every benchmark scene, in a fixed order."""
    out = [
        _straight("corridor-w100-roof50", 1.0, 0.50, "a 1.0 m wide corridor, roof at 0.50 m"),
        _straight("corridor-w160-roof60", 1.6, 0.60, "a 1.6 m wide corridor, roof at 0.60 m"),
        _straight("corridor-w120-roof80", 1.2, 0.80, "a 1.2 m wide corridor, roof at 0.80 m"),
        _straight("corridor-w60-roof100", 0.6, 1.00, "a 0.6 m wide corridor, roof at 1.00 m"),
        _straight("walls-w120-open", 1.2, None, "a 1.2 m wide corridor under open sky"),
        scene("open-sky", "open flat ground, nothing else", [], [(0.0, 0.0), (5.0, 0.0)]),
        _straight("crawl-roof34", 1.0, 0.60, "a 1.0 m corridor, roof at 0.60 m, crouching under 0.34 m for 1.5 m",
                  [box("low_roof", (2.5, 0.0, 0.34 + WALL), (0.75, 0.5, WALL))]),
        _straight("bars", 1.2, 0.80, "a 1.2 m corridor, roof 0.80 m, two pipes and a beam across it, undersides "
                  "0.38-0.42 m", [pipe("pipe_a", 1.7, 0.0, 0.40, 0.03, 1.2),
                                  box("beam", (2.5, 0.0, 0.42 + 0.1), (0.1, 0.6, 0.1)),
                                  pipe("pipe_b", 3.3, 0.0, 0.38, 0.04, 1.2)]),
        _straight("side-blocks", 1.6, 0.70, "a 1.6 m corridor, roof 0.70 m, blocks from alternate walls leave 0.7 m "
                  "openings", [box("block_a", (1.6, 0.35, 0.35), (0.2, 0.45, 0.35)),
                               box("block_b", (2.7, -0.35, 0.35), (0.2, 0.45, 0.35)),
                               box("block_c", (3.8, 0.35, 0.35), (0.2, 0.45, 0.35))], length=5.4),
        scene("pillars", "open sky, six posts (0.2 m across) on and beside the straight line",
              [pillar(f"post_{k}", x, y, 0.1, 1.0) for k, (x, y) in
               enumerate([(1.5, 0.0), (2.3, 0.6), (2.3, -0.6), (3.1, 0.0), (3.9, 0.6), (3.9, -0.6)])],
              [(0.0, 0.0), (5.2, 0.0)]),
        scene("voids", "a 1.2 m corridor, open sky, two gaps across the floor (12 and 22 cm, 0.5 m deep)",
              corridor("c", [(-0.6, 0.0), (5.6, 0.0)], 1.2, None)
              + _floor_with_gaps("floor", (-1.0, 0.0), (6.0, 0.0), 1.6, [(2.8, 0.12), (4.2, 0.22)]),
              [(0.0, 0.0), (5.0, 0.0)], plane_z=-0.5),
        _straight("step-and-ramp", 1.2, 0.75, "a 1.2 m corridor, roof 0.75 m, an 8 cm step up, a 15-degree ramp down",
                  [box("step", (2.0, 0.0, 0.04), (0.5, 0.6, 0.04)),
                   _ramp("ramp_down", 2.5, 0.08, 2.5 + 0.08 / math.tan(math.radians(15)), 0.0, 1.2)], length=5.4),
        _straight("ramp-up", 1.2, 0.85, "a 1.2 m corridor, roof 0.85 m, a 12-degree ramp up 10 cm to a plateau",
                  [_ramp("ramp_up", 1.5, 0.0, 1.5 + 0.10 / math.tan(math.radians(12)), 0.10, 1.2),
                   box("plateau", (3.8, 0.0, 0.05), (1.83, 0.6, 0.05))], length=4.6, goal_z=0.10),
        scene("turn-l", "a 1.2 m corridor, roof 0.60 m, turning 90 degrees left",
              corridor("c", [(-0.9, 0.0), (2.5, 0.0), (2.5, 3.9)], 1.2, 0.60),
              [(-0.3, 0.0), (2.5, 0.0), (2.5, 3.3)]),
        scene("turn-s", "a 1.0 m corridor, roof 0.55 m, two 45-degree bends",
              corridor("c", [(-0.9, 0.0), (1.5, 0.0), (2.8, 1.3), (5.7, 1.3)], 1.0, 0.55),
              [(-0.3, 0.0), (1.5, 0.0), (2.8, 1.3), (5.1, 1.3)]),
    ]
    turn = math.radians(30)
    bend = np.array([1.8 + 2.5 * math.cos(turn), -2.5 * math.sin(turn)])
    ahead = np.array([math.cos(turn), -math.sin(turn)])
    out.append(scene("turn-30", "a 0.8 m corridor under open sky, bending 30 degrees right",
                     corridor("c", [(-0.9, 0.0), (1.8, 0.0), tuple(bend + 1.3 * ahead)], 0.8, None),
                     [(-0.3, 0.0), (1.8, 0.0), tuple(bend + 0.7 * ahead)]))
    out.append(_course())
    return out


def _course() -> Scene:
    """18 m: a low corridor with a bar, an L turn into a wide corridor with side blocks, open sky with a void and
    a step, a 45-degree bend to the goal."""
    route = [(-0.5, 0.0), (4.0, 0.0), (4.0, 4.0), (9.0, 4.0), (12.5, 7.5)]
    geoms = corridor("low", [(-1.1, 0.0), (4.0, 0.0), (4.0, 1.8)], 1.2, 0.55, closed=False)
    geoms.append(pipe("bar", 2.2, 0.0, 0.40, 0.04, 1.2))
    geoms += corridor("wide", [(4.0, 1.8), (4.0, 4.0), (6.2, 4.0)], 1.6, 0.70, closed=False)
    geoms += [box("block_a", (3.65, 2.9, 0.35), (0.45, 0.2, 0.35)),
              box("block_b", (5.3, 4.35, 0.35), (0.2, 0.45, 0.35))]
    geoms += _floor_with_gaps("floor_a", (-1.5, 0.0), (4.0, 0.0), 3.0, [])
    geoms += _floor_with_gaps("floor_b", (4.0, -1.0), (4.0, 4.0), 3.0, [])
    geoms += _floor_with_gaps("floor_c", (2.5, 4.0), (9.0, 4.0), 3.0, [(4.5, 0.15)])
    geoms += _floor_with_gaps("floor_d", (9.0, 4.0), (13.5, 8.5), 3.0, [])
    geoms.append(box("step", (8.3, 4.0, 0.04), (0.35, 1.0, 0.04)))
    geoms += corridor("bend", [(10.2, 5.2), (13.1, 8.1)], 1.4, 0.80, closed=False)
    return scene("course", "18 m: a corridor with a bar, an L turn, side blocks, open sky with a 15 cm void and an "
                 "8 cm step, a 45-degree bend", geoms, route, plane_z=-0.5)
