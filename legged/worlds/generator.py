"""Reproducible confined-space worlds: floor and ceiling height maps of random pyramids.

A world is a tunnel (length from the difficulty, 1.6 m wide) with a little free space beyond each
end, closed by solid walls. Both the floor
and the ceiling carry a grid of square pyramids (as in Xu et al., ICRA 2024): ceiling pyramids hang down
U[0.15, 0.35] m from the nominal ceiling, floor pyramids are lower bumps. The ceiling never comes
closer to the floor than `min_clearance`, and start and goal sit in flat free zones.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from legged.files import atomic_path
from legged.worlds.maps import HeightMaps


class WorldError(ValueError):
    """A world file or world configuration is unusable; the message says why."""


@dataclasses.dataclass(frozen=True)
class WorldConfig:
    """Parameters of the confined-world generator (lengths in metres)."""

    resolution: float = 0.05
    """Horizontal spacing of height-map samples."""
    tunnel_width: float = 1.6
    """Free width of the tunnel (y extent)."""
    base_length: float = 3.0
    """Tunnel length at difficulty 0; each level adds `length_per_level`."""
    length_per_level: float = 1.0
    """Extra tunnel length per difficulty level (3/4/5 m for levels 0/1/2)."""
    end_margin: float = 0.5
    """Flat free space beyond each tunnel end, so the robot fits behind the start, metres."""
    wall_thickness: float = 0.1
    """Solid wall around the free space (floor raised to the ceiling)."""
    ceiling_nominal: float = 0.5
    """Ceiling height above z = 0 where no pyramid hangs."""
    min_clearance: float = 0.32
    """Smallest allowed ceiling-minus-floor gap anywhere inside the tunnel."""
    ceiling_pyramid_height: tuple[float, float] = (0.15, 0.35)
    """Range of hanging-pyramid heights (uniform)."""
    floor_pyramid_height: tuple[float, float] = (0.02, 0.06)
    """Range of floor-bump heights at level 0 (uniform); the top grows by `floor_height_per_level`."""
    floor_height_per_level: float = 0.02
    """Extra maximum floor-bump height per difficulty level."""
    pyramid_half_width: tuple[float, float] = (0.2, 0.4)
    """Range of pyramid half widths (uniform)."""
    center_jitter: float = 0.3
    """Uniform jitter of pyramid centres around their grid cell, +- metres."""
    pyramids_per_row: int = 2
    """Pyramids across the tunnel in each row."""
    base_rows: int = 3
    """Pyramid rows at difficulty 0; one more per level."""
    endpoint_fraction: float = 0.375
    """Start at -fraction * length and goal at +fraction * length along the tunnel axis."""
    body_height: float = 0.27
    """Height of the body centre above the floor at start and goal."""
    free_radius: float = 0.35
    """Radius of the flat, pyramid-free zone around start and goal."""

    def length(self, difficulty: int) -> float:
        """Tunnel length for a difficulty level."""
        return self.base_length + self.length_per_level * difficulty

    def rows(self, difficulty: int) -> int:
        """Number of pyramid rows for a difficulty level."""
        return self.base_rows + difficulty

    def validate(self) -> None:
        """Raise WorldError if the parameters cannot give a traversable world."""
        if self.resolution <= 0:
            raise WorldError(f"resolution must be > 0, got {self.resolution}")
        if self.min_clearance <= 0 or self.min_clearance > self.ceiling_nominal:
            raise WorldError(
                f"min_clearance must be in (0, ceiling_nominal={self.ceiling_nominal}], got {self.min_clearance}")
        if self.body_height >= self.ceiling_nominal:
            raise WorldError(f"body_height {self.body_height} does not fit under the ceiling {self.ceiling_nominal}")
        if not 0 < self.endpoint_fraction < 0.5:
            raise WorldError(f"endpoint_fraction must be in (0, 0.5), got {self.endpoint_fraction}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class World(HeightMaps):
    """A confined world as data: its height maps (floor, ceiling, resolution, origin; world frame, row index
    along x; the ceiling equals the floor inside solid walls) plus start, goal and where it came from."""

    ceiling_anti_diagonal: bool = True
    """The ceiling is realised as an upside-down MuJoCo height field."""
    source: str = "generated world"
    """Where the maps came from (for messages)."""
    start: np.ndarray
    """Start position of the body centre (x, y, z)."""
    goal: np.ndarray
    """Goal position of the body centre (x, y, z)."""
    seed: int = -1
    """Seed it was generated from (-1 if not generated)."""
    difficulty: int = -1
    """Difficulty level it was generated at (-1 if not generated)."""

    @property
    def shape(self) -> tuple[int, int]:
        """Number of samples along x and y."""
        return self.floor.shape

    @property
    def size(self) -> tuple[float, float]:
        """Extent of the map along x and y, metres."""
        return ((self.shape[0] - 1) * self.resolution, (self.shape[1] - 1) * self.resolution)

    @property
    def clearance(self) -> np.ndarray:
        """Ceiling minus floor at every sample (0 inside walls)."""
        return self.ceiling - self.floor

    @property
    def min_clearance(self) -> float:
        """Smallest gap over the free (non-wall) samples."""
        c = self.clearance
        return float(c[c > 1e-6].min())

    def cell_of(self, xy) -> tuple[int, int]:
        """Nearest sample index of a world x, y."""
        ij = np.rint((np.asarray(xy, float)[:2] - self.origin) / self.resolution).astype(int)
        return int(ij[0]), int(ij[1])

    def summary(self) -> dict:
        """JSON-friendly description (size, start, goal, minimum clearance)."""
        return {
            "seed": self.seed,
            "difficulty": self.difficulty,
            "shape": list(self.shape),
            "size_m": [round(s, 4) for s in self.size],
            "resolution": self.resolution,
            "origin": [float(v) for v in self.origin],
            "start": [round(float(v), 4) for v in self.start],
            "goal": [round(float(v), 4) for v in self.goal],
            "min_clearance_m": round(self.min_clearance, 4),
        }

    def save(self, path: str | Path) -> Path:
        """Write the world as .npz (floor, ceiling, resolution, origin, start, goal, seed, difficulty)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path, suffix=".npz") as tmp:  # np.savez would append .npz to any other name
            np.savez_compressed(
                tmp, floor=self.floor, ceiling=self.ceiling, resolution=self.resolution, origin=self.origin,
                start=self.start, goal=self.goal, seed=self.seed, difficulty=self.difficulty)
        return path

    @classmethod
    def load(cls, path: str | Path) -> "World":
        """Read a world written by `save`; raises WorldError naming what is missing or wrong."""
        path = Path(path)
        if not path.is_file():
            raise WorldError(f"world file not found: {path}")
        try:
            data = np.load(path)
        except Exception as exc:  # corrupt zip, not an npz, ...
            raise WorldError(f"cannot read world file {path}: {exc}") from exc
        required = ("floor", "ceiling", "resolution", "origin", "start", "goal")
        missing = [k for k in required if k not in data.files]
        if missing:
            raise WorldError(f"world file {path} lacks arrays {missing}")
        floor, ceiling = np.asarray(data["floor"], np.float32), np.asarray(data["ceiling"], np.float32)
        if floor.ndim != 2 or floor.shape != ceiling.shape:
            raise WorldError(f"world file {path}: floor {floor.shape} and ceiling {ceiling.shape} must be equal 2-D")
        if np.any(ceiling < floor - 1e-6):
            raise WorldError(f"world file {path}: ceiling lies below the floor somewhere")
        return cls(
            floor=floor, ceiling=ceiling, resolution=float(data["resolution"]),
            origin=np.asarray(data["origin"], np.float64), start=np.asarray(data["start"], np.float64),
            goal=np.asarray(data["goal"], np.float64),
            seed=int(data["seed"]) if "seed" in data.files else -1,
            difficulty=int(data["difficulty"]) if "difficulty" in data.files else -1)


def _pyramid_field(xs, ys, centres, heights, half_widths) -> np.ndarray:
    """Max over square pyramids of h * (1 - Chebyshev distance / half width), on the xs x ys grid."""
    field = np.zeros((xs.size, ys.size))
    for (cx, cy), h, w in zip(centres, heights, half_widths):
        dist = np.maximum(np.abs(xs[:, None] - cx), np.abs(ys[None, :] - cy))
        field = np.maximum(field, h * np.clip(1.0 - dist / w, 0.0, None))
    return field


def _pyramid_grid(rng, cfg: WorldConfig, length: float, rows: int, height_range):
    """Centres, heights and half widths of a rows x pyramids_per_row grid with jitter."""
    span = cfg.endpoint_fraction * length
    row_x = np.linspace(-span, span, rows + 2)[1:-1]
    lane_w = cfg.tunnel_width / cfg.pyramids_per_row
    lane_y = -cfg.tunnel_width / 2 + lane_w * (np.arange(cfg.pyramids_per_row) + 0.5)
    centres = np.stack(np.meshgrid(row_x, lane_y, indexing="ij"), -1).reshape(-1, 2)
    centres = centres + rng.uniform(-cfg.center_jitter, cfg.center_jitter, centres.shape)
    n = len(centres)
    return centres, rng.uniform(*height_range, n), rng.uniform(*cfg.pyramid_half_width, n)


def generate_world(seed: int, difficulty: int, config: WorldConfig = WorldConfig()) -> World:
    """Generate the world of (seed, difficulty); the same inputs always give the same arrays."""
    config.validate()
    if difficulty < 0:
        raise WorldError(f"difficulty must be >= 0, got {difficulty}")
    rng = np.random.default_rng([int(seed), int(difficulty)])
    length, rows, res = config.length(difficulty), config.rows(difficulty), config.resolution
    half_x = length / 2 + config.end_margin + config.wall_thickness
    half_y = config.tunnel_width / 2 + config.wall_thickness
    nx, ny = int(round(2 * half_x / res)) + 1, int(round(2 * half_y / res)) + 1
    xs, ys = -half_x + res * np.arange(nx), -half_y + res * np.arange(ny)

    ceil_drop = _pyramid_field(xs, ys, *_pyramid_grid(rng, config, length, rows, config.ceiling_pyramid_height))
    lo, hi = config.floor_pyramid_height
    bump_range = (lo, hi + config.floor_height_per_level * difficulty)
    floor = _pyramid_field(xs, ys, *_pyramid_grid(rng, config, length, rows, bump_range))
    ceiling = config.ceiling_nominal - ceil_drop

    ex = config.endpoint_fraction * length
    start_xy, goal_xy = np.array([-ex, 0.0]), np.array([ex, 0.0])
    for p in (start_xy, goal_xy):
        near = np.hypot(xs[:, None] - p[0], ys[None, :] - p[1]) < config.free_radius
        floor[near], ceiling[near] = 0.0, config.ceiling_nominal
    ceiling = np.maximum(ceiling, floor + config.min_clearance)

    wall = (np.abs(xs[:, None]) > length / 2 + config.end_margin + 1e-9) | (np.abs(ys[None, :]) > config.tunnel_width / 2 + 1e-9)
    top = max(float(ceiling.max()), config.ceiling_nominal)
    floor, ceiling = np.where(wall, top, floor), np.where(wall, top, ceiling)

    z = config.body_height
    return World(
        floor=floor.astype(np.float32), ceiling=ceiling.astype(np.float32), resolution=res,
        origin=np.array([xs[0], ys[0]]), start=np.array([*start_xy, z]), goal=np.array([*goal_xy, z]),
        seed=int(seed), difficulty=int(difficulty))
