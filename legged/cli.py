"""The `legged` command line: worlds, benchmarks and the demo (training, planning and viewing come next)."""

from __future__ import annotations

import argparse
import json
import sys


def _int_list(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"batch sizes must be positive integers, got {text!r}")
    return values


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


def cmd_bench(args) -> int:
    from legged.bench import attach_peer, bench_env, bench_peer, print_table
    from legged.envs import default_config

    default_config(args.task)  # unknown task -> clear error before any compilation
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = bench_env(args.task, args.batch, args.seconds, progress=progress)
    if args.peer_python:
        if progress:
            progress("running the Playground peer in the same run")
        attach_peer(records, bench_peer(args.peer_python, args.peer_script, args.batch, args.seconds))
    if args.json:
        print(json.dumps(records))
    else:
        print_table(records)
    return 0


def cmd_tasks(args) -> int:
    from legged.envs import TASKS

    for name in sorted(TASKS):
        print(name)
    return 0


def cmd_demo(args) -> int:
    from legged.demo import run_demo

    return run_demo(args.out, args.seconds, args.seed, args.difficulty)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="legged", description="Legged-robot RL in MuJoCo/MJX.")
    sub = p.add_subparsers(dest="command", required=True)

    w = sub.add_parser("world", help="generate a confined world (world.npz + world.xml)")
    w.add_argument("--seed", type=int, default=0)
    w.add_argument("--difficulty", type=int, default=0, help="0/1/2 give 3/4/5 m tunnels; higher is longer")
    w.add_argument("--out", required=True, help="output directory")
    w.add_argument("--json", action="store_true", help="print a JSON summary")
    w.set_defaults(fn=cmd_world)

    b = sub.add_parser("bench", help="benchmarks")
    bsub = b.add_subparsers(dest="what", required=True)
    be = bsub.add_parser("env", help="environment steps per second (MJX) beside native MuJoCo")
    be.add_argument("--task", default="confined-waypoints")
    be.add_argument("--batch", type=_int_list, default=[1, 64, 256], help="comma-separated batch sizes")
    be.add_argument("--seconds", type=float, default=3.0, help="timed seconds per batch size")
    be.add_argument("--peer-python", default=None,
                    help="python of the MuJoCo Playground peer (../shared/peers); adds ratio_vs_peer")
    be.add_argument("--peer-script", default="../shared/peers/bench_playground.py")
    be.add_argument("--json", action="store_true", help="print a JSON list, one object per batch size")
    be.add_argument("--quiet", action="store_true", help="no progress messages")
    be.set_defaults(fn=cmd_bench)

    t = sub.add_parser("tasks", help="list the registered tasks")
    t.set_defaults(fn=cmd_tasks)

    d = sub.add_parser("demo", help="generate a world and run Go1 in it (MJX and native MuJoCo)")
    d.add_argument("--out", default="legged-demo", help="where to write the world files")
    d.add_argument("--seconds", type=float, default=4.0, help="simulated seconds")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--difficulty", type=int, default=1)
    d.set_defaults(fn=cmd_demo)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from legged.envs.registry import UnknownTaskError
    from legged.worlds import WorldError

    try:
        return args.fn(args)
    except (UnknownTaskError, WorldError, OSError, ValueError) as exc:
        print(f"legged {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
