"""Planner benchmark: success rate, median planning time and path length per difficulty level."""

from __future__ import annotations

import time

import mujoco
import numpy as np
from tqdm import tqdm

from legged.robots import GO1
from legged.worlds.generator import generate_world
from planners.body_planner import PlannerConfig, PlanningError, plan_path
from planners.narrow_scenes import narrow_scenes
from planners.scene_maps import maps_from_scene, reference_between
from legged.worlds.maps import HeightMaps


def bench_planner(difficulties, num_worlds: int, config: PlannerConfig = PlannerConfig(), first_seed: int = 0,
                  progress: bool = True) -> list[dict]:
    """Plan worlds first_seed .. first_seed + num_worlds - 1 at each difficulty (no cache); one record each."""
    config.validate()
    records = []
    for difficulty in difficulties:
        times, lengths, counts, failures = [], [], [], []
        for seed in tqdm(range(first_seed, first_seed + num_worlds), desc=f"difficulty {difficulty}",
                         unit="world", disable=not progress):
            world = generate_world(seed, difficulty)
            try:
                plan = plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, config)
            except PlanningError:
                failures.append(seed)
                continue
            times.append(plan.plan_time_s)
            lengths.append(plan.length_m)
            counts.append(len(plan.waypoints))
        straight = 2 * world.goal[0]
        records.append({
            "difficulty": difficulty, "worlds": num_worlds, "solved": len(times),
            "success_rate": round(len(times) / num_worlds, 3),
            "median_plan_time_s": round(float(np.median(times)), 4) if times else None,
            "max_plan_time_s": round(float(np.max(times)), 4) if times else None,
            "median_length_m": round(float(np.median(lengths)), 4) if lengths else None,
            "straight_line_m": round(float(straight), 4),
            "median_waypoints": int(np.median(counts)) if counts else None,
            "failed_seeds": failures,
            "planner": config.planner, "time_limit_s": config.time_limit, "spacing_m": config.spacing,
            "planner_seed": config.seed,
        })
    return records


def _fmt(value, spec: str) -> str:
    return format(value, spec) if value is not None else "-"


def print_table(records: list[dict]) -> None:
    """Human-readable table of `bench_planner` records."""
    print(f"{'difficulty':>10} {'solved':>8} {'median time s':>14} {'max time s':>11} {'median length m':>16} "
          f"{'straight m':>11}")
    for r in records:
        print(f"{r['difficulty']:>10} {r['solved']:>4}/{r['worlds']:<3} "
              f"{_fmt(r['median_plan_time_s'], '14.3f')} {_fmt(r['max_plan_time_s'], '11.3f')} "
              f"{_fmt(r['median_length_m'], '16.3f')} {r['straight_line_m']:>11.3f}")




PREVIOUS_PLANNER = PlannerConfig(planner="rrtconnect", space="full")
"""The planner before narrow-passage support (6-D sampling with RRTConnect), measured beside the current one."""


def bench_narrow(configs: dict[str, PlannerConfig], resolution: float = 0.025, progress: bool = True) -> dict:
    """Plan every scene of planners.narrow_scenes with each named planner config; one record per (scene,
    config) with its wall-clock time (simplification included, map sampling excluded), plus a summary."""
    records = []
    for scene in tqdm(narrow_scenes(GO1), desc="narrow scenes", unit="scene", disable=not progress):
        model = mujoco.MjModel.from_xml_string(scene.xml)
        maps = maps_from_scene(model, reference_between(np.array(scene.start), np.array(scene.goal)), resolution)
        for label, config in configs.items():
            began = time.perf_counter()
            try:
                plan = plan_path(maps, scene.start, scene.goal, GO1, config)
                record = {"solved": True, "planner_used": plan.planner, "length_m": round(plan.length_m, 4),
                          "min_body_height_m": round(float(plan.waypoints[:, 2].min()), 4)}
            except PlanningError as exc:
                record = {"solved": False, "error": str(exc)[:200]}
            records.append({"scene": scene.name, "config": label, "time_s": round(time.perf_counter() - began, 4),
                            **record})
    summary = {}
    for label in configs:
        mine = [r for r in records if r["config"] == label]
        solved = [r["time_s"] for r in mine if r["solved"]]
        summary[label] = {"scenes": len(mine), "solved": len(solved), "success_rate": round(len(solved) / len(mine), 3),
                          "median_time_s": round(float(np.median(solved)), 4) if solved else None,
                          "max_time_s": round(float(np.max(solved)), 4) if solved else None}
    return {"resolution_m": resolution, "summary": summary, "scenes": records}
