"""The `legged` command line: worlds, planning, benchmarks and the demo."""

from __future__ import annotations

import argparse
import json
import sys

from legged.cli_args import (SEED, THREADS, Parser, bounded, choices, ints, join_negative_coordinates, task_names,
                             xyz)


def _print_records(records: list[dict], as_json: bool, print_table) -> int:
    """Benchmark output: a JSON list, or the benchmark's own table."""
    if as_json:
        print(json.dumps(records))
    else:
        print_table(records)
    return 0


def cmd_world(args) -> int:
    from legged.robots import GO1
    from legged.worlds import generate_world, write_world

    world = generate_world(args.seed, args.difficulty)
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
                           spacing=args.spacing)
    config.validate()
    return config


def _scene_maps(args):
    """Height maps sampled from a user's MJCF scene (errors name the file and the cause)."""
    from pathlib import Path

    import mujoco

    from planners import maps_from_scene, reference_between

    if args.start is None or args.goal is None:
        raise ValueError("--scene needs --start X,Y,Z and --goal X,Y,Z (body centre, metres)")
    path = Path(args.scene)
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise ValueError(f"cannot load scene {path}: {exc}") from None
    return maps_from_scene(model, reference_between(args.start, args.goal), args.resolution)


def cmd_plan(args) -> int:
    import numpy as np

    from planners import HeightMaps, plan_path
    from legged.robots import GO1
    from legged.worlds import generate_world

    config = _planner_config(args)  # bad settings fail before any sampling
    if args.scene:
        maps, start, goal = _scene_maps(args), np.array(args.start), np.array(args.goal)
    else:
        world = generate_world(args.seed, args.difficulty)
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
    from planners.bench import bench_planner, print_table

    records = bench_planner(args.difficulties, args.worlds, _planner_config(args), args.first_seed,
                            progress=not args.quiet)
    return _print_records(records, args.json, print_table)


def _add_planner_options(parser) -> None:
    from planners import PLANNERS

    parser.add_argument("--planner", default="rrtconnect",
                        help=f"OMPL planner: {', '.join(PLANNERS)} (RRT*, BIT* style names work too)")
    parser.add_argument("--time-limit", type=bounded(float, 0.0, 3600.0), default=5.0,
                        help="seconds the planner may search")
    parser.add_argument("--spacing", type=bounded(float, 0.01, 10.0), default=0.5,
                        help="largest distance between waypoints, m")
    parser.add_argument("--planner-seed", type=SEED, default=0, help="seed of OMPL's sampling")


def cmd_bench(args) -> int:
    from legged.bench import attach_peer, bench_env, bench_peer, print_table
    from legged.tasks import default_config

    default_config(args.task)  # unknown task -> clear error before any compilation
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = bench_env(args.task, args.batch, args.seconds, physics=args.physics, threads=args.threads or None,
                        progress=progress)
    if args.peer_python:
        if progress:
            progress("running the Playground peer in the same run")
        attach_peer(records, bench_peer(args.peer_python, args.peer_script, args.batch, args.seconds))
    return _print_records(records, args.json, print_table)


def cmd_bench_soak(args) -> int:
    from legged.bench import soak

    progress = None if args.quiet else (lambda msg: print(f"[soak] {msg}", file=sys.stderr, flush=True))
    records = [soak(task, args.steps, args.batch, args.seed, args.physics, args.threads or None, progress)
               for task in args.tasks]
    if args.json:
        print(json.dumps(records))
    else:
        for r in records:
            print(f"{r['task']:20s} {r['env_steps']:>10,} steps  non-finite values {r['non_finite_values']}  "
                  f"episodes {r['episodes']}  diverged {r['diverged_episodes']}  {r['env_steps_per_s']:.0f} steps/s")
    return 0


def cmd_bench_soccer(args) -> int:
    from legged.soccer.bench import bench_soccer, print_soccer_table

    if not set(args.team_sizes) <= {1, 2}:
        raise ValueError(f"--team-sizes takes 1 and/or 2 (1v1, 2v2), got {args.team_sizes}")
    cameras = {"off": (False,), "on": (True,), "both": (False, True)}[args.camera]
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = bench_soccer(args.team_sizes, cameras, args.batch, args.seconds, peer=not args.no_peer,
                           peer_steps=args.peer_steps, physics=args.physics, threads=args.threads or None,
                           progress=progress)
    return _print_records(records, args.json, print_soccer_table)


def _add_physics_options(parser, default: str = "mjx") -> None:
    parser.add_argument("--physics", choices=["mjx", "native"], default=default,
                        help="physics engine: mjx (JAX; for accelerators) or native (MuJoCo's C engine; fastest on a CPU)")
    parser.add_argument("--threads", type=THREADS, default=0, metavar="N",
                        help="CPU threads of native physics and torch (default: every core)")


def cmd_train(args) -> int:
    from policies.training import resume_run, start_run

    if args.resume:
        if args.task:
            raise ValueError("--resume DIR continues a run with its own config; do not name a task")
        record = resume_run(args.resume, progress=not args.quiet)
    else:
        if not args.task:
            raise ValueError("name a task (see `legged tasks`) or continue a run with --resume DIR")
        record = start_run(args.task, args.run_dir, backend=args.backend, num_envs=args.num_envs,
                           timesteps=args.timesteps, seed=args.seed, overrides=args.set, progress=not args.quiet,
                           physics=args.physics, threads=args.threads)
    print(json.dumps(record))
    return 0


def cmd_eval(args) -> int:
    import dataclasses

    from legged.tasks import task_entry
    from policies.evaluate import evaluate, held_out, summarize
    from policies.policy_io import load_policy
    from policies.run_dir import check_compatible
    from policies.training import build_env

    if args.episodes < 1:
        raise ValueError(f"--episodes must be >= 1, got {args.episodes}")
    policy, config = load_policy(args.run_dir, args.checkpoint)
    env = build_env(dataclasses.replace(config, env=held_out(config.task, config.env)))
    check_compatible(policy.obs_sizes, policy.num_actions, env, policy.checkpoint)
    finals = evaluate(env, policy, args.episodes, args.seed, args.physics, args.num_envs, args.threads or None,
                      progress=not args.quiet)
    confined = task_entry(config.task).kind == "confined"
    report = dict(summarize(finals, confined), physics=args.physics, seed=args.seed,
                  checkpoint=str(policy.checkpoint), trained_steps=policy.step, task=config.task)
    print(json.dumps(report) if args.json else json.dumps(report, indent=2))
    return 0


def cmd_convert(args) -> int:
    from policies.convert import convert_run

    report = convert_run(args.run_dir, args.trust_pickles)
    print(json.dumps(report) if args.json else f"[convert] {len(report['converted'])} checkpoint(s) converted in "
          f"{report['run']}")
    return 0


def cmd_plot(args) -> int:
    from policies.plots import plot_run

    path = plot_run(args.run_dir, args.y, args.x, args.out, args.hline)
    print(json.dumps({"plot": str(path)}) if args.json else f"[plot] wrote {path}")
    return 0


def cmd_export(args) -> int:
    from policies.export import export_onnx
    from policies.policy_io import load_policy

    if not args.onnx:
        raise ValueError("choose a format: --onnx")
    policy, _ = load_policy(args.run_dir, args.checkpoint)
    report = export_onnx(policy, args.out or f"{args.run_dir}/policy.onnx")
    print(json.dumps(report))
    return 0


def cmd_camera(args) -> int:
    from legged.soccer.states import game_start
    from legged.soccer.vision import write_camera_images
    from legged.tasks import TASKS, make, task_entry

    if task_entry(args.task).kind != "soccer":  # unknown names fail here too
        soccer = sorted(n for n, e in TASKS.items() if e.kind == "soccer")
        raise ValueError(f"{args.task!r} is not a soccer task; soccer tasks: {', '.join(soccer)}")
    env = make(args.task)
    report = write_camera_images(env.mj_model, game_start(env, args.seed), args.out, env.config.camera)
    report = dict(report, task=args.task, seed=args.seed)
    if args.json:
        print(json.dumps(report))
    else:
        print(f"[camera] {args.task} seed {args.seed}: segmentation agreement with MuJoCo's renderer "
              f"{report['segmentation']:.4f}, median depth error {report['depth_median_abs_error']:.2e} m; "
              f"wrote {len(report['files']['ray'])} agent(s) x 2 images to {args.out}")
    return 0


def cmd_tasks(args) -> int:
    from legged.tasks import TASKS

    rows = [{"task": e.name, "kind": e.kind, "robot": e.robot.name, "physics": list(e.physics),
             "backends": list(e.backends), "vision": e.vision} for e in TASKS.values()]
    if args.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        print(f"{r['task']:20s} {r['kind']:11s} {r['robot']:5s} physics {','.join(r['physics']):11s} "
              f"backends {','.join(r['backends'])}")
    return 0


def cmd_demo(args) -> int:
    from legged.demo import run_demo

    view = {"host": args.host, "port": args.port} if args.view else None
    return run_demo(args.out, args.seconds, args.seed, args.difficulty, view=view, physics=args.physics)


def cmd_view(args) -> int:
    from web.app import Dashboard, DashboardConfig
    from web.source import ViewRequest, resolve

    request = ViewRequest(run_dir=args.run_dir, task=args.task, checkpoint=args.checkpoint, trajectory=args.trajectory,
                          num_envs=args.num_envs, physics=args.physics, seed=args.seed, steps=args.steps, host=args.host,
                          port=None if args.save else args.port)
    resolved = resolve(request, log=lambda msg: print(msg, flush=True))
    if args.save:
        if resolved.source is None:
            raise ValueError("--save records a rollout; it cannot be combined with --trajectory")
        print("[view] compiling and recording (about a minute on a CPU) ...", flush=True)
        path = resolved.source.record(args.steps, args.seed).save(args.save)
        print(f"[view] wrote {path}; play it with: legged view --trajectory {path}")
        return 0
    dashboard = Dashboard(DashboardConfig(host=args.host, port=args.port, steps=args.steps, seed=args.seed),
                          source=resolved.source, trajectory=resolved.trajectory, run_dir=resolved.run_dir)
    url = dashboard.start()
    print(f"[view] dashboard at {url} (Ctrl-C stops it)", flush=True)
    dashboard.wait()
    return 0


def _add_server_options(parser, port: int = 8080) -> None:
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to bind (default 127.0.0.1, this machine only; 0.0.0.0 exposes it)")
    parser.add_argument("--port", type=bounded(int, 0, 65535), default=port, help="port to bind (0: any free port)")


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="legged", description="Legged-robot RL in MuJoCo/MJX.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    w = sub.add_parser("world", help="generate a confined world (world.npz + world.xml)")
    w.add_argument("--seed", type=SEED, default=0)
    w.add_argument("--difficulty", type=bounded(int, 0, 20), default=0, help="0/1/2 give 3/4/5 m tunnels; higher is longer")
    w.add_argument("--out", required=True, help="output directory")
    w.add_argument("--json", action="store_true", help="print a JSON summary")
    w.set_defaults(fn=cmd_world)

    b = sub.add_parser("bench", help="benchmarks")
    bsub = b.add_subparsers(dest="what", required=True)
    be = bsub.add_parser("env", help="environment steps per second on MJX and native MuJoCo, beside bare physics")
    be.add_argument("--task", default="confined-waypoints")
    be.add_argument("--batch", type=ints(1, 65536), default=[1, 64, 256], help="comma-separated batch sizes")
    be.add_argument("--physics", type=choices("mjx", "native", "rollout"), default=["mjx", "native", "rollout"],
                    help="comma-separated: mjx, native (the task on each engine), rollout (bare native physics)")
    be.add_argument("--threads", type=THREADS, default=0, metavar="N",
                    help="threads of native physics (default: every core)")
    be.add_argument("--seconds", type=bounded(float, 0.0, 3600.0), default=3.0, help="timed seconds per batch size")
    be.add_argument("--peer-python", default=None,
                    help="python of the MuJoCo Playground peer (../shared/peers); adds ratio_vs_peer")
    be.add_argument("--peer-script", default=None,
                    help="the peer's benchmark script (default: legged/peers/playground.py of this install)")
    be.add_argument("--json", action="store_true", help="print a JSON list, one object per batch size")
    be.add_argument("--quiet", action="store_true", help="no progress messages")
    be.set_defaults(fn=cmd_bench)
    sk = bsub.add_parser("soak", help="random and extreme actions under randomisation: non-finite values and "
                                      "divergences that reach the learner")
    sk.add_argument("--tasks", type=task_names, default=["confined-waypoints", "soccer-1v1"],
                    help="comma-separated tasks")
    sk.add_argument("--steps", type=bounded(int, 1, 10**9), default=1_000_000, help="env steps per task")
    sk.add_argument("--batch", type=bounded(int, 1, 65536), default=256)
    sk.add_argument("--seed", type=SEED, default=0)
    sk.add_argument("--physics", choices=["mjx", "native"], default="native")
    sk.add_argument("--threads", type=THREADS, default=0, metavar="N", help="native physics threads")
    sk.add_argument("--json", action="store_true")
    sk.add_argument("--quiet", action="store_true")
    sk.set_defaults(fn=cmd_bench_soak)
    bs = bsub.add_parser("soccer", help="soccer env steps per second (1v1, 2v2, with/without cameras) beside "
                                        "native MuJoCo and dm_control's soccer")
    bs.add_argument("--team-sizes", type=ints(1), default=[1, 2], help="players per team: 1 and/or 2")
    bs.add_argument("--camera", choices=("off", "on", "both"), default="both", help="head cameras rendered")
    bs.add_argument("--batch", type=ints(1, 65536), default=[1, 16, 64], help="comma-separated batch sizes")
    bs.add_argument("--seconds", type=bounded(float, 0.0, 3600.0), default=3.0, help="timed seconds per measurement")
    bs.add_argument("--no-peer", action="store_true", help="skip dm_control's soccer")
    bs.add_argument("--peer-steps", type=bounded(int, 1, 100000), default=20, help="control steps timed per dm_control env")
    bs.add_argument("--physics", type=choices("mjx", "native"), default=["mjx", "native"],
                    help="comma-separated physics engines to measure")
    bs.add_argument("--threads", type=THREADS, default=0, metavar="N",
                    help="threads of native physics (default: every core)")
    bs.add_argument("--json", action="store_true", help="print a JSON list, one object per measurement")
    bs.add_argument("--quiet", action="store_true", help="no progress messages")
    bs.set_defaults(fn=cmd_bench_soccer)
    bp = bsub.add_parser("plan", help="planning time and path length per difficulty over generated worlds")
    bp.add_argument("--difficulties", type=ints(0, 20), default=[0, 1, 2], help="comma-separated levels")
    bp.add_argument("--worlds", type=bounded(int, 1, 10000), default=20, help="worlds per difficulty (seeds first-seed onward)")
    bp.add_argument("--first-seed", type=SEED, default=0)
    _add_planner_options(bp)
    bp.add_argument("--json", action="store_true", help="print a JSON list, one object per difficulty")
    bp.add_argument("--quiet", action="store_true", help="no progress bars")
    bp.set_defaults(fn=cmd_bench_plan)

    pl = sub.add_parser("plan", help="plan body-pose waypoints through a generated world or an MJCF scene")
    pl.add_argument("--seed", type=SEED, default=0, help="seed of the generated world")
    pl.add_argument("--difficulty", type=bounded(int, 0, 20), default=0)
    pl.add_argument("--scene", default=None, help="plan through this MJCF scene instead (needs --start, --goal)")
    pl.add_argument("--start", type=xyz, default=None, help="body centre X,Y,Z (default: the world's start)")
    pl.add_argument("--goal", type=xyz, default=None, help="body centre X,Y,Z (default: the world's goal)")
    pl.add_argument("--resolution", type=bounded(float, 0.005, 1.0), default=0.05, help="map resolution when sampling --scene, m")
    _add_planner_options(pl)
    pl.add_argument("--json", action="store_true",
                    help="print one JSON object: waypoints [x, y, z, roll, pitch, yaw], length_m, plan_time_s, planner")
    pl.set_defaults(fn=cmd_plan)

    tr = sub.add_parser("train", help="train a policy (Brax PPO or rsl-rl PPO) into a run directory")
    tr.add_argument("task", nargs="?", help="task name (legged tasks)")
    tr.add_argument("--backend", choices=["rsl", "brax"], default="rsl")
    tr.add_argument("--num-envs", type=bounded(int, 1, 2**20), default=256)
    tr.add_argument("--timesteps", type=bounded(int, 1, 10**12), default=1_000_000, help="environment steps, all envs together")
    tr.add_argument("--seed", type=SEED, default=0)
    _add_physics_options(tr)
    tr.add_argument("--run-dir", default=None, help="where the run is written (default runs/<task>-<time>)")
    tr.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="override any config field, e.g. ppo.learning_rate=3e-4, env.episode_seconds=10, "
                         "checkpoint_every=5, device=cuda (repeatable; see config.yaml of a run for all fields)")
    tr.add_argument("--resume", default=None, metavar="DIR", help="continue the run in DIR from its last checkpoint")
    tr.add_argument("--quiet", action="store_true", help="no progress bar")
    tr.set_defaults(fn=cmd_train)

    ev = sub.add_parser("eval", help="evaluate a run's policy on held-out worlds (MJX or native MuJoCo)")
    ev.add_argument("run_dir")
    ev.add_argument("--checkpoint", default=None, help="a checkpoint file (default: the run's newest)")
    ev.add_argument("--episodes", type=bounded(int, 1, 100000), default=32)
    ev.add_argument("--seed", type=SEED, default=12345, help="seed of the evaluation episodes")
    _add_physics_options(ev)
    ev.add_argument("--num-envs", type=bounded(int, 1, 4096), default=16, help="episodes run side by side")
    ev.add_argument("--json", action="store_true", help="one-line JSON")
    ev.add_argument("--quiet", action="store_true", help="no progress bar")
    ev.set_defaults(fn=cmd_eval)

    cv = sub.add_parser("convert-checkpoints", help="rewrite a run's old pickled checkpoints as data-only files")
    cv.add_argument("run_dir")
    cv.add_argument("--trust-pickles", action="store_true",
                    help="you trust this run: its pickles may be loaded once to convert them (pickles can run code)")
    cv.add_argument("--json", action="store_true")
    cv.set_defaults(fn=cmd_convert)

    pt = sub.add_parser("plot", help="plot a metric of a run's metrics.jsonl into a PNG")
    pt.add_argument("run_dir")
    pt.add_argument("--y", default="episode_return", help="metric to plot (a numeric field of metrics.jsonl)")
    pt.add_argument("--x", default="step", choices=["step", "wall_s", "iteration"], help="horizontal axis")
    pt.add_argument("--hline", type=float, default=None, help="draw a dashed horizontal line (a goal) here")
    pt.add_argument("--out", default=None, help="PNG file (default RUN_DIR/<metric>.png)")
    pt.add_argument("--json", action="store_true")
    pt.set_defaults(fn=cmd_plot)

    ex = sub.add_parser("export", help="export a run's policy (ONNX) and check it against the framework")
    ex.add_argument("run_dir")
    ex.add_argument("--onnx", action="store_true", help="write an ONNX model")
    ex.add_argument("--checkpoint", default=None, help="a checkpoint file (default: the run's newest)")
    ex.add_argument("--out", default=None, help="output file (default RUN_DIR/policy.onnx)")
    ex.set_defaults(fn=cmd_export)

    c = sub.add_parser("camera", help="each soccer player's head camera: the JAX ray renderer beside MuJoCo's")
    c.add_argument("--task", default="soccer-1v1-vision", help="soccer-1v1, soccer-2v2 or soccer-1v1-vision")
    c.add_argument("--seed", type=SEED, default=0, help="game state: 0 is the kick-off, others move robots and ball")
    c.add_argument("--out", default="camera", help="folder for agent<i>_ray.png and agent<i>_native.png")
    c.add_argument("--json", action="store_true", help="print the agreement figures as JSON")
    c.set_defaults(fn=cmd_camera)

    t = sub.add_parser("tasks", help="list the registered tasks: kind, robot, physics engines, trainers")
    t.add_argument("--json", action="store_true", help="one JSON list")
    t.set_defaults(fn=cmd_tasks)

    d = sub.add_parser("demo", help="generate a world and run Go1 in it (MJX and native MuJoCo)")
    d.add_argument("--out", default="legged-demo", help="where to write the world files")
    d.add_argument("--seconds", type=bounded(float, 0.0, 3600.0), default=4.0, help="simulated seconds")
    d.add_argument("--seed", type=SEED, default=0)
    d.add_argument("--difficulty", type=bounded(int, 0, 20), default=1)
    d.add_argument("--physics", type=choices("mjx", "native"), default=["mjx", "native"],
                   help="comma-separated physics engines to step side by side (default both, with their qpos gap)")
    d.add_argument("--view", action="store_true", help="afterwards, serve the dashboard on the demo's world")
    _add_server_options(d)
    d.set_defaults(fn=cmd_demo)

    v = sub.add_parser("view", help="the browser dashboard: a run's policy, a task, or a recorded trajectory")
    v.add_argument("run_dir", nargs="?", default=None,
                   help="training run: its policy, training curves (live) and checkpoint picker")
    v.add_argument("--task", default=None, help="task to show (default: the run's, else confined-waypoints)")
    v.add_argument("--checkpoint", default=None, help="checkpoint file (default: the run's newest)")
    v.add_argument("--trajectory", default=None, metavar="FILE.npz", help="play a recorded trajectory instead")
    v.add_argument("--num-envs", type=bounded(int, 1, 16), default=1, help="environments side by side (1-16)")
    v.add_argument("--physics", choices=["mjx", "native"], default="mjx",
                   help="physics of the rollouts: mjx, or native (MuJoCo's C engine; no MJX compilation of physics)")
    v.add_argument("--seed", type=SEED, default=0, help="seed of the first rollout")
    v.add_argument("--steps", type=bounded(int, 1, 100000), default=500, help="control steps per rollout (50 per second)")
    v.add_argument("--save", default=None, metavar="FILE.npz",
                   help="record one rollout into FILE.npz and exit instead of serving")
    _add_server_options(v)
    v.set_defaults(fn=cmd_view)
    return p


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser().parse_args(join_negative_coordinates(argv))
    except SystemExit as exc:  # a usage error (already printed on one line) or --help: a return code
        return exc.code if isinstance(exc.code, int) else 2
    from legged.tasks import UnknownTaskError
    from legged.worlds import WorldError

    try:
        return args.fn(args)
    except (UnknownTaskError, WorldError, OSError, ValueError) as exc:
        print(f"legged {args.command}: error: {' '.join(str(exc).split())}", file=sys.stderr)  # one line
        return 2


if __name__ == "__main__":
    sys.exit(main())
