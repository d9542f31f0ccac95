"""The level worlds' parameters: the levels d0-d4 and `LevelConfig`, every range the generator draws from
(legged.worlds.levels describes the levels; legged.worlds.level_layout draws them)."""

from __future__ import annotations

import dataclasses

from legged.worlds.generator import WorldConfig, WorldError

LEVELS = (0, 1, 2, 3, 4)
"""The difficulty levels `generate_level` knows."""
OBSTACLES = ("bar", "block", "pillars")
"""Obstacle kinds of levels 2 and up."""


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


def check_level(level: int) -> None:
    """Raise WorldError unless `level` is one of LEVELS."""
    if level not in LEVELS:
        raise WorldError(f"level must be one of {', '.join(map(str, LEVELS))}, got {level}")
