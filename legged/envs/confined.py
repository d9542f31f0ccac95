"""Confined-space navigation for a quadruped: tunnels with floors and ceilings (after Xu et al., ICRA 2024).

One environment class, four tasks that differ only in what the policy is told and rewarded for:
- `waypoints` (hierarchical follower): the next body-pose waypoint of a planned path;
- `goal` (end-to-end baseline): only the far goal;
- `velocity` (baseline): a velocity command toward the next waypoint, rewarded for tracking it;
- `skills` (parameterised-skills baseline): velocity plus body height, roll and pitch of the waypoint.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.base import LeggedEnv
from legged.envs.config import GO1_RANDOMIZATION, EnvConfig, NoiseConfig, PenaltyScales, RandomizationConfig
from legged.envs.curriculum import next_level, pick_tile
from legged.envs.math import roll_pitch, yaw_rotate
from legged.envs.paths import pad_paths, pad_speeds, straight_path
from legged.envs.rewards import roll_pitch_rate_sq, tracking, wrap_angle
from legged.robots import GO1
from legged.robots.spec import RobotSpec
from legged.sensors.heightscan import ScanConfig, scan_points_world
from legged.worlds.generator import WorldConfig
from legged.worlds.levels import LevelConfig
from legged.worlds.mjcf import SceneOptions
from legged.worlds.terrain import Terrain

Mode = Literal["waypoints", "goal", "velocity", "skills"]


@dataclasses.dataclass(frozen=True)
class ConfinedRewards:
    """Weights of the confined-navigation reward terms."""

    goal_reached: float = 10.0
    """Once, when the body centre comes within `goal_radius` of the goal."""
    waypoint_reached: float = 1.0
    """Each time the current waypoint is reached (waypoints, velocity, skills modes)."""
    exploration: float = 1.0
    """Times the base velocity projected on the direction to the current target (m/s), capped at the speed limit in
    force (`ConfinedConfig.max_speed`): speed beyond the limit earns nothing."""
    overspeed: float = -1.0
    """Times the horizontal base speed beyond the speed limit in force (m/s, linear): with `exploration` at 1 a step's
    reward peaks at the limit and falls as steeply above it as it rose below, so running at 1.5x the limit pays half
    the limit's reward per step and a third per metre, and at 2x nothing (before the penalties)."""
    stalling: float = -1.0
    """Per step while slow and still far from the current target."""
    tracking_lin_vel: float = 1.0
    """exp(-|v_cmd - v|^2 / 0.25) in velocity and skills modes."""
    tracking_yaw_rate: float = 0.5
    """exp(-(w_cmd - w)^2 / 0.25) in velocity and skills modes."""
    tracking_pose: float = 1.0
    """exp(-(height, roll, pitch error)^2 / 0.02) in skills mode."""
    ang_vel_xy: float = 0.0
    """Times the sum of the squared roll and pitch rates of the body (rad/s, body frame; the walkers' -0.05): a cost
    of tipping fast, which is how followers fall (flips). 0, no term: runs saved before it existed."""


@dataclasses.dataclass(frozen=True)
class ConfinedConfig(EnvConfig):
    """A confined-space navigation task."""

    mode: Mode = "waypoints"
    """What the policy is given: waypoints, goal, velocity or skills (see module docstring)."""
    num_worlds: int = 16
    """Worlds tiled into the training terrain; each episode picks one at random."""
    world_seed: int = 0
    """Seed of the tiled worlds."""
    difficulties: tuple[int, ...] = (0, 1, 2)
    """Difficulty levels cycled over the worlds."""
    world: WorldConfig = WorldConfig()
    """Tunnel generator settings (the worlds when `levels` is None)."""
    levels: LevelConfig | None = None
    """The level worlds d0-d4 (legged.worlds.levels: tunnels; corridors of any width under any roof or open sky;
    bars, side blocks, pillars; steps, ramps, turns; voids), `difficulties` then naming levels (None: the tunnels of
    `world` only, as runs saved before the levels existed)."""
    scan: ScanConfig = ScanConfig()
    """Floor and ceiling height-scan grid."""
    waypoint_spacing: float = 0.5
    """Spacing of the default straight-line path (used until planned paths are handed in)."""
    waypoint_radius: float = 0.25
    """A waypoint counts as reached within this horizontal distance, metres."""
    goal_radius: float = 0.2
    """The goal counts as reached within this horizontal distance, metres."""
    stall_speed: float = 0.1
    """Below this base speed (m/s) ..."""
    stall_distance: float = 0.3
    """... while farther than this from the target (m), a step counts as stalling."""
    stall_timeout_s: float = math.inf
    """End an episode as a failure (not bootstrapped) once it has stalled this long without a break, seconds, so
    that a robot standing still stops filling the rollouts (inf: never, as runs saved before it existed). Training
    only: evaluation and navigation set it to inf (navigation replans a stalled robot instead)."""
    command_speed: float = 0.5
    """Commanded speed toward the waypoint in velocity and skills modes, m/s (lowered to the speed limit in force)."""
    max_speed: float = math.inf
    """Speed limit, m/s: exploration pays no horizontal speed beyond it and `rewards.overspeed` charges for the excess.
    A planned path may lower it at some waypoints (ConfinedEnv's `speeds`); the limit in force is the lower of the
    episode's and the current waypoint's (goal mode: the episode's). The confined tasks set 1 m/s (legged.tasks);
    inf, no limit, is what runs saved before it existed trained with."""
    speed_command: bool = False
    """The command ends with the speed limit in force (`speed_limit`), so that a policy can obey a limit lower than
    the one it trained at. Off for runs saved before it existed; on for the confined tasks (legged.tasks)."""
    speed_range: tuple[float, float] | None = None
    """Each episode draws its speed limit uniformly from this range, m/s (capped at `max_speed`), so that training
    sees many limits; None: every episode's limit is `max_speed`."""
    six_dof_command: bool = False
    """Waypoints mode: add target height, roll, pitch and relative yaw to the 2-D command."""
    preview: bool = False
    """Waypoints mode: the command also holds the waypoint after the current one (its dx, dy in the yaw frame; the
    goal's own at the goal), so that a turn shows before the robot reaches it. Off for runs saved before it
    existed."""
    plan_turn_accel: float | None = None
    """Planned worlds: the planner's `turn_accel` for their plans, m/s^2 (a turn's waypoints carry the speed limit
    sqrt(turn_accel / curvature), so training meets the slower turns navigation asks for); navigation with such a
    follower plans with it too unless told otherwise. None: no limit of the plans' own."""
    plan_face_travel: bool = False
    """Planned worlds: the planner's `face_travel` for their plans (each waypoint turned to the direction the path
    travels, where the body fits; planners.headings); navigation with such a follower plans so too. False: the
    search's headings, which turn the body as little as they can (runs saved before it existed)."""
    spawn_yaw: float = 0.3
    """Initial heading is uniform in +-this, radians."""
    curriculum: bool = True
    """Each environment starts at the easiest difficulty, moves one level up after a success and one down
    after an episode that ends short of half its path (legged_gym's terrain curriculum); past the hardest
    level it draws a level at random. Off: every episode draws a tile uniformly."""
    success_bootstraps: bool = False
    """Reaching the goal ends the episode as a truncation, so the learner bootstraps the value of going on
    instead of losing it. Needed where every step pays for tracking a command (velocity, skills): there,
    ending at the goal cut the return, and the trained policies learned to stop 0.23 m short of the 0.2 m
    radius and collect tracking reward for the rest of the episode."""
    only_positive_rewards: bool = True
    """Clip each step's total reward at 0, so that ending an episode early (a fall) never pays."""
    rewards: ConfinedRewards = ConfinedRewards()
    """Task reward weights."""
    penalties: PenaltyScales = PenaltyScales()
    """Penalty weights."""
    randomization: RandomizationConfig = GO1_RANDOMIZATION
    """Domain randomisation (on, with the model ranges that cover the reference robots: legged.envs.config.COVERING)."""
    noise: NoiseConfig = NoiseConfig(enabled=True)
    """Observation noise on `state` (on)."""

    def __post_init__(self):
        super().__post_init__()
        if not 0.0 < self.max_speed <= math.inf:  # NaN fails here too
            raise ValueError(f"max_speed (the speed limit) must be a positive number of m/s, got {self.max_speed!r}")
        if not self.stall_timeout_s > 0.0:  # NaN fails here too
            raise ValueError(f"stall_timeout_s must be a positive number of seconds (inf: never), got "
                             f"{self.stall_timeout_s!r}")
        if self.plan_turn_accel is not None and not 0.0 < self.plan_turn_accel < math.inf:
            raise ValueError(f"plan_turn_accel must be a positive acceleration in m/s^2 (or null: none), got "
                             f"{self.plan_turn_accel!r}")
        if self.speed_range is not None:
            r = tuple(self.speed_range)
            if len(r) != 2 or not 0.0 < r[0] <= r[1] < math.inf:
                raise ValueError(f"speed_range must be two speeds LOW, HIGH in m/s with 0 < LOW <= HIGH, got "
                                 f"{self.speed_range!r}")


class ConfinedEnv(LeggedEnv):
    """Go1 in tiled confined worlds, following waypoints (or a goal, or commands) to the goal."""

    def __init__(self, config: ConfinedConfig = ConfinedConfig(), robot: RobotSpec = GO1,
                 terrain: Terrain | None = None, paths: Sequence[np.ndarray] | None = None, path_capacity: int = 0,
                 speeds: Sequence[np.ndarray | None] | None = None):
        """`paths`: one (n, 6) body-pose path per world (default: straight lines); `path_capacity`: room for longer
        paths handed in later; `speeds`: per path, a speed limit per waypoint (m/s; None or NaN: `max_speed`)."""
        terrain = terrain or Terrain.generate(config.num_worlds, config.world_seed, config.difficulties, config.world,
                                              config.levels)
        super().__init__(robot, terrain, SceneOptions(), config)
        if paths is None:
            paths = [straight_path(s, g, config.waypoint_spacing) for s, g in zip(terrain.starts, terrain.goals)]
        path_array, lengths = pad_paths(list(paths), terrain, path_capacity)
        self._paths, self._path_len = jnp.asarray(path_array), jnp.asarray(lengths)
        speeds = [None] * len(lengths) if speeds is None else list(speeds)
        self._speeds = jnp.asarray(pad_speeds(speeds, lengths, path_array.shape[1], config.max_speed))
        self._starts = jnp.asarray(terrain.starts, jnp.float32)
        self._goals = jnp.asarray(terrain.goals, jnp.float32)
        self._scan_points = jnp.asarray(config.scan.points(), jnp.float32)
        self._levels = np.unique(terrain.difficulties)
        self._tile_level = jnp.asarray(np.searchsorted(self._levels, terrain.difficulties), jnp.int32)

    @property
    def penalty_scales(self) -> PenaltyScales:
        return self.config.penalties

    @property
    def command_names(self) -> tuple[str, ...]:
        mode = self.config.mode
        if mode in ("waypoints", "goal"):
            six = mode == "waypoints" and self.config.six_dof_command
            names = ("dx", "dy") + (("dz", "roll", "pitch", "dyaw") if six else ())
            names += ("next_dx", "next_dy") if mode == "waypoints" and self.config.preview else ()
        else:
            names = ("vx", "vy", "yaw_rate") + (("height", "roll", "pitch") if mode == "skills" else ())
        return names + (("speed_limit",) if self.config.speed_command else ())

    # ----------------------------------------------------------------- read-outs (dashboard, analysis)
    def path_of(self, info) -> tuple[jax.Array, jax.Array]:
        """The episode's waypoints (max_waypoints, 6) and how many of them are valid. They live in `info`
        ('path', 'path_len'; the planned path of the episode's world at its start), so a navigator may hand
        an episode a new plan between steps (then also setting info['waypoint'] and the plan's per-waypoint speed
        limits, info['speeds'], laid out by legged.envs.paths.pad_speeds)."""
        return info["path"], info["path_len"]

    def speed_limit(self, info) -> jax.Array:
        """The speed limit in force, m/s: the episode's (info['speed_limit']: `max_speed`, or drawn from
        `speed_range`), lowered to the current waypoint's own limit (info['speeds']) except in goal mode."""
        if self.config.mode == "goal":
            return info["speed_limit"]
        return jnp.minimum(info["speed_limit"], info["speeds"][info["waypoint"]])

    def scan_world_points(self, data) -> jax.Array:
        """World positions of the floor then the ceiling height-scan points, shape (2, n, 3)."""
        xy = scan_points_world(data.xpos[self._trunk], self.base_yaw(data), self._scan_points)
        heights = jnp.stack([self.floor_height(xy), self.ceiling_height(xy)])
        return jnp.concatenate([jnp.broadcast_to(xy, (2,) + xy.shape), heights[..., None]], -1)

    # ----------------------------------------------------------------- hooks
    @property
    def levels(self) -> np.ndarray:
        """The difficulties present in the terrain, easiest first (curriculum level i plays levels[i])."""
        return self._levels

    def carry(self, info):
        """Curriculum: one level up after a success, one down after ending short of half the path."""
        progress = info["waypoint"] / info["path_len"]
        return next_level(info["level"], info["succeeded"], progress < 0.5)

    def _task_reset(self, rng, carry=None):
        k_tile, k_yaw = jax.random.split(rng)
        tile, level = pick_tile(k_tile, carry, self._tile_level, len(self._levels), self.config.curriculum)
        start = self._starts[tile]
        z = self.floor_height(start[:2]) + self.robot.standing_height + 0.02
        yaw = jax.random.uniform(k_yaw, minval=-self.config.spawn_yaw, maxval=self.config.spawn_yaw)
        limit = jnp.float32(self.config.max_speed)
        if self.config.speed_range is not None:  # a key of its own: the tile and yaw draws stay those of older runs
            low, high = self.config.speed_range
            limit = jnp.minimum(jax.random.uniform(jax.random.fold_in(rng, 1), minval=low, maxval=high), limit)
        info = dict(tile=tile, level=level, waypoint=jnp.int32(1), goal=self._goals[tile], succeeded=jnp.bool_(False),
                    path=self._paths[tile], path_len=self._path_len[tile], speeds=self._speeds[tile],
                    speed_limit=limit, speed_sum=jnp.float32(0.0), overspeed_sum=jnp.float32(0.0),
                    stalled_steps=jnp.int32(0))
        return jnp.array([start[0], start[1], z]), yaw, info

    def _target(self, info) -> jax.Array:
        """Current target pose (x, y, z, roll, pitch, yaw): the goal in goal mode, else the waypoint."""
        if self.config.mode == "goal":
            return jnp.concatenate([info["goal"], jnp.zeros(3)])
        return info["path"][info["waypoint"]]

    def _velocity_command(self, data, info) -> jax.Array:
        """(vx, vy, yaw rate) in the yaw frame that heads for the current target."""
        base, yaw = data.xpos[self._trunk], self.base_yaw(data)
        rel = yaw_rotate(yaw, self._target(info)[:2] - base[:2])
        dist = jnp.linalg.norm(rel)
        speed = jnp.minimum(self.config.command_speed, self.speed_limit(info))
        v = speed * rel / jnp.maximum(dist, 1e-6) * jnp.minimum(dist / 0.3, 1.0)
        yaw_rate = jnp.clip(2.0 * jnp.arctan2(rel[1], rel[0]), -1.0, 1.0) * (dist > 0.1)
        return jnp.array([v[0], v[1], yaw_rate])

    def _command(self, data, info):
        cmd = self._task_command(data, info)
        if self.config.speed_command:
            cmd = jnp.concatenate([cmd, self.speed_limit(info)[None]])
        return cmd

    def _task_command(self, data, info):
        """The command without the speed limit: the target (waypoints, goal) or the velocity command."""
        mode, target = self.config.mode, self._target(info)
        base, yaw = data.xpos[self._trunk], self.base_yaw(data)
        rel = yaw_rotate(yaw, target[:2] - base[:2])
        if mode in ("waypoints", "goal"):
            if mode == "waypoints" and self.config.six_dof_command:
                rel = jnp.concatenate([rel, jnp.stack([target[2] - base[2], target[3], target[4],
                                                       wrap_angle(target[5] - yaw)])])
            if mode == "waypoints" and self.config.preview:
                after = info["path"][jnp.minimum(info["waypoint"] + 1, info["path_len"] - 1)]
                rel = jnp.concatenate([rel, yaw_rotate(yaw, after[:2] - base[:2])])
            return rel
        cmd = self._velocity_command(data, info)
        if mode == "skills":
            height = target[2] - self.floor_height(target[:2])
            cmd = jnp.concatenate([cmd, jnp.stack([height, target[3], target[4]])])
        return cmd

    def _exteroception(self, data, info):
        base, yaw = data.xpos[self._trunk], self.base_yaw(data)
        xy = scan_points_world(base, yaw, self._scan_points)
        scan = self.config.scan
        clip, top = scan.clip, scan.clip if scan.ceiling_clip is None else scan.ceiling_clip
        floor = jnp.clip(self.floor_height(xy) - base[2], -clip, clip)
        ceiling = jnp.clip(self.ceiling_height(xy) - base[2], -clip, top)
        scans = jnp.concatenate([ceiling, floor])
        return scans, jnp.full_like(scans, self.config.noise.height_scan)

    def _task_failed(self, data, info):
        """Stalled for `stall_timeout_s` without a break."""
        return info["stalled_steps"] * self.dt >= self.config.stall_timeout_s - 1e-6  # 5 x 0.02 s is 0.1 s

    @property
    def success_is_truncation(self) -> bool:
        return self.config.success_bootstraps

    def _task_privileged(self, data, info):
        base = data.xpos[self._trunk]
        return jnp.stack([base[2] - self.floor_height(base[:2]), self.ceiling_height(base[:2]) - base[2]])

    def _task_step(self, data, info, action):
        cfg, w = self.config, self.config.rewards
        base, vel = data.xpos[self._trunk], data.qvel[0:3]
        target = self._target(info)
        to_target = target[:2] - base[:2]
        dist = jnp.linalg.norm(to_target)
        goal_dist = jnp.linalg.norm(info["goal"][:2] - base[:2])
        success = goal_dist < cfg.goal_radius
        last = info["waypoint"] >= info["path_len"] - 1
        reached = (dist < cfg.waypoint_radius) & ~last & (cfg.mode != "goal")
        speed = jnp.linalg.norm(vel[:2])
        limit = self.speed_limit(info)
        overspeed = jnp.maximum(speed - limit, 0.0)
        stalling = (speed < cfg.stall_speed) & (dist > cfg.stall_distance)
        terms = {
            "goal_reached": w.goal_reached * success,
            "waypoint_reached": w.waypoint_reached * reached,
            "stalling": w.stalling * stalling,
            "overspeed": w.overspeed * overspeed,
        }
        if w.ang_vel_xy:
            terms["ang_vel_xy"] = w.ang_vel_xy * roll_pitch_rate_sq(data.qvel)
        if cfg.mode in ("waypoints", "goal"):
            toward = jnp.dot(vel[:2], to_target / jnp.maximum(dist, 1e-6))
            terms["exploration"] = w.exploration * jnp.minimum(toward, limit)
        else:
            cmd = self._velocity_command(data, info)
            yaw = self.base_yaw(data)
            local = yaw_rotate(yaw, vel[:2])
            yaw_rate = (self.base_rotation(data) @ data.qvel[3:6])[2]
            terms["tracking_lin_vel"] = w.tracking_lin_vel * tracking(jnp.sum(jnp.square(cmd[:2] - local)), 0.25)
            terms["tracking_yaw_rate"] = w.tracking_yaw_rate * tracking(jnp.square(cmd[2] - yaw_rate), 0.25)
            if cfg.mode == "skills":
                roll, pitch = roll_pitch(self.base_rotation(data))
                height = base[2] - self.floor_height(base[:2])
                err = (jnp.square(target[2] - self.floor_height(target[:2]) - height)
                       + jnp.square(target[3] - roll) + jnp.square(target[4] - pitch))
                terms["tracking_pose"] = w.tracking_pose * tracking(err, 0.02)
        info["waypoint"] = jnp.where(reached, info["waypoint"] + 1, info["waypoint"])
        info["succeeded"] = success
        info["stalled_steps"] = jnp.where(stalling, info["stalled_steps"] + 1, 0)
        info["speed_sum"] = info["speed_sum"] + speed
        info["overspeed_sum"] = info["overspeed_sum"] + overspeed
        metrics = {
            "curriculum_level": info["level"].astype(jnp.float32),
            "path_progress": info["waypoint"] / info["path_len"],
            "success": success.astype(jnp.float32),
            "time_to_goal_s": jnp.where(success, info["step"] * self.dt, 0.0),
            "final_distance_m": goal_dist,
            "waypoint_index": info["waypoint"].astype(jnp.float32),
            "speed": speed,
            "speed_limit": limit,
            "mean_speed_mps": info["speed_sum"] / info["step"],
            "overspeed_mps": info["overspeed_sum"] / info["step"],
            "stalled_out": self._task_failed(data, info).astype(jnp.float32),
        }
        return terms, success, metrics, info
