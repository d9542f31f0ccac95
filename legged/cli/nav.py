"""The command line's planning and navigation commands: `legged world`, `plan`, `navigate`, `bench plan`."""

from __future__ import annotations

import json

from legged.cli.args import SEED, add_physics_options, add_robot_option, bounded, ints, xyz


def _print_records(records: list[dict], as_json: bool, print_table) -> int:
    """Benchmark output: a JSON list, or the benchmark's own table."""
    if as_json:
        print(json.dumps(records))
    else:
        print_table(records)
    return 0


def _generated_world(args):
    """The world of --seed and --level (legged.worlds.levels) or else --difficulty (the tunnels)."""
    return generated_world(args.seed, args.level, args.difficulty)


def generated_world(seed: int, level: int | None, difficulty: int | None):
    """The generated world of `seed` at `level` (legged.worlds.levels), or with level None the tunnel of
    `difficulty`."""
    from legged.worlds.generator import WorldConfig
    from legged.worlds.levels import LevelConfig, make_world

    if level is not None:
        return make_world(seed, level, WorldConfig(), LevelConfig())
    return make_world(seed, difficulty, WorldConfig(), None)


def cmd_world(args) -> int:
    """`legged world`: generate a world and write its files."""
    from legged.robots import GO1
    from legged.worlds import write_world

    world = _generated_world(args)
    files = write_world(world, GO1, args.out)
    summary = dict(world.summary(), files=files)
    print(json.dumps(summary) if args.json else
          f"world seed={world.seed} difficulty={world.difficulty} size={summary['size_m']} m "
          f"min clearance={summary['min_clearance_m']} m\n  start={summary['start']} goal={summary['goal']}\n"
          f"  wrote {files['npz']} and {files['xml']}")
    return 0


def _planner_config(args):
    from planners import PlannerConfig

    config = PlannerConfig(planner=args.planner, time_limit=args.time_limit, seed=args.planner_seed,
                           spacing=args.spacing, space=args.space, max_checks=args.max_checks,
                           crouch_speed=args.crouch_speed, turn_accel=args.turn_accel,
                           face_travel=None if args.headings is None else args.headings == "travel")
    config.validate()
    return config


def _scene_maps(args):
    """Height maps sampled from a user's MJCF scene around its start and goal (errors name the file and the cause)."""
    from legged.worlds.scenes import read_model
    from planners import navigation_maps

    if args.start is None or args.goal is None:
        raise ValueError("--scene needs --start X,Y,Z and --goal X,Y,Z (body centre, metres)")
    return navigation_maps(read_model(args.scene), args.start, args.goal, args.resolution)


def cmd_plan(args) -> int:
    """`legged plan`: body-pose waypoints through a generated world or an MJCF scene."""
    import numpy as np

    from planners import HeightMaps, plan_path
    from legged.robots import GO1

    config = _planner_config(args)  # bad settings fail before any sampling
    if args.scene:
        maps, start, goal = _scene_maps(args), np.array(args.start), np.array(args.goal)
    else:
        world = _generated_world(args)
        maps = HeightMaps.from_world(world)
        start = np.array(args.start) if args.start else world.start
        goal = np.array(args.goal) if args.goal else world.goal
    plan = plan_path(maps, start, goal, GO1, config)
    if args.json:
        print(json.dumps(plan.to_json()))
    else:
        print(f"{plan.planner}: {len(plan.waypoints)} waypoints, {plan.length_m:.3f} m, planned in "
              f"{plan.plan_time_s:.3f} s\n  x y z roll pitch yaw:")
        for pose in plan.waypoints:
            print("  " + " ".join(f"{v:7.3f}" for v in pose))
    return 0


def cmd_bench_plan(args) -> int:
    """`legged bench plan`: planning time and path length, or the narrow scenes."""
    from planners.bench import PREVIOUS_PLANNER, bench_narrow, bench_planner, print_table

    if args.narrow:
        report = bench_narrow({"current": _planner_config(args), "previous": PREVIOUS_PLANNER},
                              progress=not args.quiet)
        if args.json:
            print(json.dumps(report))
        else:
            for r in report["scenes"]:
                print(f"{r['scene']:>20} {r['config']:>8} {'solved' if r['solved'] else 'FAILED':>7} "
                      f"{r['time_s']:7.3f} s")
            for label, summary in report["summary"].items():
                print(f"{label}: {summary['solved']}/{summary['scenes']} solved, median {summary['median_time_s']} s")
        return 0
    records = bench_planner(args.difficulties, args.worlds, _planner_config(args), args.first_seed,
                            progress=not args.quiet)
    return _print_records(records, args.json, print_table)


def cmd_bench_navigate(args) -> int:
    """`legged bench navigate`: plan, follow and replan on a directory's scenes."""
    from policies.nav_bench import bench_navigate, print_table

    report = bench_navigate(args.scenes, shipped_policy(args.policy), args.seeds, args.first_seed, args.robot,
                            args.physics, args.threads or None, args.resolution, _planner_config(args),
                            progress=not args.quiet, max_speed=args.max_speed)
    if args.json:
        print(json.dumps(report))
    else:
        print_table(report)
    return 0


def cmd_scenes(args) -> int:
    """`legged scenes`: write the navigation benchmark's scenes."""
    from legged.worlds.bench_scenes import build
    from legged.worlds.scenes import write_scenes

    paths = write_scenes(args.out, build())
    if args.json:
        print(json.dumps({"out": str(args.out), "scenes": [p.name for p in paths]}))
    else:
        print(f"[scenes] wrote {len(paths)} scenes to {args.out}: {', '.join(p.stem for p in paths)}")
    return 0


def _add_planner_options(parser) -> None:
    from planners import PLANNERS

    parser.add_argument("--planner", default="auto",
                        help="auto (RRTConnect for 60 motion checks, then the complete lattice search), lattice, or "
                             f"an OMPL planner: {', '.join(PLANNERS)} (RRT*, BIT* style names work too)")
    parser.add_argument("--space", choices=["projected", "full"], default="projected",
                        help="projected: search x, y, yaw with body height, roll and pitch derived from the gap "
                             "(default); full: sample all six (the earlier planner)")
    parser.add_argument("--time-limit", type=bounded(float, 0.0, 3600.0), default=5.0,
                        help="seconds an OMPL planner may search")
    parser.add_argument("--max-checks", type=bounded(int, 0, 10**9), default=0,
                        help="an OMPL planner also stops after this many motion checks (0: the time limit alone; "
                             "a count gives the same search on any machine)")
    parser.add_argument("--spacing", type=bounded(float, 0.01, 10.0), default=0.5,
                        help="largest distance between waypoints, m")
    parser.add_argument("--planner-seed", type=SEED, default=0, help="seed of OMPL's sampling")
    parser.add_argument("--crouch-speed", type=bounded(float, 0.0, 10.0), default=None, metavar="M/S",
                        help="speed limit of the plan where the body must crouch (under bars and low roofs)")
    parser.add_argument("--turn-accel", type=bounded(float, 0.0, 100.0), default=None, metavar="M/S2",
                        help="largest sideways acceleration the plan asks for in its turns: where the path turns, the "
                             "speed limit is sqrt(this / curvature) (default: the follower's env.plan_turn_accel, "
                             "the limit its training plans had, if any)")
    parser.add_argument("--headings", choices=["search", "travel"], default=None,
                        help="search: the body headings of the search, which turns the body as little as it can; "
                             "travel: each waypoint faces the way the path goes, where the body fits so (default: a "
                             "follower's env.plan_face_travel, the headings its training plans had; else search)")


SHIPPED_FOLLOWER = "assets/policies/go1-confined-follower"
"""The waypoint follower that ships with the project (navigate's and the demo's default policy)."""


def cmd_navigate(args) -> int:
    """`legged navigate`: plan, follow and replan; 0 if the robot reached the goal."""
    import numpy as np

    from policies.navigate import Unreachable, load_follower, navigate

    policy_dir = shipped_policy(args.policy)
    load_follower(policy_dir, args.robot, args.physics)  # another task's policy or an unusable robot model fails first
    if args.scene:
        maps, start, goal = _scene_maps(args), np.array(args.start), np.array(args.goal)
        where = {"scene": args.scene}
    else:
        if args.start is not None or args.goal is not None:
            raise ValueError("--start and --goal go with --scene; a generated world (--seed, --difficulty or --level) "
                             "has its own")
        world = _generated_world(args)
        maps, start, goal = world, world.start, world.goal
        where = {"world_seed": args.seed, **({"difficulty": args.difficulty} if args.level is None else
                                             {"level": args.level})}
    recording = None
    if args.view or args.record:
        from web.nav_recording import NavigationRecording

        recording = NavigationRecording()
    if args.view:
        from web.source import check_port

        check_port(args.host, args.port)  # fail before the work
    where = dict(where, start=[round(float(v), 4) for v in start[:3]], goal=[round(float(v), 4) for v in goal[:3]])
    try:
        report = navigate(policy_dir, maps, start, goal, args.physics, args.threads or None,
                          planner=_planner_config(args), seed=args.seed, robot=args.robot,
                          on_step=None if recording is None else recording.add, max_speed=args.max_speed,
                          where=where)
    except Unreachable as exc:
        print(json.dumps(dict(where, success=False, reachable=False, error=str(exc))) if args.json
              else f"legged navigate: {exc}")
        return 1
    print(json.dumps(report) if args.json else json.dumps(report, indent=2))
    if recording is not None:
        traj = recording.trajectory(dict(report, task="navigation"))
        if args.record:
            print(f"[navigate] wrote {traj.save(args.record)}; play it with: legged view --trajectory {args.record}",
                  flush=True)
        if args.view:
            from web.app import Dashboard, DashboardConfig

            dashboard = Dashboard(DashboardConfig(host=args.host, port=args.port), trajectory=traj)
            print(f"[navigate] dashboard at {dashboard.start()} (Ctrl-C stops it)", flush=True)
            dashboard.wait()
    return 0 if report["success"] else 1


def shipped_policy(policy: str | None) -> str:
    """The policy run directory to use: `policy`, else the shipped follower (a clear error if it is absent)."""
    from pathlib import Path

    if policy:
        return policy
    for base in (Path.cwd(), Path(__file__).resolve().parents[2]):
        if (base / SHIPPED_FOLLOWER / "config.yaml").is_file():
            return str(base / SHIPPED_FOLLOWER)
    raise FileNotFoundError(f"no shipped follower at {SHIPPED_FOLLOWER}; pass --policy RUN (a confined-waypoints run)")


def _add_speed_option(parser) -> None:
    """--max-speed: the navigation's speed limit."""
    parser.add_argument("--max-speed", type=bounded(float, 0.0, 10.0), default=None, metavar="M/S",
                        help="speed limit, m/s (default: the policy's env.max_speed, 1 m/s); a follower trained with "
                             "env.speed_command is told it, one trained without runs at its own speed and is only "
                             "measured against it")


def _add_level_option(parser) -> None:
    """--level: a generated world of legged.worlds.levels instead of the tunnels."""
    parser.add_argument("--level", type=bounded(int, 0, 4), default=None,
                        help="a world of level 0-4 instead of --difficulty's tunnels (it overrides --difficulty): "
                        "tunnels; corridors, open sky, crawls; bars, blocks, pillars; steps, ramps, turns; voids")


def add_navigation_commands(sub) -> None:
    """The `world`, `plan` and `navigate` sub-commands."""
    w = sub.add_parser("world", help="generate a confined world (world.npz + world.xml)")
    w.add_argument("--seed", type=SEED, default=0)
    w.add_argument("--difficulty", type=bounded(int, 0, 20), default=0,
                   help="0/1/2 give 3/4/5 m tunnels; higher is longer")
    _add_level_option(w)
    w.add_argument("--out", required=True, help="output directory")
    w.add_argument("--json", action="store_true", help="print a JSON summary")
    w.set_defaults(fn=cmd_world)

    pl = sub.add_parser("plan", help="plan body-pose waypoints through a generated world or an MJCF scene")
    pl.add_argument("--seed", type=SEED, default=0, help="seed of the generated world")
    pl.add_argument("--difficulty", type=bounded(int, 0, 20), default=0)
    _add_level_option(pl)
    pl.add_argument("--scene", default=None, help="plan through this MJCF scene instead (needs --start, --goal)")
    pl.add_argument("--start", type=xyz, default=None, help="body centre X,Y,Z (default: the world's start)")
    pl.add_argument("--goal", type=xyz, default=None, help="body centre X,Y,Z (default: the world's goal)")
    pl.add_argument("--resolution", type=bounded(float, 0.005, 1.0), default=0.025,
                    help="map resolution when sampling --scene, m (the maps are widened by one cell to be safe)")
    _add_planner_options(pl)
    pl.add_argument("--json", action="store_true",
                    help="print one JSON object: waypoints [x, y, z, roll, pitch, yaw], length_m, plan_time_s, "
                         "planner")
    pl.set_defaults(fn=cmd_plan)

    nv = sub.add_parser("navigate", help="plan, follow with a trained waypoint follower, replan when straying")
    nv.add_argument("--scene", default=None, help="MJCF scene to navigate (else a generated world)")
    nv.add_argument("--start", type=xyz, default=None, help="with --scene: start body centre X,Y,Z")
    nv.add_argument("--goal", type=xyz, default=None, help="with --scene: goal body centre X,Y,Z")
    nv.add_argument("--resolution", type=bounded(float, 0.005, 1.0), default=0.025,
                    help="map resolution of --scene, m")
    nv.add_argument("--seed", type=SEED, default=0, help="world seed (without --scene) and episode seed")
    nv.add_argument("--difficulty", type=bounded(int, 0, 20), default=0, help="generated world's level")
    _add_level_option(nv)
    nv.add_argument("--policy", default=None, help=f"a waypoint-follower run (default: {SHIPPED_FOLLOWER})")
    _add_speed_option(nv)
    add_physics_options(nv, "native")
    add_robot_option(nv)
    _add_planner_options(nv)
    nv.add_argument("--view", action="store_true",
                    help="afterwards, show the navigation and its replans in the dashboard")
    nv.add_argument("--record", default=None, metavar="FILE", help="save the navigation as a trajectory (.npz)")
    nv.add_argument("--host", default="127.0.0.1", help="dashboard address (with --view)")
    nv.add_argument("--port", type=bounded(int, 0, 65535), default=8080, help="dashboard port (with --view)")
    nv.add_argument("--json", action="store_true", help="one-line JSON")
    nv.set_defaults(fn=cmd_navigate)

    sc = sub.add_parser("scenes", help="write the navigation benchmark's scenes (MJCF built from primitives)")
    sc.add_argument("--out", required=True, help="output directory (one NAME.xml per scene)")
    sc.add_argument("--json", action="store_true", help="print a JSON summary")
    sc.set_defaults(fn=cmd_scenes)


def add_bench_plan(bsub) -> None:
    """The `bench plan` and `bench navigate` sub-commands."""
    bp = bsub.add_parser("plan", help="planning time and path length per difficulty over generated worlds")
    bp.add_argument("--difficulties", type=ints(0, 20), default=[0, 1, 2], help="comma-separated levels")
    bp.add_argument("--worlds", type=bounded(int, 1, 10000), default=20,
                    help="worlds per difficulty (seeds first-seed onward)")
    bp.add_argument("--first-seed", type=SEED, default=0)
    bp.add_argument("--narrow", action="store_true",
                    help="instead: the fixed narrow-passage scenes (low bars, side gaps), beside the previous planner")
    _add_planner_options(bp)
    bp.add_argument("--json", action="store_true", help="print a JSON list, one object per difficulty")
    bp.add_argument("--quiet", action="store_true", help="no progress bars")
    bp.set_defaults(fn=cmd_bench_plan)

    bn = bsub.add_parser("navigate", help="plan, follow and replan on every scene of a directory, a few seeds each")
    bn.add_argument("--scenes", required=True, help="directory of scene files (start, goal, time limit inside; "
                    "legged scenes --out DIR writes the benchmark's)")
    bn.add_argument("--seeds", type=bounded(int, 1, 1000), default=5, help="episodes per scene")
    bn.add_argument("--first-seed", type=SEED, default=0)
    bn.add_argument("--policy", default=None, help=f"a waypoint-follower run (default: {SHIPPED_FOLLOWER})")
    _add_speed_option(bn)
    bn.add_argument("--resolution", type=bounded(float, 0.005, 1.0), default=0.025, help="map resolution, m")
    add_physics_options(bn, "native")
    add_robot_option(bn)
    _add_planner_options(bn)
    bn.add_argument("--json", action="store_true", help="print one JSON object")
    bn.add_argument("--quiet", action="store_true", help="no progress bar")
    bn.set_defaults(fn=cmd_bench_navigate)
