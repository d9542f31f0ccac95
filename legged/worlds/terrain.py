"""Many worlds tiled into one terrain, so thousands of parallel environments share one MjModel."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from legged.worlds.generator import World, WorldConfig, WorldError
from legged.worlds.levels import LevelConfig, make_world
from legged.worlds.maps import HeightMaps


@dataclasses.dataclass(frozen=True, kw_only=True)
class Terrain(HeightMaps):
    """Height maps holding one or more worlds side by side, plus each world's start and goal."""

    ceiling_anti_diagonal: bool = True
    """The ceiling is realised as an upside-down MuJoCo height field."""
    source: str = "terrain"
    """Where the maps came from (for messages)."""
    starts: np.ndarray
    """Start of each tile's world, shape (n_tiles, 3)."""
    goals: np.ndarray
    """Goal of each tile's world, shape (n_tiles, 3)."""
    difficulties: np.ndarray
    """Difficulty level of each tile, shape (n_tiles,)."""
    ceiling_top: float
    """Highest ceiling value (used to close the ceiling and as the clip of height scans)."""

    @property
    def num_tiles(self) -> int:
        """Number of worlds in the terrain."""
        return len(self.starts)

    @property
    def shape(self) -> tuple[int, int]:
        """Number of samples along x and y."""
        return self.floor.shape

    @classmethod
    def from_worlds(cls, worlds: list[World], columns: int | None = None) -> "Terrain":
        """Tile worlds on a grid (tile k at row k // columns, column k % columns).

        Tile 0 keeps its own coordinates, so a one-world terrain is exactly that world.
        Smaller worlds are padded with solid rock (floor = ceiling).
        """
        if not worlds:
            raise WorldError("cannot build a terrain from zero worlds")
        res = worlds[0].resolution
        if any(abs(w.resolution - res) > 1e-12 for w in worlds):
            raise WorldError("all tiled worlds need the same resolution")
        columns = columns or math.ceil(math.sqrt(len(worlds)))
        rows = math.ceil(len(worlds) / columns)
        tx = max(w.shape[0] for w in worlds)
        ty = max(w.shape[1] for w in worlds)
        top = max(float(w.ceiling.max()) for w in worlds)
        floor = np.full((rows * tx, columns * ty), top, np.float32)
        ceiling = np.full_like(floor, top)
        starts, goals = [], []
        origin = np.asarray(worlds[0].origin, float)
        for k, w in enumerate(worlds):
            i0, j0 = (k // columns) * tx, (k % columns) * ty
            floor[i0:i0 + w.shape[0], j0:j0 + w.shape[1]] = w.floor
            ceiling[i0:i0 + w.shape[0], j0:j0 + w.shape[1]] = w.ceiling
            shift = origin + res * np.array([i0, j0]) - np.asarray(w.origin, float)
            starts.append(np.asarray(w.start, float) + [*shift, 0.0])
            goals.append(np.asarray(w.goal, float) + [*shift, 0.0])
        return cls(floor=floor, ceiling=ceiling, resolution=res, origin=origin, starts=np.array(starts),
                   goals=np.array(goals), difficulties=np.array([w.difficulty for w in worlds]),
                   ceiling_top=top)

    @classmethod
    def generate(cls, num_worlds: int, seed: int, difficulties=(0, 1, 2),
                 config: WorldConfig = WorldConfig(), levels: LevelConfig | None = None) -> "Terrain":
        """Generate `num_worlds` worlds, cycling through `difficulties`, and tile them: the tunnels of `config`, or
        with `levels` the level worlds d0-d4 of legged.worlds.levels (`difficulties` are then levels)."""
        worlds = [make_world(seed * 100_003 + k, difficulties[k % len(difficulties)], config, levels)
                  for k in range(num_worlds)]
        return cls.from_worlds(worlds)

    @classmethod
    def flat(cls, size: float = 20.0, resolution: float = 0.5) -> "Terrain":
        """Open flat ground (no ceiling reachable) for flat-ground tasks."""
        n = int(round(size / resolution)) + 1
        floor = np.zeros((n, n), np.float32)
        return cls(floor=floor, ceiling=floor + 2.0, resolution=resolution, origin=np.array([-size / 2] * 2),
                   starts=np.array([[0.0, 0.0, 0.0]]), goals=np.array([[0.0, 0.0, 0.0]]),
                   difficulties=np.array([0]), ceiling_top=2.0)
