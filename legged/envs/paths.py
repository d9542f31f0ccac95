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


def pad_speeds(speeds: list[np.ndarray | None], lengths, capacity: int, default: float) -> np.ndarray:
    """Per-waypoint speed limits (m/s) laid out like `pad_paths`' paths: (n_paths, capacity), one row per path of
    `lengths[k]` waypoints; None or NaN (no limit of its own) becomes `default`, and a row is padded with its last
    value. Each given array must have one limit per waypoint, each positive (or NaN)."""
    if len(speeds) != len(lengths):
        raise ValueError(f"got {len(speeds)} speed-limit arrays for {len(lengths)} waypoint paths")
    out = np.full((len(speeds), capacity), default, np.float32)
    for k, (s, n) in enumerate(zip(speeds, lengths)):
        if s is None:
            continue
        s = np.asarray(s, np.float64)
        if s.shape != (n,):
            raise ValueError(f"speed limits of path {k} must be one per waypoint, shape ({n},); got {s.shape}")
        if not np.all(np.isnan(s) | (s > 0)):
            raise ValueError(f"speed limits of path {k} must be positive m/s (NaN: none of its own); got {s}")
        s = np.where(np.isnan(s), default, s)
        out[k, :n] = s
        out[k, n:] = s[-1]
    return out
