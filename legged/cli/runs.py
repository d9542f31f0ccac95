"""The command line's commands on run directories: `legged convert-checkpoints`, `legged slim`, `legged average`,
`legged curve` and `legged card`."""

from __future__ import annotations

import argparse
import dataclasses
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
                              difficulty=None if args.difficulty is None else (args.difficulty,),
                              opponent=args.opponent, progress=not args.quiet)
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


def cmd_card(args) -> int:
    """`legged card`: the figures of cards written (or checked) from the JSONs beside them; `--summary`: the tables
    of shipped policies in README.md and docs/policies.md from the cards."""
    from policies.card_summary import write_summaries  # the cards' modules load torch: only for this command
    from policies.cards import CardError, run_exists, write_card

    if bool(args.run_dir) == args.summary:
        raise ValueError("name the run directories whose cards to write, or --summary for the tables of shipped "
                         "policies (not both)")
    if args.summary:
        results = write_summaries(".", check=args.check)
        stale = [page for page, current in results.items() if not current]
    else:
        for run_dir in args.run_dir:  # every directory checked before any card is written
            run_exists(run_dir)
        results = {run_dir: write_card(run_dir, check=args.check) for run_dir in args.run_dir}
        stale = [run_dir for run_dir, r in results.items() if not r["up_to_date"]]
    if args.json:
        print(json.dumps({"checked" if args.check else "written": results, "stale": stale}))
    else:
        for name in results:
            state = "stale" if name in stale else "up to date"
            print(f"[card] {name}: {state if args.check else ('rewritten' if name in stale else 'up to date')}")
    if args.check and stale:
        raise CardError(f"{', '.join(stale)}: not as the JSONs have them; run `legged card "
                        f"{'--summary' if args.summary else ' '.join(stale)}`")
    return 0


def cmd_lint_figures(args) -> int:
    """`legged lint-figures`: the figures on the pages that no file they cite holds (exit 1 if any)."""
    from policies.figure_lint import explain, lint  # reads JSON only, but lives with the cards

    if args.explain:
        figures = explain(".", args.page or None)
        for figure, source in figures:
            print(f"{figure.page}:{figure.line}: {figure.text:>9}  <- {source or 'NOTHING'}")
        return 1 if any(source is None for _, source in figures) else 0
    findings = lint(".", args.page or None)
    if args.json:
        print(json.dumps([dataclasses.asdict(f) for f in findings]))
    else:
        for finding in findings:
            print(finding)
        print(f"[lint-figures] {len(findings)} figure(s) no cited file holds")
    return 1 if findings else 0


def _weights(text: str) -> list[float]:
    """Parser of comma-separated checkpoint weights (for argparse `type=`)."""
    try:
        return [float(w) for w in text.split(",") if w]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def add_run_commands(sub) -> None:
    """Register `convert-checkpoints`, `slim`, `average`, `curve` and `card`."""
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
    cu.add_argument("--difficulty", type=bounded(int, 0, 99), default=None,
                    help="confined tasks: the one level whose held-out worlds every checkpoint plays")
    cu.add_argument("--opponent", default=None, metavar="placo|scripted|RUN",
                    help="soccer tasks: who plays the other team (default: the standing script, as `legged eval`)")
    cu.add_argument("--figure", default="tracking_error_mps",
                    help="the evaluation figure plotted (tracking_error_mps, episodes_with_a_fall, episode_return, "
                         "success_rate, goals_for_per_episode, ...)")
    cu.add_argument("--goal", type=float, default=None, help="draw a dashed goal line at this value")
    cu.add_argument("--out", default=None, help="PNG file (default: the first RUN_DIR/curve_<figure>.png)")
    cu.add_argument("--json", action="store_true", help="one-line JSON: the plot and every point")
    cu.add_argument("--quiet", action="store_true", help="no progress bars")
    cu.set_defaults(fn=cmd_curve)

    ca = sub.add_parser("card", help="write the figures of policies' CARD.md from the evaluation JSONs beside them "
                                     "(each checked: written by an evaluation of that checkpoint, unedited)")
    ca.add_argument("run_dir", nargs="*", help="run directories with a CARD.md whose header names its JSONs")
    ca.add_argument("--summary", action="store_true",
                    help="instead, the tables of shipped policies in README.md and docs/policies.md, from the cards")
    ca.add_argument("--check", action="store_true", help="write nothing; exit 2 if a card or table is stale")
    ca.add_argument("--json", action="store_true", help="one-line JSON")
    ca.set_defaults(fn=cmd_card)

    lf = sub.add_parser("lint-figures", help="list the decimal numbers and percentages on README.md, docs/ and the "
                                             "cards that no JSON or run the page cites holds (exit 1 if any)")
    lf.add_argument("page", nargs="*", help="pages to check, relative to the repository (default: all of them)")
    lf.add_argument("--json", action="store_true", help="one JSON list of findings")
    lf.add_argument("--explain", action="store_true", help="every figure with the file and key it matched (or "
                                                           "NOTHING), to tell a figure's source from a coincidence")
    lf.set_defaults(fn=cmd_lint_figures)
