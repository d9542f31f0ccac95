"""`legged demo`: a generated level world (by default level 3, seed 48: a corridor under a 0.62 m roof with a step, a
side block, a low bar and a 66-degree turn; `--tunnel` for the generator's tunnels), a body-pose plan through it,
and the shipped waypoint follower walking Go1 through it to the goal (native MuJoCo by default; MJX too on request)."""

from __future__ import annotations

import json
import time

from legged.cli.args import SEED, add_server_options, bounded, choices
from legged.cli.nav import generated_world, shipped_policy


def cmd_demo(args) -> int:
    """`legged demo`: world, plan and navigation, printed as they happen; 0 if Go1 reached the goal."""
    view = {"host": args.host, "port": args.port} if args.view else None
    return run_demo(args.out, args.seed, args.difficulty, shipped_policy(args.policy), view=view,
                    physics=args.physics, level=None if args.tunnel else args.level)


def run_demo(out: str, seed: int, difficulty: int, policy_dir: str, view: dict | None = None,
             physics=("native",), level: int | None = None) -> int:
    """Write a world (a tunnel of `difficulty`, or with `level` that level of legged.worlds.levels), plan through it
    and navigate it with the follower of `policy_dir` on each of `physics`, on the project's Go1 as it is (no
    randomisation or observation noise); 0 if Go1 reached the goal on every engine. With `view` ({'host', 'port'})
    the dashboard is served afterwards on the demo's world, rolling out the follower."""
    from legged.robots import GO1
    from legged.worlds import write_world
    from planners import HeightMaps, PlannerConfig, follower_planner, plan_path
    from policies.navigate import load_follower, navigate

    if view is not None:
        from web.source import check_port

        check_port(view["host"], view["port"])  # fail before the demo's minute of work
    _, follower = load_follower(policy_dir)  # a missing or foreign policy fails before any work
    world = generated_world(seed, level, difficulty)
    files = write_world(world, GO1, out)
    kind = f"tunnel difficulty={difficulty}" if level is None else f"level={level}"
    print(f"[demo] world seed={seed} {kind}: {world.summary()['size_m']} m, "
          f"min clearance {world.min_clearance:.2f} m -> {files['xml']}")
    plan = plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1,
                     follower_planner(follower.env, PlannerConfig()))  # the plan navigate() makes
    print(f"[demo] {plan.planner} planned {len(plan.waypoints)} body-pose waypoints, {plan.length_m:.2f} m, "
          f"in {plan.plan_time_s:.2f} s (lowest body height {plan.waypoints[:, 2].min():.3f} m)")
    runs = {}
    for engine in physics:
        print(f"[demo] Go1 follows the plan with {policy_dir} in {engine} physics (compiling first: "
              f"{'about a minute' if engine == 'mjx' else 'about 20 s'}) ...", flush=True)
        began = time.perf_counter()
        runs[engine] = navigate(policy_dir, world, world.start, world.goal, engine, seed=seed, nominal=True)
        runs[engine]["wall_s"] = round(time.perf_counter() - began, 1)
        r = runs[engine]
        print(f"[demo] {engine}: {'reached the goal' if r['success'] else 'did NOT reach the goal'} in "
              f"{r['time_s']:.1f} s simulated ({r['collisions']} collisions, {r['replans']} replans, "
              f"{r['final_distance_m']:.2f} m from the goal at the end)", flush=True)
    report = {"world": files, "plan": {"waypoints": len(plan.waypoints), "length_m": round(plan.length_m, 3),
                                       "planner": plan.planner}, "navigation": runs}
    print(json.dumps(report, indent=2))
    print("[demo] open the scene in MuJoCo's viewer with:\n"
          f"       python -m mujoco.viewer --mjcf={files['xml']}")
    ok = all(r["success"] for r in runs.values())
    if view is not None:
        _serve(world, plan, policy_dir, seed, view, physics[0])
    return 0 if ok else 1


def _serve(world, plan, policy_dir: str, seed: int, view: dict, physics: str) -> None:
    """Serve the dashboard on the demo's world, rolling out the follower, until Ctrl-C."""
    from legged.envs.confined import ConfinedEnv
    from legged.robots import GO1
    from legged.worlds import Terrain
    from policies.navigate import episode_config, load_follower, nominal_config, plan_speeds
    from web.app import Dashboard, DashboardConfig
    from web.rollout import RecorderConfig
    from web.source import RolloutSource

    policy, config = load_follower(policy_dir)
    env_config = episode_config(nominal_config(config.env))
    env = ConfinedEnv(env_config, GO1, Terrain.from_worlds([world]), [plan.waypoints], speeds=[plan_speeds(plan)])
    source = RolloutSource(env, f"{config.task} (demo world)", RecorderConfig(physics=physics), policy)
    dashboard = Dashboard(DashboardConfig(host=view["host"], port=view["port"], seed=seed,
                                          steps=env.config.episode_steps), source=source)
    print(f"[demo] dashboard at {dashboard.start()} (the first rollout compiles first; Ctrl-C stops)", flush=True)
    dashboard.wait()


def add_demo_command(sub) -> None:
    """Register `demo`."""
    d = sub.add_parser("demo", help="generate a world, plan through it, and watch the shipped follower walk Go1 "
                                    "to the goal")
    d.add_argument("--out", default="legged-demo", help="where to write the world files")
    d.add_argument("--seed", type=SEED, default=48, help="world seed (default 48: at level 3 a corridor with a step, "
                                                         "a side block, a low bar and a 66-degree turn under a 0.62 m "
                                                         "roof)")
    d.add_argument("--level", type=bounded(int, 0, 4), default=3,
                   help="the level of the world: 0-4 (tunnels; corridors; bars, blocks, pillars; steps, ramps, "
                        "turns; voids; default 3)")
    d.add_argument("--tunnel", action="store_true", help="the generator's pyramid tunnel of --difficulty instead "
                                                         "of a level world")
    d.add_argument("--difficulty", type=bounded(int, 0, 20), default=1, help="difficulty of the tunnel (--tunnel)")
    d.add_argument("--policy", default=None, help="a waypoint-follower run (default: the shipped follower)")
    d.add_argument("--physics", type=choices("mjx", "native"), default=["native"],
                   help="comma-separated physics engines to navigate in (default native; mjx,native runs both)")
    d.add_argument("--view", action="store_true", help="afterwards, serve the dashboard on the demo's world")
    add_server_options(d)
    d.set_defaults(fn=cmd_demo)
