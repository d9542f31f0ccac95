"""`legged bench navigate`: the whole plan-follow-replan loop (policies.navigate) on every scene of a directory
(legged.worlds.scenes: start, goal and time limit inside each file), a few episode seeds each, with per-scene and
total figures.

Per scene: success rate, median time to goal and its ratio to the path length at the speed limit, mean and
95th-percentile body speed (horizontal, over every control step), collisions, falls and replans per episode.
Total: the success rate with its 95% Wilson interval, the worst scene, the pooled speed percentile.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from tqdm import tqdm

from legged.worlds.scenes import SPEED, read_scene, scene_files
from planners import PlannerConfig, follower_planner, navigation_maps
from policies.evaluate import wilson_interval
from policies.navigate import (NavigationError, Unreachable, check_speed_limit, follower_provenance, load_follower,
                               navigate_seeds)
from policies.provenance import repo_path, sealed


def _median(values: list) -> float | None:
    return round(float(np.median(values)), 3) if values else None


def scene_row(scene, reports: list[dict], speed: float) -> dict:
    """One scene's figures from its episodes' reports."""
    wins = [r for r in reports if r["success"]]
    speeds = np.concatenate([r["speeds_mps"] for r in reports]) if reports else np.zeros(0)
    at_limit = [r["time_to_goal_s"] / (r["path_length_m"] / speed) for r in wins]
    mean = lambda key: round(float(np.mean([r[key] for r in reports])), 3)
    return {"scene": scene.name, "description": scene.description, "episodes": len(reports), "successes": len(wins),
            "success_rate": round(len(wins) / len(reports), 4), "time_limit_s": scene.time_limit_s,
            "path_length_m": reports[0]["path_length_m"],
            "time_to_goal_s": _median([r["time_to_goal_s"] for r in wins]),
            "time_vs_path_at_speed": _median(at_limit),
            "mean_speed_mps": round(float(speeds.mean()), 3) if len(speeds) else 0.0,
            "p95_speed_mps": round(float(np.percentile(speeds, 95)), 3) if len(speeds) else 0.0,
            "collisions": mean("collisions"), "falls_per_episode": mean("falls"), "replans": mean("replans"),
            "plan_time_s": reports[0]["plan_time_s"], "outcomes": [_outcome(r) for r in reports]}


def _outcome(report: dict) -> str:
    if report["success"]:
        return "goal"
    return "fell" if report["falls"] else "timeout"


def _unplanned(scene, episodes: int, why: str) -> dict:
    """The row of a scene the planner found no path through (every episode fails)."""
    return {"scene": scene.name, "description": scene.description, "episodes": episodes, "successes": 0,
            "success_rate": 0.0, "time_limit_s": scene.time_limit_s, "path_length_m": None, "time_to_goal_s": None,
            "time_vs_path_at_speed": None, "mean_speed_mps": 0.0, "p95_speed_mps": 0.0, "collisions": 0.0,
            "falls_per_episode": 0.0, "replans": 0.0, "plan_time_s": None, "outcomes": ["unplanned"] * episodes,
            "error": why}


def bench_navigate(scenes_dir, policy_dir, seeds: int = 5, first_seed: int = 0, robot: str = "project",
                   physics: str = "native", threads: int | None = None, resolution: float = 0.025,
                   planner: PlannerConfig = PlannerConfig(), speed: float = SPEED, progress: bool = True,
                   max_speed: float | None = None) -> dict:
    """Every scene of `scenes_dir` navigated by the follower `policy_dir` with episode seeds first_seed onward.
    Scene files and the policy are checked before any navigation starts. `max_speed`: the navigations' speed limit,
    m/s (policies.navigate; default: the run's `env.max_speed`); times to goal are compared at the lower of it and
    `speed`, and the scenes' time limits (written for 1 m/s) stretched by 1 m/s over that speed where it is lower."""
    check_speed_limit(max_speed)
    scenes = [read_scene(path) for path in scene_files(scenes_dir)]
    _, run_config = load_follower(policy_dir, robot, physics)
    limit = run_config.env.max_speed if max_speed is None else max_speed  # what the navigations run at
    speed = min(speed, limit)
    stretch = SPEED / speed  # the scenes' time limits are written for SPEED: slower limits get more time
    rows, pooled = [], []
    bar = tqdm(total=len(scenes) * seeds, unit="episode", desc="bench navigate", disable=not progress)
    for model, scene in scenes:
        bar.set_postfix_str(scene.name)
        try:
            maps = navigation_maps(model, scene.start, scene.goal, resolution)
            reports = navigate_seeds(policy_dir, maps, scene.start, scene.goal,
                                     list(range(first_seed, first_seed + seeds)), physics, threads, planner=planner,
                                     robot=robot, time_limit_s=scene.time_limit_s * stretch,
                                     progress=bar.update,
                                     max_speed=max_speed)
        except (Unreachable, NavigationError) as exc:  # the planner's failure is the benchmark's result
            rows.append(_unplanned(scene, seeds, str(exc)))
            bar.update(seeds)
            continue
        rows.append(scene_row(scene, reports, speed))
        pooled.extend(np.concatenate([r["speeds_mps"] for r in reports]).tolist())
    bar.close()
    episodes, wins = sum(r["episodes"] for r in rows), sum(r["successes"] for r in rows)
    ratios = [r["time_vs_path_at_speed"] for r in rows if r["time_vs_path_at_speed"] is not None]
    total = {"scenes": len(rows), "episodes": episodes, "successes": wins, "success_rate": round(wins / episodes, 4),
             "success_interval_95": wilson_interval(wins, episodes),
             "worst_scene_success": min(r["success_rate"] for r in rows),
             "median_time_vs_path_at_speed": _median(ratios),
             "p95_speed_mps": round(float(np.percentile(pooled, 95)), 3) if pooled else 0.0}
    return sealed({"scenes_dir": repo_path(scenes_dir), "policy": repo_path(policy_dir), "robot": robot,
                   "physics": physics, "seeds": list(range(first_seed, first_seed + seeds)), "speed_limit_mps": speed,
                   "planner": dataclasses.asdict(follower_planner(run_config.env, planner)), "total": total,
                   "scenes": rows}, *follower_provenance(policy_dir, robot))


def print_table(report: dict) -> None:
    """The benchmark as a table on stdout."""
    print(f"{'scene':>22} {'success':>8} {'to goal s':>9} {'x path':>7} {'mean m/s':>8} {'p95 m/s':>8} "
          f"{'coll':>5} {'falls':>5} {'replans':>7}")
    for r in report["scenes"]:
        fmt = lambda v, f: format(v, f) if v is not None else "-"
        print(f"{r['scene']:>22} {r['successes']:>3}/{r['episodes']:<4} {fmt(r['time_to_goal_s'], '9.2f')} "
              f"{fmt(r['time_vs_path_at_speed'], '7.2f')} {r['mean_speed_mps']:8.2f} {r['p95_speed_mps']:8.2f} "
              f"{r['collisions']:5.1f} {r['falls_per_episode']:5.2f} {r['replans']:7.1f}")
    t = report["total"]
    lo, hi = t["success_interval_95"]
    print(f"total: {t['successes']}/{t['episodes']} ({t['success_rate']:.0%}, 95% interval {lo:.0%}-{hi:.0%}); "
          f"worst scene {t['worst_scene_success']:.0%}; p95 speed {t['p95_speed_mps']} m/s")
