"""Floor and ceiling height scans by exact look-up in the height maps.

MuJoCo draws a height field as two triangles per cell, split along the diagonal from sample (i, j)
to (i + 1, j + 1). The ceiling is a height field turned over about x, which mirrors y, so its cells
are split along the other diagonal. `surface_height` interpolates on exactly those triangles, so a
scan equals what `mujoco.mj_ray` returns on the compiled scene (tests/test_heightscan.py).
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class ScanConfig:
    """Grid of height-scan points in the yaw-aligned body frame (metres)."""

    x_range: tuple[float, float] = (0.1, 1.0)
    """First and last scan row along the heading (front rows of the paper's [-1, 1] grid)."""
    y_range: tuple[float, float] = (-0.5, 0.5)
    """First and last scan column across the heading."""
    spacing: float = 0.1
    """Distance between scan points."""
    clip: float = 0.5
    """Scans are heights relative to the base, clipped to [-clip, clip]."""
    ceiling_clip: float | None = None
    """When set, the ceiling scan is clipped to [-clip, ceiling_clip] instead: a roof higher than this above the
    base constrains no body pose, so roofs at any height beyond it and open sky read the same (None: `clip`)."""

    def points(self) -> np.ndarray:
        """Scan points as an (n, 2) array, rows along x then columns along y."""
        xs = np.arange(self.x_range[0], self.x_range[1] + 1e-9, self.spacing)
        ys = np.arange(self.y_range[0], self.y_range[1] + 1e-9, self.spacing)
        return np.stack(np.meshgrid(xs, ys, indexing="ij"), -1).reshape(-1, 2)

    @property
    def num_points(self) -> int:
        """Points per layer."""
        return len(self.points())


def surface_height(grid, origin, resolution, xy, anti_diagonal: bool = False):
    """Height of a triangulated height map at world points xy (..., 2); works on numpy and jax arrays.

    `anti_diagonal` selects the split of each cell used by a height field turned upside down.
    Points outside the map take the height of its border.
    """
    xp = jnp if not isinstance(grid, np.ndarray) else np
    nx, ny = grid.shape
    f = (xy - origin) / resolution
    # minimum/maximum rather than clip: the same result, and numpy's clip is slow on small arrays.
    fx = xp.minimum(xp.maximum(f[..., 0], 0.0), nx - 1.0)
    fy = xp.minimum(xp.maximum(f[..., 1], 0.0), ny - 1.0)
    i = xp.minimum(xp.floor(fx).astype(np.int32), nx - 2)
    j = xp.minimum(xp.floor(fy).astype(np.int32), ny - 2)
    u, v = fx - i, fy - j
    h00, h10 = grid[i, j], grid[i + 1, j]
    h01, h11 = grid[i, j + 1], grid[i + 1, j + 1]
    if anti_diagonal:
        low = h00 + u * (h10 - h00) + v * (h01 - h00)
        high = h11 + (1 - u) * (h01 - h11) + (1 - v) * (h10 - h11)
        return xp.where(u + v <= 1.0, low, high)
    below = h00 + u * (h10 - h00) + v * (h11 - h10)
    above = h00 + v * (h01 - h00) + u * (h11 - h01)
    return xp.where(u >= v, below, above)


def scan_points_world(base_pos, yaw, points):
    """Scan points (n, 2) in the yaw frame of a base at base_pos -> world x, y (n, 2)."""
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    x = base_pos[0] + c * points[:, 0] - s * points[:, 1]
    y = base_pos[1] + s * points[:, 0] + c * points[:, 1]
    return jnp.stack([x, y], -1)
