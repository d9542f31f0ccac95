"""Confined-space worlds at fixed difficulty levels d0-d4; each level may hold everything the one before may.

- d0: the pyramid tunnels of `generate_world` (its difficulty `seed % 3`).
- d1: a straight corridor 0.5-2.0 m wide, 3-6 m from start to goal, flat floor at z = 0; a roof at 0.4-1.0 m or
  open sky (a quarter of the worlds); in half of them a low section 0.5-1.5 m long under a 0.30-0.40 m roof
  (the body must crouch).
- d2: d1 plus 1-4 obstacles: bars (the roof drops to 0.36-0.45 m in a 0.05-0.2 m stripe across the corridor),
  side blocks (solid, from one wall, leaving at least 0.45 m to the other; with `block_group` above 1, a slalom of
  up to that many from alternate walls) and pillar groups (2-5 square or round columns 0.1-0.25 m across, at least
  0.45 m from each other and the walls).
- d3: d2 plus 1-2 steps (3-10 cm up or down, for good) or ramps (5-15 degrees, at most 10 cm up or down), and the
  centre line may turn: an L (one bend) or an S (two opposite bends), each bend 30-90 degrees; with `bend_blocks`
  above 0, side blocks right before and after a bend make the path turn sharply between obstacles.
- d4: d3 plus 1-2 voids: gaps across the floor 10-25 cm long and 0.1-1.0 m deep.

The ranges are the fields of `LevelConfig` (legged.worlds.level_config). A world is drawn in two steps:
`level_layout` (legged.worlds.level_layout) draws the corridor and its features as numbers (a `Layout`), and
`render_layout`, here, samples that onto floor and ceiling maps with the
conventions of legged.worlds.generator (row index along x; walls where floor == ceiling == the top value).
The route leaves the start (at the origin) along +x, the way the environments spawn the robot facing.
Features lie on the straight parts of the route, never within `free_radius` of start or goal nor within
`feature_spacing` of one another along the route. Roof, bar and crawl heights are measured from the local floor
level, which steps and ramps move (the roof also keeps its height over the upper side of a step).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from legged.worlds.generator import World, WorldConfig, WorldError, generate_world
from legged.worlds.level_config import LEVELS, OBSTACLES, LevelConfig, check_level
from legged.worlds.level_layout import Feature, Layout, level_layout

__all__ = ["LEVELS", "OBSTACLES", "Feature", "Layout", "LevelConfig", "generate_level", "level_layout", "make_world",
           "render_layout"]


def _roof_base(layout: Layout, s: np.ndarray, reach: float) -> np.ndarray:
    """Highest floor level within `reach` along the route of each s: a roof over it keeps its height above both
    sides of a step or a ramp's end."""
    level = layout.floor_level(s)
    best = np.maximum(level, np.maximum(layout.floor_level(s - reach), layout.floor_level(s + reach)))
    for f in layout.features:
        if f.kind in ("step", "ramp"):
            for b in (f.begin, f.end):
                peak = float(max(layout.floor_level(b - 1e-9), layout.floor_level(b)))
                best = np.where(np.abs(s - b) <= reach, np.maximum(best, peak), best)
    return best


def render_layout(layout: Layout, config: LevelConfig = LevelConfig()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(floor, ceiling, origin) of a layout: float32 maps at `config.resolution` and the x, y of sample [0, 0]."""
    res, half = config.resolution, layout.width / 2
    line = layout.centre_line
    seg = np.diff(line, axis=0)
    lengths = np.linalg.norm(seg, axis=1)
    unit = seg / lengths[:, None]
    normal = np.stack([-unit[:, 1], unit[:, 0]], 1)
    corners = [line[:-1] + half * normal, line[:-1] - half * normal, line[1:] + half * normal,
               line[1:] - half * normal, line[1:-1] + half, line[1:-1] - half]  # legs' rectangles, bends' round sides
    lo, hi = np.min([c.min(0) for c in corners if len(c)], 0), np.max([c.max(0) for c in corners if len(c)], 0)
    origin = res * np.floor((lo - config.wall_thickness) / res + 1e-9)
    shape = np.ceil((hi + config.wall_thickness - origin) / res - 1e-9).astype(int) + 1
    xs, ys = origin[0] + res * np.arange(shape[0]), origin[1] + res * np.arange(shape[1])
    p = np.stack(np.meshgrid(xs, ys, indexing="ij"), -1)
    s0 = np.concatenate([[0.0], np.cumsum(lengths)[:-1]]) - layout.end_margin
    rel = p[None] - line[:-1, None, None, :]  # (segments, nx, ny, 2)
    t = np.einsum("kxyc,kc->kxy", rel, unit)
    v = np.einsum("kxyc,kc->kxy", rel, normal)
    tc = np.clip(t, 0.0, lengths[:, None, None])
    inside = np.any((t >= -1e-9) & (t <= lengths[:, None, None] + 1e-9) & (np.abs(v) <= half + 1e-9), axis=0)
    for corner in line[1:-1]:  # the outer side of each bend
        inside |= np.hypot(p[..., 0] - corner[0], p[..., 1] - corner[1]) <= half + 1e-9
    nearest = np.argmin(np.hypot(t - tc, v), axis=0)
    s = np.take_along_axis(s0[:, None, None] + tc, nearest[None], 0)[0]

    level = layout.floor_level(s)
    floor = level.copy()
    ceiling = _roof_base(layout, s, config.feature_spacing / 2) + (config.open_sky if layout.roof is None
                                                                   else layout.roof)
    solid = ~inside
    for f in layout.features:
        k = int(np.clip(np.searchsorted(s0, f.begin, side="right") - 1, 0, len(seg) - 1))
        if f.kind == "void":
            floor = np.where((s >= f.begin - 1e-9) & (s <= f.end + 1e-9), level - f.value, floor)
        elif f.kind in ("crawl", "bar"):
            centre, width = (f.begin + f.end) / 2, f.end - f.begin
            if f.kind == "bar":  # a thin bar on a slanted leg keeps at least one sample in every row across
                width = max(width, res * (abs(unit[k, 0]) + abs(unit[k, 1])))
            band = np.abs(s - centre) <= width / 2 + 1e-9
            ceiling = np.where(band, np.minimum(ceiling, level + f.value), ceiling)
        for sc, vc, hs, hv, rnd in f.solids:
            ds, dv = s0[k] + t[k] - sc, v[k] - vc
            solid |= (np.hypot(ds, dv) <= hs + 1e-9) if rnd else (np.maximum(np.abs(ds) - hs, np.abs(dv) - hv) <= 1e-9)
    top = float(ceiling[~solid].max())
    floor, ceiling = np.where(solid, top, floor), np.where(solid, top, ceiling)
    return floor.astype(np.float32), ceiling.astype(np.float32), origin


def generate_level(seed: int, level: int, config: LevelConfig = LevelConfig()) -> World:
    """The world of (seed, level): tunnels at level 0, else `render_layout(level_layout(...))`; the same inputs
    always give the same arrays."""
    config.validate()
    check_level(level)
    if seed < 0:
        raise WorldError(f"seed must be >= 0, got {seed}")
    if level == 0:
        return dataclasses.replace(generate_world(seed, seed % 3, config.tunnels), difficulty=0)
    layout = level_layout(seed, level, config)
    floor, ceiling, origin = render_layout(layout, config)
    ends = [np.zeros(2), layout.point(layout.length)]  # the start lies at the origin
    z = layout.floor_level(np.array([0.0, layout.length])) + config.body_height
    if np.any(ceiling[ceiling > floor + 1e-6] - floor[ceiling > floor + 1e-6] < config.min_clearance - 1e-6):
        raise WorldError(f"internal: level {level} world of seed {seed} has a gap below {config.min_clearance} m")
    return World(floor=floor, ceiling=ceiling, resolution=config.resolution, origin=origin,
                 start=np.array([*ends[0], z[0]]), goal=np.array([*ends[1], z[1]]),
                 source=f"level {level} world", seed=int(seed), difficulty=int(level))


def make_world(seed: int, difficulty: int, tunnels: WorldConfig, levels: LevelConfig | None) -> World:
    """A generated world: today's tunnels `generate_world(seed, difficulty, tunnels)` when `levels` is None, else
    the level world `generate_level(seed, difficulty, levels)` (difficulty 0-4)."""
    if levels is None:
        return generate_world(seed, difficulty, tunnels)
    check_level(difficulty)
    return generate_level(seed, difficulty, levels)
