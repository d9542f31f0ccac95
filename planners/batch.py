"""Plan many worlds at once, cached on disk, and hand the paths to the confined-space environments.

A cached plan is keyed by everything that decides it: the world's arrays, start and goal, the robot's
body box and leg reach, and every planner setting. Failures are cached too (with their message), so a
training run does not spend the time limit again on a world already known to be blocked.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import hashlib
import json
import multiprocessing
import os
from pathlib import Path

import numpy as np
from tqdm import tqdm

from legged.files import atomic_path
from legged.robots import GO1
from legged.robots.spec import RobotSpec
from legged.worlds.generator import World
from legged.worlds.levels import LevelConfig, make_world
from planners.body_planner import Plan, PlannerConfig, PlanningError, plan_path
from legged.worlds.maps import HeightMaps

CACHE_VERSION = 3
"""Bump when the planner's output for the same inputs changes, so stale cache entries are not used."""


def default_cache_dir() -> Path:
    """$LEGGED_CACHE_DIR/plans, else ~/.cache/legged/plans."""
    root = os.environ.get("LEGGED_CACHE_DIR")
    return (Path(root) if root else Path.home() / ".cache" / "legged") / "plans"


def cache_key(world: World, robot: RobotSpec, config: PlannerConfig) -> str:
    """Hex digest of everything that decides the plan of `world`."""
    h = hashlib.sha256()
    for array in (world.floor, world.ceiling, world.origin, world.start, world.goal):
        h.update(np.ascontiguousarray(np.asarray(array, np.float64)).tobytes())
    settings = {"version": CACHE_VERSION, "resolution": world.resolution, "config": dataclasses.asdict(config),
                "robot": [robot.name, robot.body_box_half_extents, robot.body_height_range, robot.default_pose]}
    h.update(json.dumps(settings, sort_keys=True).encode())
    return h.hexdigest()[:32]


def _read(path: Path) -> Plan | PlanningError | None:
    try:
        with np.load(path) as data:
            if "error" in data.files:
                return PlanningError(str(data["error"]))
            return Plan(waypoints=data["waypoints"], length_m=float(data["length_m"]),
                        plan_time_s=float(data["plan_time_s"]), planner=str(data["planner"]),
                        speeds=data["speeds"] if "speeds" in data.files else None)
    except Exception:  # unreadable or partial entry: plan again (writes are atomic, so this is rare)
        return None


def _write(path: Path, result: Plan | PlanningError) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, suffix=".npz") as tmp:  # np.savez would append .npz to any other name
        if isinstance(result, PlanningError):
            np.savez(tmp, error=str(result))
        else:
            extra = {} if result.speeds is None else {"speeds": result.speeds}
            np.savez(tmp, waypoints=result.waypoints, length_m=result.length_m, plan_time_s=result.plan_time_s,
                     planner=result.planner, **extra)


def plan_world(world: World, robot: RobotSpec = GO1, config: PlannerConfig = PlannerConfig(),
               cache_dir: Path | str | None = None) -> tuple[Plan | PlanningError, bool]:
    """Plan one generated world's start -> goal, using the cache; returns (plan or error, from_cache)."""
    path = Path(cache_dir or default_cache_dir()) / f"{cache_key(world, robot, config)}.npz"
    if path.is_file():
        cached = _read(path)
        if cached is not None:
            return cached, True
    try:
        result: Plan | PlanningError = plan_path(HeightMaps.from_world(world), world.start, world.goal, robot, config)
    except PlanningError as exc:
        result = exc
    _write(path, result)
    return result, False


def _plan_job(args):
    return plan_world(*args)


def plan_worlds(worlds: list[World], robot: RobotSpec = GO1, config: PlannerConfig = PlannerConfig(),
                cache_dir: Path | str | None = None, workers: int = 1,
                progress: bool = True) -> list[tuple[Plan | PlanningError, bool]]:
    """`plan_world` for every world, in order; `workers` > 1 plans in that many processes."""
    config.validate()
    jobs = [(w, robot, config, cache_dir) for w in worlds]
    bar = tqdm(total=len(jobs), desc="planning worlds", unit="world", disable=not progress)
    results = []
    if workers <= 1:
        for job in jobs:
            results.append(_plan_job(job))
            bar.update()
    else:
        context = multiprocessing.get_context("spawn")  # never fork a process that may hold JAX threads
        with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
            for result in pool.map(_plan_job, jobs):
                results.append(result)
                bar.update()
    bar.close()
    return results


def feasible_worlds(num_worlds: int, seed: int, difficulties, world_config, robot: RobotSpec = GO1,
                    config: PlannerConfig = PlannerConfig(), cache_dir=None, workers: int = 1,
                    max_tries: int = 5, progress: bool = True,
                    levels: LevelConfig | None = None) -> tuple[list[World], list[Plan]]:
    """`num_worlds` generated worlds with planned paths; a world with no path is replaced by a fresh one
    of the same difficulty (the first try of slot k is the world Terrain.generate would use; with `levels`, the
    level worlds of legged.worlds.levels instead of the tunnels of `world_config`)."""
    worlds: list[World | None] = [None] * num_worlds
    plans: list[Plan | None] = [None] * num_worlds
    for attempt in range(max_tries):
        slots = [k for k in range(num_worlds) if plans[k] is None]
        if not slots:
            break
        tries = [make_world(seed * 100_003 + k + attempt * num_worlds, difficulties[k % len(difficulties)],
                            world_config, levels) for k in slots]
        for k, world, (result, _) in zip(slots, tries, plan_worlds(tries, robot, config, cache_dir, workers, progress)):
            if isinstance(result, Plan):
                worlds[k], plans[k] = world, result
    missing = [k for k in range(num_worlds) if plans[k] is None]
    if missing:
        raise PlanningError(f"no traversable world found for slots {missing} in {max_tries} tries each "
                            f"(difficulties {[difficulties[k % len(difficulties)] for k in missing]}); "
                            "raise the planner time limit or ease the world generator")
    return worlds, plans
