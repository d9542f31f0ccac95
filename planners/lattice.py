"""A complete search over (x, y, yaw) on the height maps' own grid: the planner for narrow corridors.

Tree planners find a corridor only a little wider than the robot by luck (their samples must land in
it). Here every grid cell and every one of `YAW_BINS` headings is checked at once with image filters: a
level body at a heading fits at a cell when the band of heights it may take (above the floor under its
footprint, below the ceiling over it, legs within reach; planners.pose_band) is not empty. The footprint
is enlarged by one cell, so the filters are conservative for the bilinear height look-ups. Dijkstra's
algorithm (scipy) then finds the shortest chain of cells and turns, which is shortcut with the exact
motion check and handed back as states of the projected space. The lattice (valid nodes and graph) is
built once per BodyChecker and reused, so replanning on the same maps only runs the search.
"""

from __future__ import annotations

import math
import weakref

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

from planners.body_check import BodyChecker, widest_band

YAW_BINS = 16
"""Headings searched (every 22.5 degrees)."""

_LATTICES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Per BodyChecker: {angle_weight: (valid nodes, graph)}, freed with the checker."""


def _footprint(half_x: float, half_y: float, yaw: float, res: float, centre=(0.0, 0.0)) -> np.ndarray:
    """Boolean kernel (centred on the body's cell) of the cells a rectangle may touch: half extents + one cell, centred
    at `centre` in the body frame, the body turned by `yaw`."""
    hx, hy = half_x + res, half_y + res
    cos, sin = math.cos(yaw), math.sin(yaw)
    cx, cy = cos * centre[0] - sin * centre[1], sin * centre[0] + cos * centre[1]
    reach = int(math.ceil((abs(cx) + abs(hx * cos) + abs(hy * sin)) / res)) + 1
    reach_y = int(math.ceil((abs(cy) + abs(hx * sin) + abs(hy * cos)) / res)) + 1
    dx, dy = np.meshgrid(np.arange(-reach, reach + 1) * res, np.arange(-reach_y, reach_y + 1) * res, indexing="ij")
    u = dx * cos + dy * sin
    v = -dx * sin + dy * cos
    return (np.abs(u - centre[0]) <= hx) & (np.abs(v - centre[1]) <= hy)


def _shifted(field: np.ndarray, di: int, dj: int, fill: float) -> np.ndarray:
    """field[i + di, j + dj] at every (i, j) (fill off the grid)."""
    out = np.full_like(field, fill)
    nx, ny = field.shape
    src_i, dst_i = slice(max(di, 0), nx + min(di, 0)), slice(max(-di, 0), nx - max(di, 0))
    src_j, dst_j = slice(max(dj, 0), ny + min(dj, 0)), slice(max(-dj, 0), ny - max(dj, 0))
    out[dst_i, dst_j] = field[src_i, src_j]
    return out


def _foot_range(floor: np.ndarray, offset: np.ndarray, res: float) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest floor sample around a point `offset` (x, y) from every cell (bilinear bounds)."""
    i0, j0 = math.floor(offset[0] / res), math.floor(offset[1] / res)
    corners = [_shifted(floor, i0 + a, j0 + b, np.nan) for a in (0, 1) for b in (0, 1)]
    return np.min(corners, axis=0), np.max(corners, axis=0)


def valid_grid(checker: BodyChecker) -> np.ndarray:
    """valid[k, i, j]: a level body centred on cell (i, j) at heading k * 2 pi / YAW_BINS fits (conservative)."""
    maps, res = checker.maps, checker.maps.resolution
    floor, ceiling = np.asarray(maps.floor, float), np.asarray(maps.ceiling, float)
    hx, hy, hz = checker.half_extents
    lo, hi = checker.height_range
    out = np.zeros((YAW_BINS,) + floor.shape, bool)
    for k in range(YAW_BINS):
        yaw = 2 * math.pi * k / YAW_BINS
        kernel = _footprint(hx, hy, yaw, res)
        low = ndimage.maximum_filter(floor, footprint=kernel, mode="constant", cval=np.inf) + hz
        if checker.leg_rectangle is not None:  # the legs' rectangle at knee height above the floor too
            x0, y0, x1, y1, depth = checker.leg_rectangle
            legs = _footprint((x1 - x0) / 2, (y1 - y0) / 2, yaw, res, ((x0 + x1) / 2, (y0 + y1) / 2))
            low = np.maximum(low, ndimage.maximum_filter(floor, footprint=legs, mode="constant", cval=np.inf) - depth)
        high = ndimage.minimum_filter(ceiling, footprint=kernel, mode="constant", cval=-np.inf) - hz
        if checker.config.check_heights:  # each foot's reach from the lowest and highest floor around it
            rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
            ranges = [[_foot_range(floor, rot @ p[:2], res) for p in points] for points in checker.stance_choices]
            g_min = np.stack([np.stack([r[0] for r in choice], -1) for choice in ranges], -1)  # (nx, ny, F, C)
            g_max = np.stack([np.stack([r[1] for r in choice], -1) for choice in ranges], -1)
            starts = np.where(np.isnan(g_max), np.inf, g_max + lo)
            ends = np.where(np.isnan(g_min), -np.inf, g_min + hi)
            fits = np.flatnonzero(high >= low)  # only where the box fits, in chunks (the band is 272 numbers a cell)
            for chunk in np.array_split(fits, max(1, len(fits) // 8192)):
                cell = np.unravel_index(chunk, floor.shape)
                z_low, z_high = widest_band(low[cell], high[cell], starts[cell], ends[cell])
                out[k][cell] = z_high >= z_low
        else:
            out[k] = high >= low
    return out


def _graph(valid: np.ndarray, res: float, angle_weight: float) -> sparse.csr_matrix:
    """Edges between valid lattice nodes: the 8 neighbouring cells at one heading, and the next headings."""
    shape, n = valid.shape, valid.size
    index = np.arange(n).reshape(shape)
    rows, cols, costs = [], [], []
    moves = [(0, di, dj, res * math.hypot(di, dj)) for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj]
    moves += [(dk, 0, 0, angle_weight * 2 * math.pi / YAW_BINS) for dk in (-1, 1)]
    k, i, j = np.nonzero(valid)
    for dk, di, dj, cost in moves:
        k2, i2, j2 = (k + dk) % shape[0], i + di, j + dj
        inside = (i2 >= 0) & (i2 < shape[1]) & (j2 >= 0) & (j2 < shape[2])
        ok = inside.copy()
        ok[inside] = valid[k2[inside], i2[inside], j2[inside]]
        rows.append(index[k[ok], i[ok], j[ok]])
        cols.append(index[k2[ok], i2[ok], j2[ok]])
        costs.append(np.full(ok.sum(), cost))
    return sparse.csr_matrix((np.concatenate(costs), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def lattice_of(checker: BodyChecker, angle_weight: float) -> tuple[np.ndarray, sparse.csr_matrix]:
    """(valid nodes, graph) of the checker's maps, built on first use and kept while the checker lives."""
    built = _LATTICES.setdefault(checker, {})
    if angle_weight not in built:
        valid = next(iter(built.values()))[0] if built else valid_grid(checker)
        built[angle_weight] = valid, _graph(valid, checker.maps.resolution, angle_weight)
    return built[angle_weight]


def _nearby_nodes(valid: np.ndarray, maps, pose) -> list[tuple[int, int, int]]:
    """Valid lattice nodes around a pose (its own cell and heading first, then the neighbours)."""
    k0 = int(round(pose[5] / (2 * math.pi / YAW_BINS))) % YAW_BINS
    i0, j0 = np.rint((np.asarray(pose[:2]) - maps.origin) / maps.resolution).astype(int)
    out = []
    for dk in (0, -1, 1):
        for di in (0, -1, 1, -2, 2):
            for dj in (0, -1, 1, -2, 2):
                k, i, j = (k0 + dk) % YAW_BINS, i0 + di, j0 + dj
                if 0 <= i < valid.shape[1] and 0 <= j < valid.shape[2] and valid[k, i, j]:
                    out.append((k, i, j))
    return out


def lattice_path(space, checker: BodyChecker, start_pose, goal_pose, check_step: float,
                 angle_weight: float) -> np.ndarray | None:
    """States of `space` (a ProjectedSpace) from start to goal through the lattice, shortcut; None if the
    lattice holds no path."""
    maps, res = checker.maps, checker.maps.resolution
    valid, graph = lattice_of(checker, angle_weight)
    vector_of = lambda node: space.to_vector(np.array([maps.origin[0] + node[1] * res, maps.origin[1] + node[2] * res,
                                                       0.0, 0.0, 0.0, 2 * math.pi * node[0] / YAW_BINS]))
    start, goal = space.to_vector(start_pose), space.to_vector(goal_pose)
    motion_ok = lambda a, b: bool(space.valid(_line(a, b, check_step)).all())
    def connected(nodes, end, outward):  # the nodes a straight motion joins to `end`, checked in one batch
        lines = [_line(end, vector_of(n), check_step) if outward else _line(vector_of(n), end, check_step)
                 for n in nodes]
        if not lines:
            return []
        ok = space.valid(np.concatenate(lines))
        bounds = np.cumsum([0] + [len(line) for line in lines])
        return [n for n, a, b in zip(nodes, bounds[:-1], bounds[1:]) if ok[a:b].all()]
    entries = connected(_nearby_nodes(valid, maps, start_pose), start, True)
    exits = connected(_nearby_nodes(valid, maps, goal_pose), goal, False)
    if not entries or not exits:
        return None
    index = lambda node: np.ravel_multi_index(node, valid.shape)
    dist, pred, _ = csgraph.dijkstra(graph, indices=[index(n) for n in entries], min_only=True,
                                     return_predecessors=True)
    ends = [index(n) for n in exits]
    best = min(ends, key=lambda e: dist[e])
    if not np.isfinite(dist[best]):
        return None
    chain = [best]
    while pred[chain[-1]] >= 0:
        chain.append(pred[chain[-1]])
    nodes = [np.unravel_index(c, valid.shape) for c in reversed(chain)]
    states = [start] + [vector_of(n) for n in nodes] + [goal]
    def grid_ok(a, b):  # cheap, near-exact: every state on the line rounds to a valid lattice node
        line = _line(a, b, res / 2)
        poses = space._xy_yaw(line)
        i = np.rint((poses[:, 0] - maps.origin[0]) / res).astype(int)
        j = np.rint((poses[:, 1] - maps.origin[1]) / res).astype(int)
        k = np.rint(poses[:, 2] / (2 * math.pi / YAW_BINS)).astype(int) % YAW_BINS
        inside = (i >= 0) & (i < valid.shape[1]) & (j >= 0) & (j < valid.shape[2])
        return bool(inside.all() and valid[k, i, j].all())
    return shortcut(np.array(states), grid_ok, motion_ok)


def _line(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    n = max(int(math.ceil(np.linalg.norm(b - a) / step)), 1)
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


def shortcut(states: np.ndarray, cheap_ok, exact_ok) -> np.ndarray:
    """Greedy shortcutting: from each kept state, jump to the farthest later state that a straight motion
    reaches (bisection on the index with the cheap check, then confirmed by the exact one, stepping back
    while it fails; the next state is always reachable)."""
    kept, i = [states[0]], 0
    while i < len(states) - 1:
        lo, hi = i + 1, len(states) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if cheap_ok(states[i], states[mid]):
                lo = mid
            else:
                hi = mid - 1
        while lo > i + 1 and not exact_ok(states[i], states[lo]):
            lo = max(i + 1, (i + lo) // 2)
        kept.append(states[lo])
        i = lo
    return np.array(kept)
