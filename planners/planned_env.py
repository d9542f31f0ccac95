"""Confined-space environments whose waypoints come from the planner (what training uses).

The environments never import the planner (tests/test_layers.py): this module plans the worlds ahead of time,
tiles the traversable ones into a terrain and hands the paths over as arrays.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from legged.envs.confined import ConfinedEnv
from legged.tasks import make, task_entry
from legged.worlds.terrain import Terrain
from planners.batch import feasible_worlds
from planners.body_planner import PlannerConfig


def tile_paths(terrain: Terrain, worlds, plans) -> list[np.ndarray]:
    """Move each world's planned waypoints to where its tile sits in the terrain."""
    out = []
    for k, (world, plan) in enumerate(zip(worlds, plans)):
        path = np.array(plan.waypoints, np.float64)
        path[:, :2] += terrain.starts[k, :2] - np.asarray(world.start)[:2]
        out.append(path)
    return out


def follower_planner(env_config, planner: PlannerConfig) -> PlannerConfig:
    """The planner for a follower trained on `env_config`: `planner`, with the turn limit the follower's training
    plans had (`plan_turn_accel`) and their headings (`plan_face_travel`) where `planner` sets none."""
    turn_accel = getattr(env_config, "plan_turn_accel", None)
    if planner.turn_accel is None and turn_accel is not None:
        planner = dataclasses.replace(planner, turn_accel=turn_accel)
    if planner.face_travel is None and getattr(env_config, "plan_face_travel", False):
        planner = dataclasses.replace(planner, face_travel=True)
    return planner


def make_planned_env(task: str, planner: PlannerConfig = PlannerConfig(), cache_dir=None, workers: int = 1,
                     progress: bool = True, config=None, **overrides):
    """Build `task`; confined tasks get traversable worlds and planned waypoints, others are built as is."""
    entry = task_entry(task)
    config = config or entry.config
    if overrides:
        config = dataclasses.replace(config, **overrides)
    if entry.kind != "confined":
        return make(task, config)
    if config.levels is None:  # a tunnel run saved before the level worlds: planned as it was (no strides, no walls)
        planner = dataclasses.replace(planner, body=dataclasses.replace(planner.body, stride_slack=0.0,
                                                                        step_height=None))
    planner = follower_planner(config, planner)
    worlds, plans = feasible_worlds(config.num_worlds, config.world_seed, config.difficulties, config.world,
                                    entry.robot, planner, cache_dir, workers, progress=progress, levels=config.levels)
    terrain = Terrain.from_worlds(worlds)
    return ConfinedEnv(config, entry.robot, terrain, tile_paths(terrain, worlds, plans),
                       speeds=[plan.speeds for plan in plans])
