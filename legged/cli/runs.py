"""The command line's commands on run directories: `legged convert-checkpoints`, `legged slim`, `legged average`
and `legged curve`."""

from __future__ import annotations

import argparse
import json

from legged.cli.args import SEED, add_physics_options, bounded


def cmd_convert(args) -> int:
    """`legged convert-checkpoints`: a run's pickled checkpoints as data-only files."""
    from policies.convert import convert_run

    report = convert_run(args.run_dir, args.trust_pickles)
    print(json.dumps(report) if args.json else f"[convert] {len(report['converted'])} checkpoint(s) converted in "
          f"{report['run']}")
    return 0


def cmd_slim(args) -> int:
    """`legged slim`: a finished run's checkpoints with the weights only."""
    from policies.slim import slim_run

    report = slim_run(args.run_dir)
    print(json.dumps(report) if args.json else
          f"[slim] {len(report['slimmed'])} of {report['checkpoints']} checkpoint(s) slimmed in {report['run']}: "
          f"{report['bytes_before'] / 1e6:.1f} MB -> {report['bytes_after'] / 1e6:.1f} MB")
    return 0


def cmd_average(args) -> int:
    """`legged average`: a new run whose weights are the mean of checkpoints."""
    from policies.average import average_checkpoints

    report = average_checkpoints(args.source, args.out, args.weights)
    print(json.dumps(report) if args.json else
          f"[average] wrote {report['checkpoint']}: the mean of " +
          ", ".join(f"{s['checkpoint']} (weight {s['weight']:g})" for s in report["sources"]))
    return 0


def cmd_curve(args) -> int:
    """`legged curve`: runs' checkpoints evaluated on held-out episodes against wall time, a PNG and JSON."""
    from policies.eval_report import EvalRequest
    from policies.learning_curve import learning_curve, plot_curves

    curves = []
    for run_dir in args.run_dir:
        request = EvalRequest(run_dir=run_dir, episodes=args.episodes, seed=args.seed, physics=args.physics,
                              threads=args.threads or None, num_envs=args.num_envs, nominal=args.nominal,
                              progress=not args.quiet)
        curves.append(learning_curve(request, args.every))
    out = args.out or f"{args.run_dir[0].rstrip('/')}/curve_{args.figure}.png"
    path = plot_curves(curves, args.figure, out, args.goal)
    if args.json:
        print(json.dumps({"plot": str(path), "curves": curves}))
    else:
        for curve in curves:
            print(f"[curve] {curve['run']}: " + ", ".join(
                f"{p['wall_s'] / 60:.1f} min {p.get(args.figure)}" for p in curve["points"]))
        print(f"[curve] wrote {path}")
    return 0


def _weights(text: str) -> list[float]:
    """Parser of comma-separated checkpoint weights (for argparse `type=`)."""
    try:
        return [float(w) for w in text.split(",") if w]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def add_run_commands(sub) -> None:
    """Register `convert-checkpoints`, `slim`, `average` and `curve`."""
    cv = sub.add_parser("convert-checkpoints", help="rewrite a run's old pickled checkpoints as data-only files")
    cv.add_argument("run_dir")
    cv.add_argument("--trust-pickles", action="store_true",
                    help="you trust this run: its pickles may be loaded once to convert them (pickles can run code)")
    cv.add_argument("--json", action="store_true")
    cv.set_defaults(fn=cmd_convert)

    sl = sub.add_parser("slim", help="keep only a finished policy's weights in a run's checkpoints (drop the "
                                     "optimiser state and self-play pool: to ship it; it can no longer be resumed)")
    sl.add_argument("run_dir")
    sl.add_argument("--json", action="store_true", help="one-line JSON")
    sl.set_defaults(fn=cmd_slim)

    av = sub.add_parser("average", help="a new run whose policy's weights are the mean of several checkpoints of "
                                        "one network (a model soup; rsl-rl runs)")
    av.add_argument("source", nargs="+", help="run directories (their newest checkpoint) or checkpoint files, "
                                              "at least two, of one task, algorithm and environment config")
    av.add_argument("--out", required=True, help="the new run directory")
    av.add_argument("--weights", type=_weights, default=None,
                    help="comma-separated positive weights, one per source (default: equal)")
    av.add_argument("--json", action="store_true", help="one-line JSON")
    av.set_defaults(fn=cmd_average)

    cu = sub.add_parser("curve", help="a held-out learning curve: every Nth checkpoint of runs evaluated on the same "
                                      "episodes, against minutes from the training process's start (PNG, JSON)")
    cu.add_argument("run_dir", nargs="+", help="one run directory, or several to compare")
    cu.add_argument("--every", type=bounded(int, 1, 10**6), default=1,
                    help="evaluate every Nth checkpoint, counted back from the newest (default: all)")
    cu.add_argument("--episodes", type=bounded(int, 1, 100000), default=50)
    cu.add_argument("--seed", type=SEED, default=12345, help="seed of the evaluation episodes")
    add_physics_options(cu, default="native")
    cu.add_argument("--num-envs", type=bounded(int, 1, 4096), default=None, help="episodes run side by side")
    cu.add_argument("--nominal", action="store_true", help="domain randomisation and observation noise off")
    cu.add_argument("--figure", default="tracking_error_mps",
                    help="the evaluation figure plotted (tracking_error_mps, episodes_with_a_fall, episode_return, ...)")
    cu.add_argument("--goal", type=float, default=None, help="draw a dashed goal line at this value")
    cu.add_argument("--out", default=None, help="PNG file (default: the first RUN_DIR/curve_<figure>.png)")
    cu.add_argument("--json", action="store_true", help="one-line JSON: the plot and every point")
    cu.add_argument("--quiet", action="store_true", help="no progress bars")
    cu.set_defaults(fn=cmd_curve)
