"""Floor and ceiling height maps over one grid: the one height-map type of the project.

A generated `World` and a tiled `Terrain` are HeightMaps with more fields; the planner reads any of them,
or maps sampled from an MJCF scene (planners.scene_maps)."""

from __future__ import annotations

import dataclasses

import numpy as np

from legged.sensors.heightscan import surface_height


@dataclasses.dataclass(frozen=True)
class HeightMaps:
    """Two height maps over one grid: the solid floor below and the solid ceiling above the free space."""

    floor: np.ndarray
    """Floor height z (metres), shape (nx, ny); sample [i, j] lies at origin + (i, j) * resolution."""
    ceiling: np.ndarray
    """Ceiling height z, same shape; equal to the floor where the column is solid (a wall)."""
    resolution: float
    """Spacing of samples, metres."""
    origin: np.ndarray
    """World x, y of sample [0, 0]."""
    ceiling_anti_diagonal: bool = False
    """True when the ceiling is an upside-down MuJoCo height field (cells split along the other diagonal)."""
    source: str = ""
    """Where the maps came from (for messages)."""

    def __post_init__(self):
        if self.floor.ndim != 2 or self.floor.shape != self.ceiling.shape:
            raise ValueError(f"floor {self.floor.shape} and ceiling {self.ceiling.shape} must be equal 2-D arrays")
        if min(self.floor.shape) < 2:
            raise ValueError(f"height maps need at least 2 x 2 samples, got {self.floor.shape}")
        if self.resolution <= 0:
            raise ValueError(f"resolution must be > 0, got {self.resolution}")

    @classmethod
    def from_world(cls, world: "HeightMaps") -> "HeightMaps":
        """Just the maps of a World or Terrain (float64 copies of what its MJCF height fields realise)."""
        return HeightMaps(floor=np.asarray(world.floor, np.float64), ceiling=np.asarray(world.ceiling, np.float64),
                          resolution=float(world.resolution), origin=np.asarray(world.origin, np.float64),
                          ceiling_anti_diagonal=world.ceiling_anti_diagonal, source=world.source)

    @property
    def upper(self) -> np.ndarray:
        """World x, y of the last sample."""
        return self.origin + self.resolution * (np.array(self.floor.shape) - 1)

    def contains(self, xy) -> np.ndarray:
        """Whether world points xy (..., 2) lie on the map."""
        xy = np.asarray(xy, np.float64)
        return np.all((xy >= self.origin - 1e-9) & (xy <= self.upper + 1e-9), axis=-1)

    def floor_at(self, xy) -> np.ndarray:
        """Floor height under world points xy (..., 2), interpolated on the map's triangles."""
        return surface_height(self.floor, self.origin, self.resolution, np.asarray(xy, np.float64))

    def ceiling_at(self, xy) -> np.ndarray:
        """Ceiling height above world points xy (..., 2)."""
        return surface_height(self.ceiling, self.origin, self.resolution, np.asarray(xy, np.float64),
                              anti_diagonal=self.ceiling_anti_diagonal)

    def lookup(self, xy: np.ndarray, ceiling: bool = False) -> np.ndarray:
        """`floor_at` / `ceiling_at` for points (n, 2), with nan for points off the map."""
        xy = np.asarray(xy, np.float64)
        heights = self.ceiling_at(xy) if ceiling else self.floor_at(xy)
        return np.where(self.contains(xy), heights, np.nan)

    def describe_bounds(self) -> str:
        """The map's x and y ranges as text."""
        lo, hi = self.origin, self.upper
        return f"x in [{lo[0]:.2f}, {hi[0]:.2f}], y in [{lo[1]:.2f}, {hi[1]:.2f}]"
