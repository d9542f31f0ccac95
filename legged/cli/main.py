"""The `legged` command's parser and dispatch, and the commands without another group: train, distill, eval,
plot, table, export, camera, tasks and view."""

from __future__ import annotations

import argparse
import json
import sys

from legged.cli.args import (SEED, Parser, add_physics_options, add_robot_option, add_server_options, bounded,
                             ints, join_negative_coordinates)
from legged.cli.bench import add_bench_commands
from legged.cli.demo import add_demo_command
from legged.cli.nav import add_navigation_commands
from legged.cli.runs import add_run_commands
from legged.cli.soccer import add_soccer_commands

DEFAULT_TIMESTEPS = 1_000_000  # `legged train`'s budget when --timesteps is not given


def cmd_train(args) -> int:
    """`legged train`: start a run, or continue one with --resume."""
    from policies.training import resume_run, start_run

    if args.resume:
        given = ["the task"] * bool(args.task) + [f"--{dest.replace('_', '-')}" for dest, default
                                                  in args.fixed_by_resume.items() if getattr(args, dest) != default]
        if given:
            raise ValueError(f"--resume DIR continues a run with its own config (DIR/config.yaml): drop "
                             f"{', '.join(given)}; only --timesteps (a new total) and --threads apply")
        record = resume_run(args.resume, progress=not args.quiet, timesteps=args.timesteps, threads=args.threads)
    else:
        if not args.task:
            raise ValueError("name a task (see `legged tasks`) or continue a run with --resume DIR")
        record = start_run(args.task, args.run_dir, backend=args.backend, num_envs=args.num_envs,
                           timesteps=args.timesteps or DEFAULT_TIMESTEPS, seed=args.seed, overrides=args.set,
                           progress=not args.quiet,
                           physics=args.physics, threads=args.threads, init_from=args.init_from or "",
                           algo=args.algo)
    print(json.dumps(record))
    return 0


def cmd_distill(args) -> int:
    """`legged distill`: distil a teacher run into a student run."""
    from policies.distill import start_distill

    record = start_distill(args.teacher_run, args.method, args.run_dir, timesteps=args.timesteps,
                           physics=args.physics, overrides=args.set, progress=not args.quiet,
                           num_envs=args.num_envs, threads=args.threads or None, task=args.task)
    print(json.dumps(record))
    return 0


def cmd_eval(args) -> int:
    """`legged eval`: the run's policy on held-out worlds (policies.eval_report), printed as JSON."""
    from policies.eval_report import evaluation_report

    report = evaluation_report(eval_request(args))
    print(json.dumps(report) if args.json else json.dumps(report, indent=2))
    return 0


def eval_request(args):
    """`legged eval`'s options as a policies.eval_report.EvalRequest."""
    from policies.eval_report import EvalRequest

    return EvalRequest(run_dir=args.run_dir, checkpoint=args.checkpoint, episodes=args.episodes, seed=args.seed,
                       physics=args.physics, threads=args.threads or None, num_envs=args.num_envs,
                       difficulty=None if args.difficulty is None else tuple(args.difficulty),
                       world_seed=args.world_seed, opponent=args.opponent, teammate=args.teammate, ood=args.ood,
                       nominal=args.nominal, oracle=tuple(args.oracle), pilot=args.pilot, tracker=args.tracker,
                       compare_teacher=args.compare_teacher, compare_pilot=args.compare_pilot,
                       env_set=tuple(args.set), robot=args.robot,
                       compare_robots=tuple(args.compare_robots or ()), progress=not args.quiet)


def cmd_plot(args) -> int:
    """`legged plot`: a metric of runs into a PNG."""
    from policies.plots import plot_runs

    path = plot_runs(args.run_dir, args.y, args.x, args.out, args.hline)
    print(json.dumps({"plot": str(path)}) if args.json else f"[plot] wrote {path}")
    return 0


def cmd_table(args) -> int:
    """`legged table`: runs' saved evaluations as a markdown table."""
    from policies.tables import eval_table

    print(eval_table(args.run_dir, args.files, args.metrics))
    return 0


def cmd_export(args) -> int:
    """`legged export`: the run's policy as ONNX (policies.export), checked; the check printed as JSON."""
    from policies.export import export_run

    if not args.onnx:
        raise ValueError("choose a format: --onnx")
    print(json.dumps(export_run(args.run_dir, args.checkpoint, args.out)))
    return 0


def cmd_camera(args) -> int:
    """`legged camera`: each soccer player's head camera, the ray caster beside MuJoCo's renderer."""
    from legged.soccer.states import game_start
    from legged.soccer.vision.cameras import write_camera_images
    from legged.tasks import TASKS, make, task_entry

    if task_entry(args.task).kind != "soccer":  # unknown names fail here too
        soccer = sorted(n for n, e in TASKS.items() if e.kind == "soccer")
        raise ValueError(f"{args.task!r} is not a soccer task; soccer tasks: {', '.join(soccer)}")
    if args.robot != "project":
        from legged.robots.models import checked_model

        checked_model(task_entry(args.task).robot, args.robot, task_entry(args.task).config.ctrl_dt)
    env = make(args.task, robot_model=args.robot)
    report = write_camera_images(env.mj_model, game_start(env, args.seed), args.out, env.config.camera, env.layout)
    report = dict(report, task=args.task, seed=args.seed, robot=args.robot)
    if args.json:
        print(json.dumps(report))
    else:
        print(f"[camera] {args.task} seed {args.seed} robot {args.robot}: segmentation agreement of the "
              f"{report['caster'].upper()} ray caster with MuJoCo's renderer {report['segmentation']:.4f}, median "
              f"depth error {report['depth_median_abs_error']:.2e} m; wrote {len(report['files']['ray'])} agent(s) "
              f"x 2 images to {args.out}")
    return 0


def cmd_tasks(args) -> int:
    """`legged tasks`: the registered tasks."""
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


def cmd_view(args) -> int:
    """`legged view`: the browser dashboard, or with --save a recorded rollout."""
    from web.app import Dashboard, DashboardConfig
    from web.source import ViewRequest, resolve

    request = ViewRequest(run_dir=args.run_dir, task=args.task, checkpoint=args.checkpoint, trajectory=args.trajectory,
                          num_envs=args.num_envs, physics=args.physics, seed=args.seed, steps=args.steps,
                          host=args.host, port=None if args.save else args.port, opponent=args.opponent,
                          drill=args.drill, robot=args.robot)
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


def build_parser() -> argparse.ArgumentParser:
    """The `legged` parser: every command, each with its function as `fn`."""
    p = Parser(prog="legged", description="Legged-robot RL in MuJoCo/MJX.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    add_navigation_commands(sub)
    add_soccer_commands(sub)
    add_run_commands(sub)
    add_bench_commands(sub)
    tr = sub.add_parser("train", help="train a policy (Brax PPO or rsl-rl PPO) into a run directory")
    tr.add_argument("task", nargs="?", help="task name (legged tasks)")
    tr.add_argument("--backend", choices=["rsl", "brax"], default="rsl")
    tr.add_argument("--num-envs", type=bounded(int, 1, 2**20), default=None,
                    help="parallel environments (default: the task's recipe, else 256)")
    tr.add_argument("--timesteps", type=bounded(int, 1, 10**12), default=None,
                    help=f"environment steps, all envs together (default {DEFAULT_TIMESTEPS:,}; with --resume: a new "
                         f"total, to train a finished run further)")
    tr.add_argument("--seed", type=SEED, default=0)
    add_physics_options(tr)
    tr.add_argument("--run-dir", default=None, help="where the run is written (default runs/<task>-<time>)")
    tr.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="override any config field, e.g. ppo.learning_rate=3e-4, env.episode_seconds=10, "
                         "checkpoint_every=5, device=cuda (repeatable; see config.yaml of a run for all fields)")
    tr.add_argument("--resume", default=None, metavar="DIR", help="continue the run in DIR from its last checkpoint")
    tr.add_argument("--init-from", default=None, metavar="RUN",
                    help="warm start from RUN's networks (rsl; e.g. the go1-flat walker for a confined follower); from a "
                         "run of the same task, also its optimiser and curriculum levels (a fine-tune)")
    tr.add_argument("--algo", choices=["ppo", "teacher", "hib", "hib-no-ib", "history"], default="ppo",
                    help="ppo; teacher (privileged encoder, for `legged distill`); hib, hib-no-ib, history "
                         "(one-stage students on the state history)")
    tr.add_argument("--quiet", action="store_true", help="no progress bar")
    fixed = ("backend", "num_envs", "seed", "physics", "run_dir", "set", "init_from", "algo")
    tr.set_defaults(fn=cmd_train, fixed_by_resume={dest: tr.get_default(dest) for dest in fixed})

    ds = sub.add_parser("distill", help="distil a teacher into a deployable student: a privileged teacher (--algo "
                                        "teacher) into a history student, a state soccer player into a vision one")
    ds.add_argument("teacher_run", help="the teacher's run directory")
    ds.add_argument("--method", required=True, help="dagger, rma (privileged teachers) or kl (vision students)")
    ds.add_argument("--task", default=None, help="the student's task (default: the teacher's; a state soccer "
                                                 "player's vision student: soccer-1v1-vision)")
    ds.add_argument("--run-dir", default=None, help="where the student's run is written")
    ds.add_argument("--timesteps", type=bounded(int, 1, 10**12), default=None,
                    help="environment steps (default: the teacher's)")
    ds.add_argument("--num-envs", type=bounded(int, 1, 2**20), default=None, help="default: the teacher's")
    add_physics_options(ds, default=None)
    ds.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="override a config field, e.g. distill.learning_rate=5e-4, latent.history_steps=30")
    ds.add_argument("--quiet", action="store_true", help="no progress bar")
    ds.set_defaults(fn=cmd_distill)

    ev = sub.add_parser("eval", help="evaluate a run's policy on held-out worlds (MJX or native MuJoCo)")
    ev.add_argument("run_dir")
    ev.add_argument("--checkpoint", default=None, help="a checkpoint file (default: the run's newest)")
    ev.add_argument("--episodes", type=bounded(int, 1, 100000), default=32)
    ev.add_argument("--seed", type=SEED, default=12345, help="seed of the evaluation episodes")
    add_physics_options(ev)
    ev.add_argument("--num-envs", type=bounded(int, 1, 4096), default=None,
                    help="episodes run side by side (default 16; confined tasks: all, up to 64)")
    ev.add_argument("--difficulty", type=ints(0, 20), default=None,
                    help="confined tasks: comma-separated difficulty levels, --episodes held-out worlds each "
                         "(default: the levels the run trained on)")
    ev.add_argument("--world-seed", type=SEED, default=None,
                    help="confined tasks: seed of the evaluation worlds (default: the training seed + 1000003, "
                         "worlds never trained on)")
    ev.add_argument("--opponent", default=None, metavar="placo|scripted|RUN",
                    help="soccer tasks: who plays the other team (default: the standing script)")
    ev.add_argument("--teammate", default=None, metavar="self|placo|scripted|RUN",
                    help="2v2: who plays the learner's teammate (default: self, the evaluated policy)")
    ev.add_argument("--ood", action="store_true",
                    help="out of the training distribution: friction 0.1-0.25, +4 kg payload, motor strength "
                         "0.7-0.8, pushes 1.5x stronger (Go1 tasks)")
    ev.add_argument("--nominal", action="store_true",
                    help="each robot model as it is: the run's domain randomisation and observation noise off")
    ev.add_argument("--set", action="append", default=[], metavar="env.PATH=VALUE",
                    help="change the evaluated environment (repeatable), as `legged train --set` takes it: "
                         "env.randomization.elliptic_share=null evaluates without the friction-cone draws")
    ev.add_argument("--oracle", type=lambda v: [p for p in v.split(",") if p], default=[], metavar="ball,own_goal,...",
                    help="diagnostics: a vision player that estimates the game steers by the truth for these parts")
    ev.add_argument("--pilot", default=None, metavar="teacher|RUN|none",
                    help="a vision player that estimates the game is steered by a state player (its distillation "
                         "teacher, or a soccer run) from its estimate; none: by its own corrections (default: the "
                         "run's soccer.pilot)")
    ev.add_argument("--tracker", action="store_true",
                    help="a vision player that estimates the game steers by its tracker's goals and ball where it "
                         "knows them (env.vision_tracker, legged.soccer.vision.tracker)")
    ev.add_argument("--compare-teacher", action="store_true",
                    help="a distilled soccer student: also play its teacher in the same games and report the "
                         "student's goals over the teacher's, with a 95%% bootstrap interval over the games")
    ev.add_argument("--compare-pilot", action="store_true",
                    help="a piloted vision student: also play its pilot at the truth in the same games and report "
                         "the student's goals over the pilot's (as --compare-teacher)")
    add_robot_option(ev)
    ev.add_argument("--compare-robots", type=lambda v: [p for p in v.split(",") if p], default=None,
                    metavar="project,menagerie,...",
                    help="the same episodes on each robot model, with each figure's ratio to the first model's")
    ev.add_argument("--json", action="store_true", help="one-line JSON")
    ev.add_argument("--quiet", action="store_true", help="no progress bar")
    ev.set_defaults(fn=cmd_eval)

    pt = sub.add_parser("plot", help="plot a metric of runs' metrics.jsonl into a PNG (one line per run)")
    pt.add_argument("run_dir", nargs="+", help="one run directory, or several to compare")
    pt.add_argument("--y", default="episode_return", help="metric to plot (a numeric field of metrics.jsonl)")
    pt.add_argument("--x", default="step", choices=["step", "wall_s", "iteration"], help="horizontal axis")
    pt.add_argument("--hline", type=float, default=None, help="draw a dashed horizontal line (a goal) here")
    pt.add_argument("--out", default=None, help="PNG file (default: the first RUN_DIR/<metric>.png)")
    pt.add_argument("--json", action="store_true")
    pt.set_defaults(fn=cmd_plot)

    tb = sub.add_parser("table", help="runs' saved evaluations side by side, as a markdown table")
    tb.add_argument("run_dir", nargs="+", help="run directories, one row each")
    tb.add_argument("--files", type=lambda s: [f for f in s.split(",") if f], default=["eval_native.json"],
                    help="comma-separated evaluation JSON files in each run (e.g. "
                         "eval_native.json,eval_ood_native.json)")
    tb.add_argument("--metrics", type=lambda s: [m for m in s.split(",") if m],
                    default=["episode_return", "tracking_error_mps", "episodes_with_a_fall"],
                    help="comma-separated report fields")
    tb.set_defaults(fn=cmd_table)

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
    c.add_argument("--robot", default="project", metavar="MODEL",
                   help="the OP3 model: project, menagerie or PATH.xml (its meshes cast by MuJoCo's C ray caster)")
    c.add_argument("--json", action="store_true", help="print the agreement figures as JSON")
    c.set_defaults(fn=cmd_camera)

    t = sub.add_parser("tasks", help="list the registered tasks: kind, robot, physics engines, trainers")
    t.add_argument("--json", action="store_true", help="one JSON list")
    t.set_defaults(fn=cmd_tasks)

    add_demo_command(sub)

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
    v.add_argument("--steps", type=bounded(int, 1, 100000), default=500,
                   help="control steps per rollout (50 per second)")
    v.add_argument("--opponent", default=None, metavar="placo|scripted|RUN",
                   help="soccer: what drives the other robots (default: the standing script)")
    v.add_argument("--drill", default=None, metavar="walk|empty-goal|getup",
                   help="soccer: a drill (as `legged drill`) played by the run's policy, or without a run by placo")
    add_robot_option(v)
    v.add_argument("--save", default=None, metavar="FILE.npz",
                   help="record one rollout into FILE.npz and exit instead of serving")
    add_server_options(v)
    v.set_defaults(fn=cmd_view)
    return p


def main(argv=None) -> int:
    """Run the `legged` command with `argv` (default: sys.argv[1:]); returns the exit code (2: bad input, with
    one line on stderr)."""
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


if __name__ == "__main__":  # python -m legged.cli.main, as python -m legged.cli
    sys.exit(main())
