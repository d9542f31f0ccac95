"""The command line's benchmarks: `legged bench env|train|physics|settings|soak|soccer|encoder|update` (and `bench
plan` and `bench navigate`, from legged.cli.nav)."""

from __future__ import annotations

import sys

from legged.cli.args import SEED, THREADS, bounded, choices, ints, task_names
from legged.cli.nav import _print_records, add_bench_plan


def _each_line(line):
    """A benchmark's table that prints `line(record)` for each record (for `_print_records`)."""
    return lambda records: print("\n".join(line(r) for r in records))


def cmd_bench(args) -> int:
    """`legged bench env`: environment steps per second, as JSON or a table."""
    from legged.bench import attach_peer, bench_env, bench_peer, peer_env, print_table
    from legged.tasks import default_config

    for task in args.task:
        default_config(task)  # unknown task -> clear error before any compilation
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = [r for task in args.task for r in bench_env(task, args.batch, args.seconds, physics=args.physics,
                                                            threads=args.threads or None, progress=progress,
                                                            randomize=tuple(args.randomize))]
    if args.peer_python:
        if progress:
            progress("running the Playground peer in the same run")
        attach_peer(records, bench_peer(args.peer_python, args.peer_script, args.batch, args.seconds,
                                        tuple(peer_env(task) for task in args.task)))
    return _print_records(records, args.json, print_table)


def cmd_bench_soak(args) -> int:
    """`legged bench soak`: random and extreme actions; non-finite values and divergences."""
    from legged.bench import soak

    progress = None if args.quiet else (lambda msg: print(f"[soak] {msg}", file=sys.stderr, flush=True))
    records = [soak(task, args.steps, args.batch, args.seed, args.physics, args.threads or None, progress)
               for task in args.tasks]
    return _print_records(records, args.json, _each_line(
        lambda r: f"{r['task']:20s} {r['env_steps']:>10,} steps  non-finite values {r['non_finite_values']}  "
                  f"episodes {r['episodes']}  diverged {r['diverged_episodes']}  {r['env_steps_per_s']:.0f} steps/s"))


def cmd_bench_encoder(args) -> int:
    """`legged bench encoder`: a history encoder's forward and backward seconds."""
    import torch

    from policies.bench_encoder import bench_encoders

    if args.threads:
        torch.set_num_threads(args.threads)
    records = bench_encoders(args.steps, args.batch)
    return _print_records(records, args.json, _each_line(
        lambda r: f"H={r['history_steps']:4d}  encoder {r['encoder_s']:.3f} s  conv1d {r['conv1d_s']:.3f} s "
                  f"({r['conv1d_over_unfold']:.2f}x)  head {r['head_s']:.3f} s  "
                  f"encoder/head {r['encoder_over_head']:.1f}x"))


def cmd_bench_update(args) -> int:
    """`legged bench update`: a PPO update's seconds under each option torch offers, side by side."""
    import torch

    from policies.bench_update import bench_update

    if args.threads:
        torch.set_num_threads(args.threads)
    records = [bench_update(inputs, tuple(hidden), batch=args.batch, epochs=args.epochs, mini_batches=args.mini_batches,
                            rounds=args.rounds, variants=tuple(args.variants))
               for inputs in args.inputs for hidden in (args.hidden or [[512, 256, 128]])]
    return _print_records(records, args.json, _each_line(
        lambda r: f"inputs {r['inputs']:5d} hidden {r['hidden']}: " + "  ".join(
            f"{v} {x['update_s']:.2f} s ({x['speed_vs_plain']:.2f}x)" for v, x in r["variants"].items())))


def cmd_bench_train(args) -> int:
    """`legged bench train`: PPO iterations of each task timed part by part, beside bare physics."""
    from legged.tasks import default_config
    from policies.bench_train import bench_train_median, print_train_table

    for task in args.task:
        default_config(task)  # unknown task -> clear error before any compilation
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = [bench_train_median(task, args.repeats, iterations=args.iterations, num_envs=args.num_envs,
                                  threads=args.threads, physics=args.physics, overrides=tuple(args.set),
                                  seed=args.seed, warmup=args.warmup, rollout_seconds=args.rollout_seconds,
                                  progress=progress)
               for task in args.task]
    return _print_records(records, args.json, print_train_table)


def cmd_bench_physics(args) -> int:
    """`legged bench physics`: the cost of each physics setting of a task's model, side by side."""
    from legged.physics_cost import bench_physics, print_cost_table, variants_named

    variants = variants_named(args.variants)  # unknown names -> one clear line before anything is built
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = bench_physics(args.task, variants, progress, batch=args.batch, threads=args.threads,
                            seconds=args.seconds, repeats=args.repeats, seed=args.seed)
    return _print_records(records, args.json, print_cost_table)


def cmd_bench_settings(args) -> int:
    """`legged bench settings`: the cost of each setting of tasks' configs under their randomisation, side by side."""
    from legged.setting_cost import changes_named, print_setting_table, setting_cost

    changes = changes_named(args.changes)  # unknown names -> one clear line before anything is built
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = setting_cost(args.task, changes, batch=args.batch, threads=args.threads, seconds=args.seconds,
                           repeats=args.repeats, seed=args.seed, progress=progress)
    return _print_records(records, args.json, print_setting_table)


def _side_by_side_parser(bsub, name: str, fn, batch: int, what: str, help: str, names: str) -> None:
    """`bench physics` and `bench settings`: tasks, the variants or changes to time (`--variants`, `--changes`), and
    how they are timed side by side."""
    parser = bsub.add_parser(name, help=help)
    parser.add_argument("task", type=task_names, help="comma-separated tasks")
    parser.add_argument(f"--{what}s", type=lambda s: [v for v in s.split(",") if v], default=None,
                        help=f"comma-separated {what}s (default: all that apply; as-trained always measured): {names}")
    parser.add_argument("--batch", type=bounded(int, 1, 65536), default=batch, help="simulations stepped together")
    parser.add_argument("--threads", type=bounded(int, 1, 1024), default=2, help="threads of the C engine")
    parser.add_argument("--seconds", type=bounded(float, 0.1, 3600.0), default=5.0,
                        help=f"timed seconds per {what} and round")
    parser.add_argument("--repeats", type=bounded(int, 1, 100), default=3,
                        help=f"rounds, every {what} interleaved in each; each figure is the median round's")
    parser.add_argument("--seed", type=SEED, default=0)
    parser.add_argument("--json", action="store_true", help=f"print a JSON list, one object per task and {what}")
    parser.add_argument("--quiet", action="store_true", help="no progress messages")
    parser.set_defaults(fn=fn)


def cmd_bench_soccer(args) -> int:
    """`legged bench soccer`: soccer env steps per second beside the peers."""
    from legged.soccer.bench import bench_soccer, print_soccer_table

    if not set(args.team_sizes) <= {1, 2}:
        raise ValueError(f"--team-sizes takes 1 and/or 2 (1v1, 2v2), got {args.team_sizes}")
    cameras = {"off": (False,), "on": (True,), "both": (False, True)}[args.camera]
    progress = None if args.quiet else (lambda msg: print(f"[bench] {msg}", file=sys.stderr, flush=True))
    records = bench_soccer(args.team_sizes, cameras, args.batch, args.seconds, peer=not args.no_peer,
                           peer_steps=args.peer_steps, physics=args.physics, threads=args.threads or None,
                           progress=progress, casters=args.caster)
    return _print_records(records, args.json, print_soccer_table)


def add_bench_commands(sub) -> None:
    """Register `bench` and its benchmarks."""
    b = sub.add_parser("bench", help="benchmarks")
    bsub = b.add_subparsers(dest="what", required=True)
    add_bench_plan(bsub)
    be = bsub.add_parser("env", help="environment steps per second on MJX and native MuJoCo, beside bare physics")
    be.add_argument("--task", type=task_names, default=["confined-waypoints"],
                    help="comma-separated tasks, measured one after the other in this run")
    be.add_argument("--batch", type=ints(1, 65536), default=[1, 64, 256], help="comma-separated batch sizes")
    be.add_argument("--physics", type=choices("mjx", "native", "rollout", "mjx-stock"),
                    default=["mjx", "native", "rollout"],
                    help="comma-separated: mjx, native (the task on each engine), rollout (bare native physics), "
                         "mjx-stock (MJX with its own sphere-height-field collision, which the project replaces)")
    be.add_argument("--threads", type=THREADS, default=0, metavar="N",
                    help="threads of native physics (default: every core)")
    be.add_argument("--seconds", type=bounded(float, 0.0, 3600.0), default=3.0, help="timed seconds per batch size")
    be.add_argument("--randomize", type=choices("default", "on", "off"), default=["default"],
                    help="comma-separated: the task's default domain randomisation, or it on or off (on,off measures "
                         "its cost: ratio_vs_off)")
    be.add_argument("--peer-python", default=None,
                    help="python of MuJoCo Playground's peer venv (bash legged/peers/setup_playground.sh builds it); "
                         "adds ratio_vs_peer beside Playground's Go1 joystick, flat for go1-flat, rough otherwise")
    be.add_argument("--peer-script", default=None,
                    help="the peer's benchmark script (default: legged/peers/playground.py of this install)")
    be.add_argument("--json", action="store_true", help="print a JSON list, one object per batch size")
    be.add_argument("--quiet", action="store_true", help="no progress messages")
    be.set_defaults(fn=cmd_bench)
    bt = bsub.add_parser("train", help="a task's PPO iterations timed part by part (physics, transition, inference, "
                                       "update, saving) beside bare physics in the same run")
    bt.add_argument("task", type=task_names, help="comma-separated tasks, measured one after the other")
    bt.add_argument("--iterations", type=bounded(int, 2, 100000), default=12,
                    help="PPO iterations per run, the warm-up ones included")
    bt.add_argument("--warmup", type=bounded(int, 1, 1000), default=2,
                    help="first iterations left out of the figures (they compile the environment)")
    bt.add_argument("--num-envs", type=bounded(int, 1, 65536), default=1024)
    bt.add_argument("--threads", type=bounded(int, 1, 1024), default=2, help="threads of physics and torch")
    bt.add_argument("--physics", choices=["native", "mjx"], default="native")
    bt.add_argument("--repeats", type=bounded(int, 1, 100), default=1,
                    help="runs per task; the record is the median run's, every run's speeds beside it")
    bt.add_argument("--rollout-seconds", type=bounded(float, 1.0, 3600.0), default=30.0,
                    help="timed seconds of bare physics (native)")
    bt.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="config override of the timed runs, as `legged train --set`")
    bt.add_argument("--seed", type=SEED, default=0)
    bt.add_argument("--json", action="store_true", help="print a JSON list, one object per task")
    bt.add_argument("--quiet", action="store_true", help="no progress messages")
    bt.set_defaults(fn=cmd_bench_train)
    _side_by_side_parser(bsub, "physics", cmd_bench_physics, batch=1024, what="variant",
                         help="what each physics setting costs: a task's model as it trains and with one setting "
                              "changed at a time (solver, iterations, cone, condim, ...)",
                         names=("as-trained, cg, pgs, iterations-1, other-cone, condim-3, no-frictionloss, "
                                "no-eulerdamp, sparse-jacobian, other-ccd, ccd-loose, no-ceiling-pairs, "
                                "no-trunk-pairs"))
    _side_by_side_parser(bsub, "settings", cmd_bench_settings, batch=256, what="change",
                         help="what each setting of a task's config costs its physics under its randomisation (cone "
                              "draws, feet condim, margin, softness, level worlds), side by side, with the ratio to "
                              "go1-flat where it runs too",
                         names=("as-trained, no-cone-draws, feet-condim-3, no-margin, model-softness, "
                                "no-randomisation, tunnels, heights-10cm"))
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
    bs.add_argument("--peer-steps", type=bounded(int, 1, 100000), default=20,
                    help="control steps timed per dm_control env")
    bs.add_argument("--physics", type=choices("mjx", "native"), default=["mjx", "native"],
                    help="comma-separated physics engines to measure")
    bs.add_argument("--threads", type=THREADS, default=0, metavar="N",
                    help="threads of native physics (default: every core)")
    bs.add_argument("--caster", type=choices("c", "c-unculled", "jax"), default=["c"],
                    help="comma-separated ray casters of the cameras under native physics: MuJoCo's C one, the "
                         "same without culling geoms outside each view, JAX's")
    bs.add_argument("--json", action="store_true", help="print a JSON list, one object per measurement")
    bs.add_argument("--quiet", action="store_true", help="no progress messages")
    bs.set_defaults(fn=cmd_bench_soccer)
    bn = bsub.add_parser("encoder", help="a PPO mini-batch's history encoder: forward + backward seconds beside the "
                                         "conv1d layout and the actor's head")
    bn.add_argument("--steps", type=ints(1, 1000), default=[20, 25, 50], help="comma-separated history lengths")
    bn.add_argument("--batch", type=bounded(int, 1, 10**6), default=6144, help="mini-batch size")
    bn.add_argument("--threads", type=THREADS, default=0, metavar="N", help="torch threads (default: torch's)")
    bn.add_argument("--json", action="store_true", help="print a JSON list, one object per history length")
    bn.set_defaults(fn=cmd_bench_encoder)
    bu = bsub.add_parser("update", help="one PPO update's seconds with each option torch offers a CPU (fused or "
                                        "multi-tensor Adam, torch.compile, one thread), side by side")
    bu.add_argument("--inputs", type=ints(1, 100000), default=[902], help="comma-separated observation sizes")
    bu.add_argument("--hidden", type=ints(1, 100000), action="append", default=None,
                    help="comma-separated hidden sizes of actor and critic (repeatable; default 512,256,128)")
    bu.add_argument("--batch", type=bounded(int, 1, 10**7), default=24576, help="steps of one iteration's rollout")
    bu.add_argument("--epochs", type=bounded(int, 1, 100), default=5)
    bu.add_argument("--mini-batches", type=bounded(int, 1, 1024), default=4)
    bu.add_argument("--rounds", type=bounded(int, 1, 100), default=5, help="timed updates per variant, interleaved")
    bu.add_argument("--variants", type=lambda s: [v for v in s.split(",") if v],
                    default=["plain", "foreach-adam", "fused-adam", "compiled", "one-thread"],
                    help="comma-separated: plain, foreach-adam, fused-adam, compiled, one-thread")
    bu.add_argument("--threads", type=THREADS, default=0, metavar="N", help="torch threads (default: torch's)")
    bu.add_argument("--json", action="store_true", help="print a JSON list, one object per size")
    bu.set_defaults(fn=cmd_bench_update)
