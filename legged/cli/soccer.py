"""The command line's soccer commands: `legged drill`."""

from __future__ import annotations

import json

from legged.cli.args import SEED, add_physics_options, add_robot_option, bounded


def cmd_drill(args) -> int:
    """`legged drill`: one skill of a soccer player, measured and printed as JSON."""
    from legged.soccer.drills import DRILLS
    from policies.soccer.drill import run_drill

    if args.drill not in DRILLS:
        raise ValueError(f"unknown drill {args.drill!r}; drills: {', '.join(DRILLS)}")
    if args.checkpoint and args.player in ("placo", "script"):
        raise ValueError(f"--checkpoint picks a checkpoint of a run; --player {args.player} has none")
    report = run_drill(args.drill, args.player, args.episodes, args.seed, args.physics, args.threads or None,
                       randomize=args.randomize, progress=not args.quiet, num_envs=min(args.episodes, args.num_envs),
                       checkpoint=args.checkpoint, seconds=args.seconds, robot=args.robot)
    print(json.dumps(report) if args.json else json.dumps(report, indent=2))
    return 0


def add_soccer_commands(sub) -> None:
    """Register `drill`."""
    dr = sub.add_parser("drill", help="measure one skill of a soccer player: walk (velocity commands), "
                                      "empty-goal (score from 1-2 m) or getup (stand up from lying)")
    dr.add_argument("drill", help="walk, empty-goal or getup")
    dr.add_argument("--player", default="placo", metavar="placo|script|RUN",
                    help="the placo player (default), ROBOTIS' scripted get-up (script: getup), a skill run "
                         "(op3-walk: walk, op3-getup: getup) or a soccer-1v1 run directory (empty-goal)")
    dr.add_argument("--checkpoint", default=None, help="a checkpoint file of the --player run (default: its newest)")
    dr.add_argument("--episodes", type=bounded(int, 1, 100000), default=16)
    dr.add_argument("--seed", type=SEED, default=12345, help="seed of the drill episodes")
    dr.add_argument("--seconds", type=bounded(float, 0, 3600), default=None,
                    help="length of an episode (default: 20 s for walk and empty-goal, 5 s for getup)")
    dr.add_argument("--num-envs", type=bounded(int, 1, 4096), default=16, help="episodes run side by side")
    dr.add_argument("--randomize", action="store_true",
                    help="the game's domain randomisation (friction, ball, masses, motor strength)")
    add_physics_options(dr, default="native")
    add_robot_option(dr)
    dr.add_argument("--json", action="store_true", help="one-line JSON")
    dr.add_argument("--quiet", action="store_true", help="no progress bar")
    dr.set_defaults(fn=cmd_drill)
