"""Waypoint paths as arrays: what the planner hands to the confined-space environments."""

from __future__ import annotations

import numpy as np

from legged.worlds.terrain import Terrain


def straight_path(start, goal, spacing: float) -> np.ndarray:
    """Body poses (x, y, z, roll, pitch, yaw) from start to goal on a straight line, `spacing` apart."""
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    n = max(int(np.ceil(np.linalg.norm(goal - start) / spacing)), 1) + 1
    xyz = start + np.linspace(0.0, 1.0, n)[:, None] * (goal - start)
    yaw = np.arctan2(goal[1] - start[1], goal[0] - start[0])
    return np.concatenate([xyz, np.zeros((n, 2)), np.full((n, 1), yaw)], 1)


def pad_paths(paths: list[np.ndarray], terrain: Terrain, capacity: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Stack one path per terrain tile into (n_tiles, max(longest, capacity), 6) plus lengths; checks end
    points. `capacity` leaves room for longer paths handed in later (replans)."""
    if len(paths) != terrain.num_tiles:
        raise ValueError(f"got {len(paths)} waypoint paths for a terrain of {terrain.num_tiles} worlds")
    longest = max(max(len(p) for p in paths), capacity)
    out = np.zeros((len(paths), longest, 6), np.float32)
    for k, p in enumerate(paths):
        p = np.asarray(p, np.float32)
        if p.ndim != 2 or p.shape[1] != 6 or len(p) < 2:
            raise ValueError(f"path {k} must be an (n >= 2, 6) array of x, y, z, roll, pitch, yaw; got {p.shape}")
        if np.linalg.norm(p[-1, :2] - terrain.goals[k, :2]) > 0.05:
            raise ValueError(f"path {k} ends at {p[-1, :2]} but world {k}'s goal is {terrain.goals[k, :2]}")
        out[k, :len(p)] = p
        out[k, len(p):] = p[-1]
    return out, np.array([len(p) for p in paths], np.int32)
