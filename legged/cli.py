"""The `legged` command line: worlds, planning, benchmarks and the demo."""

from __future__ import annotations

import argparse
import json
import sys

from legged.cli_bench import add_bench_commands
from legged.cli_nav import add_navigation_commands
from legged.cli_runs import add_run_commands
from legged.cli_soccer import add_soccer_commands
from legged.cli_args import (SEED, Parser, add_physics_options, add_robot_option, bounded, choices, ints,
                             join_negative_coordinates)


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
                           physics=args.physics, threads=args.threads, init_from=args.init_from or "",
                           algo=args.algo)
    print(json.dumps(record))
    return 0


def cmd_distill(args) -> int:
    from policies.distill import start_distill

    record = start_distill(args.teacher_run, args.method, args.run_dir, timesteps=args.timesteps,
                           physics=args.physics, overrides=args.set, progress=not args.quiet,
                           num_envs=args.num_envs, threads=args.threads or None, task=args.task)
    print(json.dumps(record))
    return 0


def cmd_eval(args) -> int:
    import dataclasses

    from legged.tasks import task_entry
    from policies.evaluate import ood_config, on_robot, robot_ratios
    from policies.policy_io import load_policy
    from policies.run_dir import RunDir

    config = RunDir(args.run_dir).load_config()
    confined = task_entry(config.task).kind == "confined"
    if not confined and (args.difficulty is not None or args.world_seed is not None):
        raise ValueError(f"--difficulty and --world-seed apply to confined tasks; {config.task} has no worlds")
    if args.ood:
        ood_config(config.env)  # fails now for tasks without dynamics randomisation
        if args.nominal:
            raise ValueError("--ood draws dynamics out of the training distribution; --nominal draws none: choose one")
    soccer = task_entry(config.task).kind == "soccer"
    if (args.opponent or args.teammate) and not soccer:
        raise ValueError(f"--opponent (or --teammate) applies to soccer tasks; {config.task} has no opponents")
    if (args.pilot or args.oracle or args.tracker) and not soccer:
        raise ValueError(f"--pilot, --oracle and --tracker apply to soccer vision students; {config.task} is not "
                         f"soccer")
    if args.pilot == "teacher" and not config.distill.teacher:
        raise ValueError(f"--pilot teacher: {args.run_dir} was not distilled from a teacher; name a soccer run")
    if args.compare_teacher and (not soccer or config.drill or not config.distill.teacher):
        raise ValueError(f"--compare-teacher plays a distilled soccer student's teacher in the same games; "
                         f"{args.run_dir} is not a soccer student distilled from a teacher (task {config.task}"
                         f"{', drill ' + config.drill if config.drill else ''})")
    if args.compare_pilot and (not soccer or config.drill or not (args.pilot or config.pilot) or args.pilot == "none"):
        raise ValueError(f"--compare-pilot plays a piloted vision student's pilot, at the truth, in the same games; "
                         f"{args.run_dir} has no pilot (give one with --pilot RUN)")
    if config.drill and (args.opponent or args.teammate):
        raise ValueError(f"{args.run_dir} trained on the {config.drill} drill, where nobody else plays: its eval "
                         f"plays the drill, without --opponent or --teammate (or use `legged drill {config.drill} "
                         f"--player {args.run_dir}`)")
    if (args.compare_teacher or args.compare_pilot) and (args.compare_robots or args.robot != "project"):
        raise ValueError("--compare-teacher and --compare-pilot play on the project's robot model; run them without "
                         "--robot and --compare-robots")
    if args.compare_robots and (args.robot != "project" or len(set(args.compare_robots)) < len(args.compare_robots)):
        raise ValueError("--compare-robots names each model once, and replaces --robot")
    robots = args.compare_robots or [args.robot]
    for robot in robots:  # a model that cannot be used fails here, before a policy is loaded or a scene compiled
        on_robot(config, robot, args.physics)
    policy, config = load_policy(args.run_dir, args.checkpoint)
    if args.pilot:  # replaces the run's own pilot (none: the student's own corrections)
        pilot = {"teacher": config.distill.teacher, "none": ""}.get(args.pilot, args.pilot)
        config = dataclasses.replace(config, pilot=pilot).resolved()
    configs = {r: on_robot(config, r) for r in robots}
    report = dict(physics=args.physics, seed=args.seed, checkpoint=str(policy.checkpoint), trained_steps=policy.step,
                  task=config.task)
    if args.ood:
        report["ood"] = True
    if args.nominal:
        report["nominal"] = True
    if args.compare_robots:
        report["robots"] = {r: _evaluate_run(args, c, policy) for r, c in configs.items()}
        report["ratios"] = robot_ratios(report["robots"], robots[0])
    else:
        report.update(_evaluate_run(args, configs[args.robot], policy), robot=args.robot)
    print(json.dumps(report) if args.json else json.dumps(report, indent=2))
    return 0


def _evaluate_run(args, config, policy) -> dict:
    """`legged eval`'s figures of `policy` with the run config `config` (its robot model chosen)."""
    import dataclasses

    from legged.tasks import task_entry
    from policies.evaluate import (HELD_OUT_SEED_OFFSET, confined_eval_config, evaluate, held_out, latent_probe,
                                   nominal_config, ood_config, summarize)
    from policies.run_dir import check_policy
    from policies.training import build_env

    soccer = task_entry(config.task).kind == "soccer"
    report = {}
    if task_entry(config.task).kind != "confined":
        env_config = held_out(config.task, config.env)
        if args.oracle:
            env_config = dataclasses.replace(env_config, estimate_oracle=tuple(args.oracle))
            report["oracle"] = list(args.oracle)
        if args.tracker:
            env_config = dataclasses.replace(env_config, vision_tracker=True)
            report["tracker"] = True
        if args.ood:
            env_config = ood_config(env_config)
        elif args.nominal:
            env_config = nominal_config(env_config)
        env = build_env(dataclasses.replace(config, env=env_config))
        check_policy(policy, env)
        if config.pilot:
            report["pilot"] = config.pilot
        samples = []
        if config.drill:
            report["drill"] = config.drill
        elif soccer:
            report["opponent"] = args.opponent or "scripted"
            if env.game.layout.players_per_team > 1:
                report["teammate"] = args.teammate or "self"
        others = _other_players(args, env, policy) if soccer and not config.drill else ()  # a drill: nobody else
        finals = evaluate(env, policy, args.episodes, args.seed, args.physics, args.num_envs or 16,
                          args.threads or None, progress=not args.quiet, probe=samples, env_args=others)
        report = dict(summarize(finals, False), **report)
        if samples and hasattr(env, "observation_layout"):
            report["latent_probe_r2"] = latent_probe(samples, env.observation_layout())
        if args.compare_teacher:
            report.update(_in_the_same_games(args, config.distill.teacher, finals, "teacher"))
        if args.compare_pilot:
            report.update(_in_the_same_games(args, config.pilot, finals, "pilot"))
    else:  # a fixed set of held-out worlds per difficulty, one episode each, every episode to its end
        report["world_seed"] = args.world_seed if args.world_seed is not None else \
            config.env.world_seed + HELD_OUT_SEED_OFFSET
        report["difficulties"] = {}
        for level in args.difficulty if args.difficulty is not None else config.env.difficulties:
            env_config = confined_eval_config(config.env, level, args.episodes, args.world_seed)
            env_config = nominal_config(env_config) if args.nominal else env_config
            env = build_env(dataclasses.replace(config, env=env_config), progress=not args.quiet)
            check_policy(policy, env)
            finals = evaluate(env, policy, args.episodes, args.seed, args.physics,
                              args.num_envs or min(args.episodes, 64), args.threads or None,
                              progress=not args.quiet, per_world=True)
            report["difficulties"][str(level)] = summarize(finals, True)
    return report


def _other_players(args, env, policy) -> tuple:
    """The soccer players `legged eval` plays `policy` with in `env`: the opponent, and in 2v2 its teammate."""
    from policies.evaluate import soccer_opponent

    others = (soccer_opponent(args.opponent or "scripted", env),)
    if env.game.layout.players_per_team > 1:
        return others + (soccer_opponent(args.teammate or "self", env, policy),)
    if args.teammate:
        raise ValueError("--teammate applies to 2v2 tasks; this one has one player per team")
    return others


def _in_the_same_games(args, state_run: str, finals: list[dict], role: str) -> dict:
    """`legged eval --compare-teacher` (or `--compare-pilot`): the student's distillation teacher (or its pilot)
    played at the truth in the games the student played (the same seed and batches start the same games), and
    the student's goals over the state player's, as `role` and `goals_vs_<role>`."""
    from policies.evaluate import evaluate, paired_goal_ratio, state_player_game, summarize
    from policies.policy_io import load_policy

    player, config = load_policy(state_run)
    env = state_player_game(config)
    player_finals = evaluate(env, player, args.episodes, args.seed, args.physics, args.num_envs or 16,
                             args.threads or None, progress=not args.quiet,
                             env_args=_other_players(args, env, player))
    summary = summarize(player_finals, False)
    keep = ("goals_for_per_episode", "goals_against_per_episode", "win_rate", "fall_rate")
    return {role: dict({k: summary[k] for k in keep}, run=state_run, checkpoint=str(player.checkpoint)),
            f"goals_vs_{role}": paired_goal_ratio([f["goals_for"] for f in finals],
                                                 [f["goals_for"] for f in player_finals])}


def cmd_plot(args) -> int:
    from policies.plots import plot_runs

    path = plot_runs(args.run_dir, args.y, args.x, args.out, args.hline)
    print(json.dumps({"plot": str(path)}) if args.json else f"[plot] wrote {path}")
    return 0


def cmd_table(args) -> int:
    from policies.tables import eval_table

    print(eval_table(args.run_dir, args.files, args.metrics))
    return 0


def cmd_export(args) -> int:
    from pathlib import Path

    from policies.export import export_onnx
    from policies.policy_io import load_policy

    if not args.onnx:
        raise ValueError("choose a format: --onnx")
    policy, config = load_policy(args.run_dir, args.checkpoint)
    out = Path(args.out or f"{args.run_dir}/policy.onnx")
    report = export_onnx(policy, out)
    if config.pilot:  # a piloted vision student deploys as two networks: it estimates, the pilot steers
        pilot, _ = load_policy(config.pilot)
        report["pilot"] = dict(export_onnx(pilot, out.with_name(f"{out.stem}_pilot.onnx")), run=config.pilot)
    print(json.dumps(report))
    return 0


def cmd_camera(args) -> int:
    from legged.soccer.states import game_start
    from legged.soccer.vision import write_camera_images
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
    from legged.cli_nav import shipped_policy
    from legged.demo import run_demo

    view = {"host": args.host, "port": args.port} if args.view else None
    return run_demo(args.out, args.seed, args.difficulty, shipped_policy(args.policy), view=view,
                    physics=args.physics)


def cmd_view(args) -> int:
    from web.app import Dashboard, DashboardConfig
    from web.source import ViewRequest, resolve

    request = ViewRequest(run_dir=args.run_dir, task=args.task, checkpoint=args.checkpoint, trajectory=args.trajectory,
                          num_envs=args.num_envs, physics=args.physics, seed=args.seed, steps=args.steps, host=args.host,
                          port=None if args.save else args.port, opponent=args.opponent,
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


def _add_server_options(parser, port: int = 8080) -> None:
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to bind (default 127.0.0.1, this machine only; 0.0.0.0 exposes it)")
    parser.add_argument("--port", type=bounded(int, 0, 65535), default=port, help="port to bind (0: any free port)")


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="legged", description="Legged-robot RL in MuJoCo/MJX.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    add_navigation_commands(sub)
    add_soccer_commands(sub)
    add_run_commands(sub)
    add_bench_commands(sub)
    tr = sub.add_parser("train", help="train a policy (Brax PPO or rsl-rl PPO) into a run directory")
    tr.add_argument("task", nargs="?", help="task name (legged tasks)")
    tr.add_argument("--backend", choices=["rsl", "brax"], default="rsl")
    tr.add_argument("--num-envs", type=bounded(int, 1, 2**20), default=256)
    tr.add_argument("--timesteps", type=bounded(int, 1, 10**12), default=1_000_000, help="environment steps, all envs together")
    tr.add_argument("--seed", type=SEED, default=0)
    add_physics_options(tr)
    tr.add_argument("--run-dir", default=None, help="where the run is written (default runs/<task>-<time>)")
    tr.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="override any config field, e.g. ppo.learning_rate=3e-4, env.episode_seconds=10, "
                         "checkpoint_every=5, device=cuda (repeatable; see config.yaml of a run for all fields)")
    tr.add_argument("--resume", default=None, metavar="DIR", help="continue the run in DIR from its last checkpoint")
    tr.add_argument("--init-from", default=None, metavar="RUN",
                    help="warm start from RUN's networks (rsl; e.g. the go1-flat walker for a confined follower)")
    tr.add_argument("--algo", choices=["ppo", "teacher", "hib", "hib-no-ib", "history"], default="ppo",
                    help="ppo; teacher (privileged encoder, for `legged distill`); hib, hib-no-ib, history "
                         "(one-stage students on the state history)")
    tr.add_argument("--quiet", action="store_true", help="no progress bar")
    tr.set_defaults(fn=cmd_train)

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
    ev.add_argument("--oracle", type=lambda v: [p for p in v.split(",") if p], default=[], metavar="ball,own_goal,...",
                    help="diagnostics: a vision player that estimates the game steers by the truth for these parts")
    ev.add_argument("--pilot", default=None, metavar="teacher|RUN|none",
                    help="a vision player that estimates the game is steered by a state player (its distillation "
                         "teacher, or a soccer run) from its estimate; none: by its own corrections (default: the "
                         "run's config.pilot)")
    ev.add_argument("--tracker", action="store_true",
                    help="a vision player that estimates the game steers by its tracker's goals and ball where it "
                         "knows them (env.vision_tracker, legged.soccer.tracker)")
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
                    help="comma-separated evaluation JSON files in each run (e.g. eval_native.json,eval_ood_native.json)")
    tb.add_argument("--metrics", type=lambda s: [m for m in s.split(",") if m],
                    default=["episode_return", "tracking_error_mps", "fall_rate"], help="comma-separated report fields")
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

    d = sub.add_parser("demo", help="generate a tunnel, plan through it, and watch the shipped follower walk Go1 "
                                    "to the goal")
    d.add_argument("--out", default="legged-demo", help="where to write the world files")
    d.add_argument("--seed", type=SEED, default=0)
    d.add_argument("--difficulty", type=bounded(int, 0, 20), default=1)
    d.add_argument("--policy", default=None, help="a waypoint-follower run (default: the shipped follower)")
    d.add_argument("--physics", type=choices("mjx", "native"), default=["native"],
                   help="comma-separated physics engines to navigate in (default native; mjx,native runs both)")
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
    v.add_argument("--opponent", default=None, metavar="placo|scripted|RUN",
                   help="soccer: what drives the other robots (default: the standing script)")
    v.add_argument("--drill", default=None, metavar="walk|empty-goal|getup",
                   help="soccer: a drill (as `legged drill`) played by the run's policy, or without a run by placo")
    add_robot_option(v)
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
