"""A level world as numbers: `level_layout` draws the corridor's centre line, width and roof and places its
features (crawls, bars, side blocks, pillars, steps, ramps, voids) along the route (`Layout`, `Feature`);
legged.worlds.levels samples a layout onto height maps."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from legged.worlds.generator import WorldError
from legged.worlds.level_config import OBSTACLES, LevelConfig, check_level

_STREAM = 0x1E7E15
"""Third entropy word of the level generator's random stream (apart from other streams of the same seed)."""
_BEND_MARGIN = 0.1
"""Clearance between a bend's overlap zone and the nearest feature along the route, metres."""


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
    check_level(level)
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
