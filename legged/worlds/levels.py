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

The ranges are the fields of `LevelConfig`. A world is drawn in two steps: `level_layout` draws the corridor and
its features as numbers (a `Layout`), `render_layout` samples that onto floor and ceiling maps with the
conventions of legged.worlds.generator (row index along x; walls where floor == ceiling == the top value).
The route leaves the start (at the origin) along +x, the way the environments spawn the robot facing.
Features lie on the straight parts of the route, never within `free_radius` of start or goal nor within
`feature_spacing` of one another along the route. Roof, bar and crawl heights are measured from the local floor
level, which steps and ramps move (the roof also keeps its height over the upper side of a step).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from legged.worlds.generator import World, WorldConfig, WorldError, generate_world

LEVELS = (0, 1, 2, 3, 4)
"""The difficulty levels `generate_level` knows."""
OBSTACLES = ("bar", "block", "pillars")
"""Obstacle kinds of levels 2 and up."""
_STREAM = 0x1E7E15
"""Third entropy word of the level generator's random stream (apart from other streams of the same seed)."""
_BEND_MARGIN = 0.1
"""Clearance between a bend's overlap zone and the nearest feature along the route, metres."""


@dataclasses.dataclass(frozen=True)
class LevelConfig:
    """Parameters of the level generator: lengths in metres, angles in degrees; (lo, hi) pairs are uniform ranges
    (inclusive integer ranges for counts)."""

    tunnels: WorldConfig = WorldConfig()
    """Level 0: the pyramid-tunnel generator's parameters."""
    resolution: float = 0.05
    """Horizontal spacing of the height-map samples."""
    wall_thickness: float = 0.1
    """Solid wall kept around the free space."""
    end_margin: float = 0.5
    """Free corridor beyond start and goal before the closing walls."""
    route_length: tuple[float, float] = (3.0, 6.0)
    """Start-to-goal length along the centre line."""
    width: tuple[float, float] = (0.5, 2.0)
    """Corridor width (raised to `block_corridor_width` / `pillar_corridor_width` where those obstacles appear)."""
    roof: tuple[float, float] = (0.4, 1.0)
    """Roof height above the floor."""
    open_sky_fraction: float = 0.25
    """Share of worlds with no roof (the ceiling at `open_sky`)."""
    open_sky: float = 1.5
    """Ceiling height above the floor under open sky."""
    crawl_fraction: float = 0.5
    """Share of worlds with a low section."""
    crawl_length: tuple[float, float] = (0.5, 1.5)
    """Length of the low section along the route."""
    crawl_roof: tuple[float, float] = (0.30, 0.40)
    """Roof height over the low section (capped 2 cm below the roof)."""
    obstacles: tuple[int, int] = (1, 4)
    """Number of obstacles (bars, side blocks, pillar groups) drawn at levels 2 and up; those that find no room
    are left out."""
    bar_width: tuple[float, float] = (0.05, 0.2)
    """Width of a bar along the route."""
    bar_underside: tuple[float, float] = (0.36, 0.45)
    """Height of a bar's underside above the floor (capped 2 cm below the roof)."""
    block_length: tuple[float, float] = (0.2, 0.5)
    """Length of a side block along the route."""
    block_corridor_width: float = 0.9
    """Smallest corridor width of a world with a side block."""
    block_group: tuple[int, int] = (1, 1)
    """Number of side blocks one block obstacle holds: a slalom, each from the wall opposite the one before
    (fewer if they do not fit; (1, 1) draws exactly the worlds of runs saved before this field)."""
    block_pitch: tuple[float, float] = (1.0, 1.6)
    """Distance along the route between the centres of consecutive blocks of a group."""
    pillars: tuple[int, int] = (2, 5)
    """Number of columns in a pillar group (fewer if they do not fit)."""
    pillar_size: tuple[float, float] = (0.1, 0.25)
    """Width (square) or diameter (round) of a column."""
    pillar_spread: float = 0.7
    """Length of route a pillar group spreads over, per column."""
    pillar_corridor_width: float = 1.2
    """Smallest corridor width of a world with a pillar group."""
    min_gap: float = 0.45
    """Smallest free gap beside a side block and between columns and walls."""
    floor_features: tuple[int, int] = (1, 2)
    """Number of steps and ramps at levels 3 and up (each one a step or a ramp, even odds)."""
    step_height: tuple[float, float] = (0.03, 0.10)
    """Height of a step (up or down, even odds)."""
    ramp_angle: tuple[float, float] = (5.0, 15.0)
    """Slope of a ramp."""
    ramp_rise: tuple[float, float] = (0.03, 0.10)
    """Height a ramp climbs or descends in total."""
    turn_fractions: tuple[float, float] = (0.35, 0.35)
    """Shares of level 3 and 4 worlds whose centre line makes an L and an S turn (the rest are straight)."""
    bend_angle: tuple[float, float] = (30.0, 90.0)
    """Angle of each bend of a turn."""
    bend_blocks: float = 0.0
    """Chance that a side block (a slalom as `block_group` draws) ends where a bend's zone begins, and, drawn
    apart, that one begins where it ends (corridors at least `block_corridor_width` wide; 0: the worlds of runs saved
    before this field)."""
    voids: tuple[int, int] = (1, 2)
    """Number of voids at level 4."""
    void_width: tuple[float, float] = (0.10, 0.25)
    """Length of a void along the route (it spans the corridor's full width)."""
    void_depth: tuple[float, float] = (0.1, 1.0)
    """Depth of a void below the floor."""
    body_height: float = 0.27
    """Height of the body centre above the floor at start and goal."""
    free_radius: float = 0.35
    """No feature lies within this distance of start or goal along the route."""
    feature_spacing: float = 0.6
    """Smallest distance between two features along the route."""
    min_clearance: float = 0.30
    """Smallest ceiling-minus-floor gap allowed anywhere (roof, crawl and bar ranges must respect it)."""

    def validate(self) -> None:
        """Raise WorldError if the parameters cannot give a traversable world."""
        if self.resolution <= 0 or self.wall_thickness < self.resolution:
            raise WorldError(f"need resolution > 0 and wall_thickness >= resolution, got {self.resolution}, "
                             f"{self.wall_thickness}")
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if isinstance(value, tuple) and field.name != "turn_fractions" and not 0 <= value[0] <= value[1]:
                raise WorldError(f"{field.name} must be a range 0 <= lo <= hi, got {value}")
        for name in ("roof", "crawl_roof", "bar_underside"):
            if getattr(self, name)[0] < self.min_clearance:
                raise WorldError(f"{name} {getattr(self, name)} reaches below min_clearance {self.min_clearance}")
        if self.open_sky < self.roof[1]:
            raise WorldError(f"open_sky {self.open_sky} lies below the highest roof {self.roof[1]}")
        if not (0 <= self.open_sky_fraction <= 1 and 0 <= self.crawl_fraction <= 1 and 0 <= self.bend_blocks <= 1
                and min(self.turn_fractions) >= 0 and sum(self.turn_fractions) <= 1):
            raise WorldError("open_sky_fraction, crawl_fraction, bend_blocks and turn_fractions must be shares in "
                             "[0, 1]")
        if self.width[0] <= 0 or self.pillar_corridor_width < 2 * self.min_gap + self.pillar_size[1]:
            raise WorldError(f"need width > 0 and pillar_corridor_width >= 2 * min_gap + the largest pillar "
                             f"({2 * self.min_gap + self.pillar_size[1]:.2f} m)")
        if self.block_corridor_width < self.min_gap + self.resolution:
            raise WorldError(f"block_corridor_width must exceed min_gap {self.min_gap}")
        if self.block_group[0] < 1 or self.block_pitch[0] < self.block_length[1] + self.min_gap:
            raise WorldError(f"need block_group >= 1 and block_pitch at least the longest block plus min_gap "
                             f"({self.block_length[1] + self.min_gap:.2f} m), got {self.block_group}, "
                             f"{self.block_pitch}")
        if self.bend_angle[1] > 90.0 or self.ramp_angle[1] >= 90.0:
            raise WorldError("bend_angle is at most 90 degrees and ramp_angle below 90")


@dataclasses.dataclass(frozen=True)
class Feature:
    """One feature of a level world, placed along the route (s: arc length along the centre line from the start)."""

    kind: str
    """crawl, bar, block, pillars, step, ramp or void."""
    begin: float
    """s where it begins."""
    end: float
    """s where it ends (equal to `begin` for a step)."""
    value: float = 0.0
    """crawl: its roof height; bar: its underside; step, ramp: the rise (negative: down); void: its depth;
    block: the narrowest gap its blocks leave; pillars: unused (0)."""
    solids: tuple = ()
    """block, pillars: solid columns as (s, v, half length along, half width across, round) in route coordinates
    (v: distance to the left of the centre line); a block obstacle holds one per block of its group."""


@dataclasses.dataclass(frozen=True)
class Layout:
    """A level world as numbers: the corridor's centre line, width and roof, and its features."""

    level: int
    """Difficulty level."""
    centre_line: np.ndarray
    """(n, 2) polyline from `end_margin` behind the start (at the origin, heading +x) to as far beyond the goal."""
    end_margin: float
    """Length of the centre line behind the start and beyond the goal."""
    length: float
    """Start-to-goal length along the centre line."""
    width: float
    """Corridor width."""
    roof: float | None
    """Roof height above the floor, None under open sky."""
    features: tuple[Feature, ...]
    """Features in the order they were drawn."""
    bends: tuple[float, ...] = ()
    """Signed angle of each bend of the centre line, degrees (positive: left)."""

    def kinds(self) -> list[str]:
        """Kind of every feature."""
        return [f.kind for f in self.features]

    def point(self, s: float) -> np.ndarray:
        """World x, y of the centre line at arc length `s` from the start."""
        seg = np.diff(self.centre_line, axis=0)
        lengths = np.linalg.norm(seg, axis=1)
        s0 = np.concatenate([[0.0], np.cumsum(lengths)[:-1]]) - self.end_margin
        k = int(np.clip(np.searchsorted(s0, s, side="right") - 1, 0, len(seg) - 1))
        return self.centre_line[k] + (s - s0[k]) / lengths[k] * seg[k]

    def floor_level(self, s) -> np.ndarray:
        """Floor height along the route (steps and ramps; voids not included)."""
        s = np.asarray(s, np.float64)
        level = np.zeros_like(s)
        for f in self.features:
            if f.kind == "step":
                level = level + np.where(s >= f.begin, f.value, 0.0)
            elif f.kind == "ramp":
                level = level + f.value * np.clip((s - f.begin) / (f.end - f.begin), 0.0, 1.0)
        return level


def _check_level(level: int) -> None:
    if level not in LEVELS:
        raise WorldError(f"level must be one of {', '.join(map(str, LEVELS))}, got {level}")


def _take(free: list[tuple[float, float]], a: float, b: float) -> list[tuple[float, float]]:
    """The intervals `free` less [a, b]."""
    out = []
    for lo, hi in free:
        if b <= lo or a >= hi:
            out.append((lo, hi))
            continue
        if a > lo:
            out.append((lo, a))
        if b < hi:
            out.append((b, hi))
    return out


def _place(rng, free: list[tuple[float, float]], size: float) -> float | None:
    """A uniformly drawn begin of an interval `size` long inside one of the `free` intervals, or None."""
    spans = [(lo, hi - size) for lo, hi in free if hi - lo >= size]
    if not spans:
        return None
    room = np.array([hi - lo for lo, hi in spans])
    pick = rng.uniform(0.0, room.sum())
    k = int(min(np.searchsorted(np.cumsum(room), pick), len(spans) - 1))
    return float(min(spans[k][0] + pick - (room[:k].sum()), spans[k][1]))


def _turn(rng, c: LevelConfig, level: int, width: float) -> list[tuple[float, float]]:
    """Bends of the centre line as (signed angle in radians, half length of the zone around it kept free of
    features): none, one (an L) or two of opposite signs (an S)."""
    if level < 3:
        return []
    u, sign = rng.uniform(), rng.choice([-1.0, 1.0])
    angles = [sign * math.radians(rng.uniform(*c.bend_angle)), -sign * math.radians(rng.uniform(*c.bend_angle))]
    count = 2 if u < c.turn_fractions[1] else 1 if u < sum(c.turn_fractions) else 0
    return [(a, width / 2 * math.tan(abs(a) / 2) + _BEND_MARGIN) for a in angles[:count]]


def _pillar_group(rng, c: LevelConfig, width: float, room: float) -> tuple[float, tuple]:
    """Columns of one pillar group within `room` of route as (span along the route, solids relative to the span's
    begin); fewer columns than drawn if they do not fit, none if fewer than `pillars[0]` fit."""
    count = int(rng.integers(c.pillars[0], c.pillars[1] + 1))
    spread = min(c.pillar_spread * count, room) - c.pillar_size[1] * math.sqrt(2.0)
    placed = []  # (s, v, half, round, reach): reach = radius of the circle around the column
    for _ in range(count):
        for _try in range(30):
            half, rnd = rng.uniform(*c.pillar_size) / 2, bool(rng.uniform() < 0.5)
            reach = half if rnd else half * math.sqrt(2.0)
            s, v = rng.uniform(0.0, max(spread, 0.0)), rng.uniform(-1.0, 1.0) * max(width / 2 - c.min_gap - half, 0.0)
            if all(math.hypot(s - p[0], v - p[1]) >= reach + p[4] + c.min_gap for p in placed):
                placed.append((s, v, half, rnd, reach))
                break
    if len(placed) < max(c.pillars[0], 1):
        return 0.0, ()
    lo = min(p[0] - p[4] for p in placed)
    span = max(p[0] + p[4] for p in placed) - lo
    return span, tuple((p[0] - lo, p[1], p[2], p[2], p[3]) for p in placed)


def _block_group(rng, c: LevelConfig, width: float) -> tuple[float, float, tuple]:
    """(span along the route, the narrowest gap, solids relative to the span's begin) of a block obstacle: one side
    block, or with `block_group` above 1 a slalom of blocks from alternate walls `block_pitch` apart."""
    solids, gaps = [], []
    count = 1 if c.block_group[1] == 1 else int(rng.integers(c.block_group[0], c.block_group[1] + 1))
    for k in range(count):  # the draws of the first block are those of a single one
        size, gap = rng.uniform(*c.block_length), rng.uniform(c.min_gap, max(c.min_gap, width / 2))
        side = float(rng.choice([-1.0, 1.0])) if k == 0 else -math.copysign(1.0, solids[-1][1])
        centre = solids[-1][0] + rng.uniform(*c.block_pitch) if k else size / 2
        depth = width / 2 - gap / 2 + c.wall_thickness / 2  # half width across, reaching into the wall
        solids.append((centre, side * (width / 2 + c.wall_thickness - depth), size / 2, depth, False))
        gaps.append(gap)
    return solids[-1][0] + solids[-1][2], min(gaps), tuple(solids)


def _fit_group(solids: tuple, gap: float, width: float, room: float) -> tuple[tuple, float]:
    """The blocks of a group (solids relative to its begin) that fit in `room` of route (at least the first), and
    the narrowest gap the kept ones leave."""
    if solids[-1][0] + solids[-1][2] <= room:
        return solids, gap
    while len(solids) > 1 and solids[-1][0] + solids[-1][2] > room:
        solids = solids[:-1]
    return solids, min(width / 2 + abs(v) - hv for _, v, _, hv, _ in solids)


def _bend_blocks(rng, c: LevelConfig, width: float, free: list, zone: tuple[float, float]) -> tuple[list, list]:
    """(free intervals left, block features) for the blocks `bend_blocks` puts against a bend's `zone` (begin, end):
    one ending where the zone begins, one beginning where it ends, each drawn apart and kept where it fits."""
    features = []
    for before in (True, False):
        if rng.uniform() >= c.bend_blocks:
            continue
        _, gap, solids = _block_group(rng, c, width)
        room = next((hi - lo for lo, hi in free if abs((hi if before else lo) - zone[0 if before else 1]) < 1e-9), 0.0)
        solids, gap = _fit_group(solids, gap, width, room)
        size = solids[-1][0] + solids[-1][2]
        if size > room:
            continue
        begin = zone[0] - size if before else zone[1]
        free = _take(free, begin - c.feature_spacing * before, begin + size + c.feature_spacing * (not before))
        features.append(Feature("block", begin, begin + size, float(gap),
                                tuple((begin + s, v, hs, hv, r) for s, v, hs, hv, r in solids)))
    return free, features


def level_layout(seed: int, level: int, config: LevelConfig = LevelConfig()) -> Layout:
    """The layout of level world (seed, level) for levels 1-4; the same inputs always give the same layout."""
    config.validate()
    _check_level(level)
    if level == 0:
        raise WorldError("level 0 worlds are the tunnels of generate_world; they have no layout")
    if seed < 0:
        raise WorldError(f"seed must be >= 0, got {seed}")
    c, rng = config, np.random.default_rng([int(seed), int(level), _STREAM])
    length = rng.uniform(*c.route_length)
    kinds = [str(k) for k in rng.choice(OBSTACLES, int(rng.integers(c.obstacles[0], c.obstacles[1] + 1)))] \
        if level >= 2 else []
    w_lo = c.width[0]
    if "block" in kinds:
        w_lo = max(w_lo, c.block_corridor_width)
    if "pillars" in kinds:
        w_lo = max(w_lo, c.pillar_corridor_width)
    width = rng.uniform(w_lo, max(w_lo, c.width[1]))
    roof = None if rng.uniform() < c.open_sky_fraction else rng.uniform(*c.roof)
    ceiling = c.open_sky if roof is None else roof

    drawn = []  # (kind, size along the route, value, solids relative to the begin), placed in this order
    if level >= 4:
        for _ in range(int(rng.integers(c.voids[0], c.voids[1] + 1))):
            drawn.append(("void", rng.uniform(*c.void_width), rng.uniform(*c.void_depth), ()))
    drawn += [("bend", 2 * zone, angle, ()) for angle, zone in _turn(rng, c, level, width)]
    if level >= 3:
        for _ in range(int(rng.integers(c.floor_features[0], c.floor_features[1] + 1))):
            sign = rng.choice([-1.0, 1.0])
            if rng.uniform() < 0.5:
                drawn.append(("step", 0.0, sign * rng.uniform(*c.step_height), ()))
            else:
                slope, rise = math.radians(rng.uniform(*c.ramp_angle)), rng.uniform(*c.ramp_rise)
                drawn.append(("ramp", rise / math.tan(slope), sign * rise, ()))
    for kind in kinds:
        if kind == "bar":
            top = min(c.bar_underside[1], ceiling - 0.02)
            drawn.append(("bar", rng.uniform(*c.bar_width), rng.uniform(min(c.bar_underside[0], top), top), ()))
        elif kind == "block":
            drawn.append(("block", *_block_group(rng, c, width)))
        else:
            drawn.append(("pillars", 0.0, 0.0, ()))  # its columns are drawn once the room left is known
    if rng.uniform() < c.crawl_fraction:
        top = min(c.crawl_roof[1], ceiling - 0.02)
        drawn.append(("crawl", rng.uniform(*c.crawl_length), rng.uniform(min(c.crawl_roof[0], top), top), ()))

    edge = c.free_radius + c.resolution  # a feature's sample row must not pull the surface into the free radius
    free, features, bends = [(edge, length - edge)], [], []
    for kind, size, value, solids in drawn:
        if kind == "bend":  # a bend's zone needs no spacing to the features beside it
            begin = _place(rng, free, size)
            if begin is not None:
                free = _take(free, begin, begin + size)
                bends.append((begin + size / 2, value))
                if c.bend_blocks > 0 and width >= c.block_corridor_width:
                    free, blocks = _bend_blocks(rng, c, width, free, (begin, begin + size))
                    features += blocks
            continue
        if kind == "pillars":
            size, solids = _pillar_group(rng, c, width, max((hi - lo for lo, hi in free), default=0.0))
            if not solids:
                continue
        elif kind == "block":  # a slalom too long for the room left keeps the blocks that fit
            solids, value = _fit_group(solids, value, width, max((hi - lo for lo, hi in free), default=0.0))
            size = solids[-1][0] + solids[-1][2]
        begin = _place(rng, free, size)
        if begin is None:
            continue  # no room left for it
        free = _take(free, begin - c.feature_spacing, begin + size + c.feature_spacing)
        features.append(Feature(kind, begin, begin + size, float(value),
                                tuple((begin + s, v, hs, hv, r) for s, v, hs, hv, r in solids)))

    heading, point, line = 0.0, np.array([-c.end_margin, 0.0]), [np.array([-c.end_margin, 0.0])]
    at = -c.end_margin
    bends.sort()
    for s, angle in bends + [(length + c.end_margin, 0.0)]:
        point = point + (s - at) * np.array([math.cos(heading), math.sin(heading)])
        line.append(point)
        heading, at = heading + angle, s
    return Layout(level=level, centre_line=np.array(line), end_margin=c.end_margin, length=float(length),
                  width=float(width), roof=roof, features=tuple(features),
                  bends=tuple(math.degrees(a) for _, a in bends))


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
    _check_level(level)
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
    _check_level(difficulty)
    return generate_level(seed, difficulty, levels)
