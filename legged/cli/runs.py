"""The command line's commands on run directories: `legged convert-checkpoints` and `legged average`."""

from __future__ import annotations

import argparse
import json


def cmd_convert(args) -> int:
    """`legged convert-checkpoints`: a run's pickled checkpoints as data-only files."""
    from policies.convert import convert_run

    report = convert_run(args.run_dir, args.trust_pickles)
    print(json.dumps(report) if args.json else f"[convert] {len(report['converted'])} checkpoint(s) converted in "
          f"{report['run']}")
    return 0


def cmd_average(args) -> int:
    """`legged average`: a new run whose weights are the mean of checkpoints."""
    from policies.average import average_checkpoints

    report = average_checkpoints(args.source, args.out, args.weights)
    print(json.dumps(report) if args.json else
          f"[average] wrote {report['checkpoint']}: the mean of " +
          ", ".join(f"{s['checkpoint']} (weight {s['weight']:g})" for s in report["sources"]))
    return 0


def _weights(text: str) -> list[float]:
    """Parser of comma-separated checkpoint weights (for argparse `type=`)."""
    try:
        return [float(w) for w in text.split(",") if w]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def add_run_commands(sub) -> None:
    """Register `convert-checkpoints` and `average`."""
    cv = sub.add_parser("convert-checkpoints", help="rewrite a run's old pickled checkpoints as data-only files")
    cv.add_argument("run_dir")
    cv.add_argument("--trust-pickles", action="store_true",
                    help="you trust this run: its pickles may be loaded once to convert them (pickles can run code)")
    cv.add_argument("--json", action="store_true")
    cv.set_defaults(fn=cmd_convert)

    av = sub.add_parser("average", help="a new run whose policy's weights are the mean of several checkpoints of "
                                        "one network (a model soup; rsl-rl runs)")
    av.add_argument("source", nargs="+", help="run directories (their newest checkpoint) or checkpoint files, "
                                              "at least two, of one task, algorithm and environment config")
    av.add_argument("--out", required=True, help="the new run directory")
    av.add_argument("--weights", type=_weights, default=None,
                    help="comma-separated positive weights, one per source (default: equal)")
    av.add_argument("--json", action="store_true", help="one-line JSON")
    av.set_defaults(fn=cmd_average)
