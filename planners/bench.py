"""Planner benchmark: success rate, median planning time and path length per difficulty level."""

from __future__ import annotations

import numpy as np
from tqdm import tqdm

from legged.robots import GO1
from legged.worlds.generator import generate_world
from planners.body_planner import PlannerConfig, PlanningError, plan_path
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


