"""`legged navigate`: plan through a world or a user's scene, follow the plan with a trained waypoint
follower, and replan when the robot strays from it (the planner-follower hierarchy, end to end).

The robot walks in the height-map realisation of the scene (the maps the planner plans on, as MuJoCo
height fields), in MJX or native MuJoCo. A replan starts from the robot's measured pose (moved to the
nearest valid body pose, planners.body_planner.replan) and is handed to the running episode in its
`info` (ConfinedEnv keeps the path there), so nothing is recompiled.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.confined import ConfinedEnv
from legged.envs.curriculum import level_carry
from legged.envs.paths import pad_speeds
from legged.envs.vector import VectorEnv
from legged.robots.models import model_path
from legged.tasks import task_entry
from legged.worlds.maps import HeightMaps
from legged.worlds.terrain import Terrain
from planners.body_check import BodyChecker
from planners.body_planner import PlannerConfig, PlanningError, plan_path, replan
from planners.planned_env import follower_planner
from policies.evaluate import nominal_config, on_robot, whole_episodes
from policies.policy_io import actor_observation, load_policy
from policies.provenance import repo_path, run_record, sealed
from policies.run_dir import RunDir, RunDirError, check_policy

PATH_CAPACITY = 256
"""Most waypoints a (re)planned path may have in a navigation episode."""


class NavigationError(ValueError):
    """Navigation cannot start: the policy does not follow waypoints, or the start or goal is unusable."""


class Unreachable(NavigationError):
    """No path leads from the start to the goal (an outcome to report, not a mistake in the input)."""


@dataclasses.dataclass(frozen=True)
class NavigateConfig:
    """When a navigation replans and gives up."""

    stray_distance: float = 0.4
    """Replan when the body centre is farther than this from the rest of the planned path, metres."""
    stall_seconds: float = 4.0
    """... or when no new waypoint was reached for this long, seconds."""
    max_replans: int = 20
    """Replans allowed in one navigation."""
    seconds_per_metre: float = 5.0
    """Time limit: 20 s plus this per metre of the first plan."""


def _distance_to_path(xy: np.ndarray, path: np.ndarray) -> float:
    """Horizontal distance from a point to a polyline (n, >= 2)."""
    a, b = path[:-1, :2], path[1:, :2]
    ab = b - a
    t = np.clip(np.sum((xy - a) * ab, 1) / np.maximum(np.sum(ab * ab, 1), 1e-12), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - xy, axis=1))) if len(a) else float(np.linalg.norm(xy - path[0, :2]))


def _pose_of(qpos: np.ndarray) -> np.ndarray:
    """Body pose x, y, z, roll, pitch, yaw from a free joint's qpos (w, x, y, z quaternion)."""
    w, x, y, z = qpos[3:7]
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.array([qpos[0], qpos[1], qpos[2], roll, pitch, yaw])


def check_speed_limit(max_speed: float | None) -> None:
    """NavigationError unless `max_speed` is None (the run's limit) or a positive number of m/s."""
    if max_speed is not None and not 0.0 < max_speed < math.inf:  # NaN fails here too
        raise NavigationError(f"the speed limit must be a positive number of m/s, got {max_speed!r}")


def terrain_of(maps: HeightMaps, start, goal) -> Terrain:
    """A one-world terrain holding `maps` with its start and goal."""
    if isinstance(maps, Terrain):
        return maps
    return Terrain(floor=np.asarray(maps.floor, np.float32), ceiling=np.asarray(maps.ceiling, np.float32),
                   resolution=maps.resolution, origin=np.asarray(maps.origin, float),
                   starts=np.asarray([start[:3]], float), goals=np.asarray([goal[:3]], float),
                   difficulties=np.array([0]), ceiling_top=float(np.max(maps.ceiling)), source="navigation scene")


def load_follower(run_dir, robot: str = "project", physics: str | None = None):
    """(policy, run config with the `robot` model) of a waypoint follower; NavigationError if the run learned
    another task, RobotModelError if the model cannot be used (in `physics`)."""
    config = RunDir(run_dir).load_config()  # the task is checked before any checkpoint is read
    entry = task_entry(config.task)
    if entry.kind != "confined" or getattr(config.env, "mode", "") == "goal":
        raise NavigationError(f"{run_dir} was trained on {config.task}, which does not follow waypoints; it needs "
                              "a confined-waypoints (or confined-velocity / confined-skills) run")
    on_robot(config, robot, physics)
    policy, config = load_policy(run_dir)
    return policy, on_robot(config, robot)


def navigate(run_dir, maps: HeightMaps, start, goal, physics: str = "native", threads: int | None = None,
             config: NavigateConfig = NavigateConfig(), planner: PlannerConfig = PlannerConfig(), seed: int = 0,
             on_step=None, robot: str = "project", time_limit_s: float | None = None,
             max_speed: float | None = None, nominal: bool = False, where: dict | None = None) -> dict:
    """Plan from start to goal, follow with the run's policy, replan on straying; the outcome as a dict (after the
    fields of `where`, which say what was navigated), with its provenance (policies.provenance).
    `on_step(env, state, plan)` is called at the start and after every control step but the last (viewers). Raises NavigationError (the
    policy cannot navigate, or the start or goal is unusable; Unreachable when no path exists) before any
    compilation. `robot`: the robot model the follower walks (legged.robots.models). `time_limit_s`: the
    navigation's time limit (default: 20 s plus `config.seconds_per_metre` per metre of the first plan).
    `max_speed`: the speed limit, m/s (default: the run's `env.max_speed`; a follower trained with
    `env.speed_command` is told it, one trained without runs at its own speed and is only measured against it).
    `nominal`: the robot model as it is (the run's domain randomisation and observation noise off); by default each
    episode draws a robot from the run's randomisation, as in training."""
    report = navigate_seeds(run_dir, maps, start, goal, [seed], physics, threads, config, planner, on_step, robot,
                            time_limit_s, max_speed=max_speed, nominal=nominal)[0]
    report.pop("speeds_mps")
    return sealed(dict(where or {}, **report), *follower_provenance(run_dir, robot))


def follower_provenance(run_dir, robot: str = "project") -> tuple[dict, dict]:
    """(the follower's `run_record` as the policy, the robot model file) for a navigation report's provenance."""
    spec = task_entry(RunDir(run_dir).load_config().task).robot
    return {"policy": run_record(run_dir)}, {robot: model_path(spec, robot) or spec.mjcf_path}


def episode_config(env_config, **changes):
    """The follower's env config for one navigation episode in one scene, with `changes`: one world, no curriculum,
    the robot facing +x, the whole episode (a stalled robot is replanned, not stopped)."""
    return whole_episodes(env_config, num_worlds=1, curriculum=False, spawn_yaw=0.0, **changes)


def navigate_seeds(run_dir, maps: HeightMaps, start, goal, seeds: list[int], physics: str = "native",
                   threads: int | None = None, config: NavigateConfig = NavigateConfig(),
                   planner: PlannerConfig = PlannerConfig(), on_step=None, robot: str = "project",
                   time_limit_s: float | None = None, progress=None, max_speed: float | None = None,
                   nominal: bool = False) -> list[dict]:
    """`navigate` once per episode seed, planned and compiled once (the same plan, another episode each);
    `progress()` is called after each. Each report also holds `speeds_mps`, the body's horizontal speed at every
    control step."""
    check_speed_limit(max_speed)
    policy, run_config = load_follower(run_dir, robot, physics)
    planner = follower_planner(run_config.env, planner)  # the turn limit the follower trained under, if any
    if nominal:
        run_config = dataclasses.replace(run_config, env=nominal_config(run_config.env))
    spec = task_entry(run_config.task).robot
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    try:
        checker = BodyChecker(maps, spec, planner.body)  # one per scene: replans reuse its lattice
        first_plan = plan_path(maps, start, goal, spec, planner, checker)
    except PlanningError as exc:
        if "no collision-free path" in str(exc):
            raise Unreachable(f"the goal cannot be reached: {exc}") from None
        raise NavigationError(str(exc)) from None  # a start or goal where the robot does not fit
    time_limit = time_limit_s if time_limit_s is not None else 20.0 + config.seconds_per_metre * first_plan.length_m
    limit = run_config.env.max_speed if max_speed is None else max_speed  # one limit, not a training draw
    env_config = episode_config(run_config.env, episode_seconds=time_limit, max_speed=limit, speed_range=None)
    env = ConfinedEnv(env_config, spec, terrain_of(maps, start, goal),
                      [first_plan.waypoints], path_capacity=PATH_CAPACITY, speeds=[plan_speeds(first_plan)])
    try:
        check_policy(policy, env)
    except RunDirError as exc:
        raise NavigationError(str(exc)) from None
    vector = VectorEnv(env, 1, physics, threads)
    reports = []
    for seed in seeds:
        report = _follow(vector, env, policy, checker, goal, spec, first_plan, seed, config, planner, on_step)
        reports.append(dict(report, physics=physics, time_limit_s=round(time_limit, 2),
                            policy=repo_path(policy.checkpoint),
                            robot=run_config.env.robot_model,
                            speed_limit_mps=None if math.isinf(limit) else limit,
                            speed_commanded=env_config.speed_command))
        if progress is not None:
            progress()
    return reports


def _follow(vector, env, policy, checker, goal, spec, first_plan, seed, config, planner, on_step) -> dict:
    """One navigation episode of `seed` along `first_plan`, replanning on straying or stalling with `checker` (the
    scene's BodyChecker, whose lattice each replan reuses)."""
    plan = first_plan
    batch = vector.reset(jax.random.PRNGKey(seed), level_carry(np.zeros(1), 0))
    policy.reset()
    if on_step is not None:
        on_step(env, batch.state, plan)
    obs, replans, failed_replans, walked = batch.state.obs, 0, 0, 0.0
    last_waypoint, last_progress_step, steps, speeds = 1, 0, 0, []
    position = np.asarray(batch.state.pipeline_state.qpos)[0, :3]
    while True:
        batch, result = vector.step(batch, jnp.asarray(policy.act(actor_observation(obs, policy.inputs))))
        obs, steps = result.obs, steps + 1
        if bool(result.done[0]):
            final = {k: float(np.asarray(v)[0]) for k, v in result.finished.items()}
            break
        info = batch.state.info
        qpos = np.asarray(batch.state.pipeline_state.qpos)[0]
        speeds.append(float(np.linalg.norm(qpos[:2] - position[:2])) / env.dt)
        walked += speeds[-1] * env.dt
        position = qpos[:3]
        waypoint = int(info["waypoint"][0])
        if waypoint != last_waypoint:
            last_waypoint, last_progress_step = waypoint, steps
        path = np.asarray(info["path"][0])[:int(info["path_len"][0])]
        stray = _distance_to_path(qpos[:2], path[max(waypoint - 1, 0):]) > config.stray_distance
        stalled = (steps - last_progress_step) * env.dt > config.stall_seconds
        if (stray or stalled) and replans + failed_replans < config.max_replans:
            try:
                plan = replan(checker.maps, _pose_of(qpos), goal, spec, planner, checker)
            except PlanningError:
                failed_replans += 1
                last_progress_step = steps
            else:
                replans += 1
                batch = _hand_over(batch, plan.waypoints, plan_speeds(plan), env.config.max_speed)
                last_waypoint, last_progress_step = 1, steps
        if on_step is not None:
            on_step(env, batch.state, plan)
    success = final["success"] > 0
    return {"success": bool(success), "time_s": round(steps * env.dt, 3),
            "time_to_goal_s": round(final["time_to_goal_s"], 3) if success else None,
            "collisions": int(final["collisions"]), "falls": int(final["events/falls"]), "replans": replans,
            "failed_replans": failed_replans, "path_length_m": round(first_plan.length_m, 4),
            "walked_m": round(walked, 4), "mean_speed_mps": round(float(np.mean(speeds)), 4) if speeds else 0.0,
            "p95_speed_mps": round(float(np.percentile(speeds, 95)), 4) if speeds else 0.0,
            "overspeed_mps": round(final["overspeed_mps"], 4),
            "final_distance_m": round(final["final_distance_m"], 4),
            "planner": first_plan.planner, "plan_time_s": round(first_plan.plan_time_s, 4),
            "speeds_mps": np.round(np.asarray(speeds, float), 3)}


def plan_speeds(plan) -> np.ndarray | None:
    """A plan's speed limit per waypoint (m/s, NaN: none of its own; `PlannerConfig.crouch_speed`), or None: the
    navigation's limit everywhere."""
    return None if plan.speeds is None else np.asarray(plan.speeds, float)


def _hand_over(batch, waypoints: np.ndarray, speeds: np.ndarray | None = None, max_speed: float = 1.0):
    """The batch with environment 0 following `waypoints` from its second pose on, with their speed limits
    (`speeds`, one per waypoint; None or NaN: `max_speed`)."""
    info = dict(batch.state.info)
    capacity = info["path"].shape[1]
    if len(waypoints) > capacity:
        keep = np.r_[:capacity - 1, len(waypoints) - 1]
        waypoints, speeds = waypoints[keep], None if speeds is None else np.asarray(speeds)[keep]
    padded = np.concatenate([waypoints, np.repeat(waypoints[-1:], capacity - len(waypoints), 0)]).astype(np.float32)
    info["path"] = info["path"].at[0].set(jnp.asarray(padded))
    info["path_len"] = info["path_len"].at[0].set(len(waypoints))
    limits = pad_speeds([speeds], [len(waypoints)], capacity, max_speed)[0]
    info["speeds"] = info["speeds"].at[0].set(jnp.asarray(limits))
    info["waypoint"] = info["waypoint"].at[0].set(1)
    return dataclasses.replace(batch, state=batch.state.replace(info=info))
