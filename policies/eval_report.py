"""`legged eval`'s figures as a library call: an `EvalRequest` (one field per option of the command) in, the
report dict out. Every request is checked against the run before a policy is loaded or a scene compiled."""

from __future__ import annotations

import dataclasses

from legged.robots.models import model_path
from legged.tasks import task_entry
from legged.worlds.levels import LEVELS
from policies.config import apply_overrides
from policies.config_io import ConfigError
from policies.environments import build_env, soccer_opponent
from policies.evaluate import (HELD_OUT_SEED_OFFSET, confined_eval_config, evaluate, held_out, latent_probe,
                               nominal_config, on_robot, ood_config, paired_goal_ratio, robot_ratios,
                               state_player_game, summarize)
from policies.policy_io import load_policy
from policies.provenance import checkpoint_record, frozen_runs, repo_path, sealed
from policies.run_dir import RunDir, check_policy


@dataclasses.dataclass(frozen=True)
class EvalRequest:
    """What to evaluate and how: the options of `legged eval` (the error messages name them as options)."""

    run_dir: str
    """The run directory whose policy is evaluated."""
    checkpoint: str | None = None
    """A checkpoint file of the run (None: its newest)."""
    episodes: int = 32
    """Episodes to play (confined tasks: held-out worlds per difficulty, one episode each)."""
    seed: int = 12345
    """Seed of the evaluation episodes."""
    physics: str = "mjx"
    """Physics engine: mjx or native."""
    threads: int | None = None
    """CPU threads of native physics and torch (None: every core)."""
    num_envs: int | None = None
    """Episodes run side by side (None: 16; confined tasks: all, up to 64)."""
    difficulty: tuple[int, ...] | None = None
    """Confined tasks: the difficulty levels to evaluate (None: the levels the run trained on)."""
    world_seed: int | None = None
    """Confined tasks: seed of the evaluation worlds (None: the training seed + HELD_OUT_SEED_OFFSET)."""
    opponent: str | None = None
    """Soccer tasks: who plays the other team, placo, scripted or a run (None: the standing script)."""
    teammate: str | None = None
    """2v2: who plays the learner's teammate, self, placo, scripted or a run (None: self)."""
    ood: bool = False
    """Dynamics drawn out of the training distribution."""
    nominal: bool = False
    """Each robot model as it is: domain randomisation and observation noise off."""
    oracle: tuple[str, ...] = ()
    """Diagnostics: the parts of the game a vision player steers by the truth for."""
    pilot: str | None = None
    """The state player steering a vision player: teacher, a soccer run or none (None: the run's own)."""
    tracker: bool = False
    """A vision player steers by its tracker's goals and ball where it knows them."""
    compare_teacher: bool = False
    """A distilled soccer student: also play its teacher in the same games."""
    compare_pilot: bool = False
    """A piloted vision student: also play its pilot at the truth in the same games."""
    env_set: tuple[str, ...] = ()
    """Changes to the evaluated environment, `env.PATH=VALUE` as `legged train --set` takes them
    (`env.randomization.elliptic_share=null`): the setting's effect on a trained policy."""
    robot: str = "project"
    """The robot model the policy runs on."""
    compare_robots: tuple[str, ...] = ()
    """The same episodes on each of these robot models (replaces `robot`; empty: `robot` alone)."""
    progress: bool = True
    """Show progress bars."""


def evaluation_report(request: EvalRequest) -> dict:
    """Evaluate the policy of `request.run_dir` as `request` asks and return the report (`legged eval`'s JSON).
    A request the run cannot serve fails with a ValueError before a policy is loaded or a scene compiled."""
    config = RunDir(request.run_dir).load_config()
    robots = check_request(request, config)
    policy, config = load_policy(request.run_dir, request.checkpoint)
    if request.pilot:  # replaces the run's own pilot (none: the student's own corrections)
        pilot = {"teacher": config.distill.teacher, "none": ""}.get(request.pilot, request.pilot)
        config = dataclasses.replace(config, soccer=dataclasses.replace(config.soccer, pilot=pilot)).resolved()
    configs = {r: on_robot(config, r) for r in robots}
    report = dict(physics=request.physics, seed=request.seed, checkpoint=repo_path(policy.checkpoint),
                  trained_steps=policy.step, task=config.task)
    if request.ood:
        report["ood"] = True
    if request.nominal:
        report["nominal"] = True
    if request.env_set:
        report["env_set"] = list(request.env_set)
    if request.compare_robots:
        report["robots"] = {r: _evaluate_run(request, c, policy) for r, c in configs.items()}
        report["ratios"] = robot_ratios(report["robots"], robots[0])
    else:
        report.update(_evaluate_run(request, configs[request.robot], policy), robot=request.robot)
    others = {"opponent": request.opponent, "teammate": request.teammate,
              "teacher": config.distill.teacher if request.compare_teacher else None}
    spec = task_entry(config.task).robot
    return sealed(report, dict(policy=checkpoint_record(policy), **frozen_runs(config, **others)),
                  {r: model_path(spec, r) or spec.mjcf_path for r in robots})


def check_request(request: EvalRequest, config) -> list[str]:
    """Check `request` against the run's config `config` (a ValueError naming the option if it does not fit);
    returns the robot models to evaluate on, each checked to be usable."""
    confined = task_entry(config.task).kind == "confined"
    if not confined and (request.difficulty is not None or request.world_seed is not None):
        raise ValueError(f"--difficulty and --world-seed apply to confined tasks; {config.task} has no worlds")
    if confined and config.env.levels is not None and request.difficulty is not None:
        unknown = sorted(set(request.difficulty) - set(LEVELS))
        if unknown:
            raise ValueError(f"--difficulty {unknown} is no level of this run's worlds: levels are "
                             f"{', '.join(map(str, LEVELS))}")
    if request.ood:
        ood_config(config.env)  # fails now for tasks without dynamics randomisation
        if request.nominal:
            raise ValueError("--ood draws dynamics out of the training distribution; --nominal draws none: choose one")
    soccer = task_entry(config.task).kind == "soccer"
    if (request.opponent or request.teammate) and not soccer:
        raise ValueError(f"--opponent (or --teammate) applies to soccer tasks; {config.task} has no opponents")
    if (request.pilot or request.oracle or request.tracker) and not soccer:
        raise ValueError(f"--pilot, --oracle and --tracker apply to soccer vision students; {config.task} is not "
                         f"soccer")
    if request.pilot == "teacher" and not config.distill.teacher:
        raise ValueError(f"--pilot teacher: {request.run_dir} was not distilled from a teacher; name a soccer run")
    drill = config.soccer.drill
    if request.compare_teacher and (not soccer or drill or not config.distill.teacher):
        raise ValueError(f"--compare-teacher plays a distilled soccer student's teacher in the same games; "
                         f"{request.run_dir} is not a soccer student distilled from a teacher (task {config.task}"
                         f"{', drill ' + drill if drill else ''})")
    if request.compare_pilot and (not soccer or drill or not (request.pilot or config.soccer.pilot)
                                  or request.pilot == "none"):
        raise ValueError(f"--compare-pilot plays a piloted vision student's pilot, at the truth, in the same games; "
                         f"{request.run_dir} has no pilot (give one with --pilot RUN)")
    if drill and (request.opponent or request.teammate):
        raise ValueError(f"{request.run_dir} trained on the {drill} drill, where nobody else plays: its eval "
                         f"plays the drill, without --opponent or --teammate (or use `legged drill {drill} "
                         f"--player {request.run_dir}`)")
    if (request.compare_teacher or request.compare_pilot) and (request.compare_robots or request.robot != "project"):
        raise ValueError("--compare-teacher and --compare-pilot play on the project's robot model; run them without "
                         "--robot and --compare-robots")
    if request.compare_robots and (request.robot != "project"
                                   or len(set(request.compare_robots)) < len(request.compare_robots)):
        raise ValueError("--compare-robots names each model once, and replaces --robot")
    changed_env(config, config.env, request.env_set)  # a bad change fails here, in one line
    robots = list(request.compare_robots or [request.robot])
    for robot in robots:  # a model that cannot be used fails here, before a policy is loaded or a scene compiled
        on_robot(config, robot, request.physics)
    return robots


def changed_env(config, env_config, changes: tuple[str, ...]):
    """`env_config` with `legged eval --set`'s changes (`env.PATH=VALUE`); a change outside `env.` or naming no
    field is a ValueError in one line."""
    if not changes:
        return env_config
    wrong = [c for c in changes if not c.startswith("env.")]
    if wrong:
        raise ValueError(f"legged eval --set changes the evaluated environment only (env.PATH=VALUE), got "
                         f"{', '.join(wrong)}")
    try:
        return apply_overrides(dataclasses.replace(config, env=env_config), list(changes)).env
    except ConfigError as e:
        raise ValueError(f"--set: {e}") from None


def _evaluate_run(request: EvalRequest, config, policy) -> dict:
    """The figures of `policy` with the run config `config` (its robot model chosen)."""
    soccer = task_entry(config.task).kind == "soccer"
    report = {}
    if task_entry(config.task).kind != "confined":
        env_config = held_out(config.task, config.env)
        if request.oracle:
            env_config = dataclasses.replace(env_config, estimate_oracle=tuple(request.oracle))
            report["oracle"] = list(request.oracle)
        if request.tracker:
            env_config = dataclasses.replace(env_config, vision_tracker=True)
            report["tracker"] = True
        if request.ood:
            env_config = ood_config(env_config)
        elif request.nominal:
            env_config = nominal_config(env_config)
        env_config = changed_env(config, env_config, request.env_set)
        env = build_env(dataclasses.replace(config, env=env_config))
        check_policy(policy, env)
        if config.soccer.pilot:
            report["pilot"] = config.soccer.pilot
        samples = []
        if config.soccer.drill:
            report["drill"] = config.soccer.drill
        elif soccer:
            report["opponent"] = request.opponent or "scripted"
            if env.game.layout.players_per_team > 1:
                report["teammate"] = request.teammate or "self"
        others = () if not soccer or config.soccer.drill else _other_players(request, env, policy)  # drills: alone
        finals = evaluate(env, policy, request.episodes, request.seed, request.physics, request.num_envs or 16,
                          request.threads, progress=request.progress, probe=samples, env_args=others)
        report = dict(summarize(finals, False), **report)
        if samples and hasattr(env, "observation_layout"):
            report["latent_probe_r2"] = latent_probe(samples, env.observation_layout())
        if request.compare_teacher:
            report.update(_in_the_same_games(request, config.distill.teacher, finals, "teacher"))
        if request.compare_pilot:
            report.update(_in_the_same_games(request, config.soccer.pilot, finals, "pilot"))
    else:  # a fixed set of held-out worlds per difficulty, one episode each, every episode to its end
        report["world_seed"] = request.world_seed if request.world_seed is not None else \
            config.env.world_seed + HELD_OUT_SEED_OFFSET
        report["difficulties"] = {}
        for level in request.difficulty if request.difficulty is not None else config.env.difficulties:
            env_config = confined_eval_config(config.env, level, request.episodes, request.world_seed)
            env_config = nominal_config(env_config) if request.nominal else env_config
            env_config = changed_env(config, env_config, request.env_set)
            env = build_env(dataclasses.replace(config, env=env_config), progress=request.progress)
            check_policy(policy, env)
            finals = evaluate(env, policy, request.episodes, request.seed, request.physics,
                              request.num_envs or min(request.episodes, 64), request.threads,
                              progress=request.progress, per_world=True)
            report["difficulties"][str(level)] = summarize(finals, True)
    return report


def _other_players(request: EvalRequest, env, policy) -> tuple:
    """The soccer players `policy` plays with in `env`: the opponent, and in 2v2 its teammate."""
    others = (soccer_opponent(request.opponent or "scripted", env),)
    if env.game.layout.players_per_team > 1:
        return others + (soccer_opponent(request.teammate or "self", env, policy),)
    if request.teammate:
        raise ValueError("--teammate applies to 2v2 tasks; this one has one player per team")
    return others


def _in_the_same_games(request: EvalRequest, state_run: str, finals: list[dict], role: str) -> dict:
    """`compare_teacher` (or `compare_pilot`): the student's distillation teacher (or its pilot) played at the
    truth in the games the student played (the same seed and batches start the same games), and the student's
    goals over the state player's, as `role` and `goals_vs_<role>`."""
    player, config = load_policy(state_run)
    env = state_player_game(config)
    player_finals = evaluate(env, player, request.episodes, request.seed, request.physics, request.num_envs or 16,
                             request.threads, progress=request.progress,
                             env_args=_other_players(request, env, player))
    summary = summarize(player_finals, False)
    keep = ("goals_for_per_episode", "goals_against_per_episode", "win_rate", "falls_per_episode",
            "episodes_with_a_fall")
    return {role: dict({k: summary[k] for k in keep}, run=state_run, checkpoint=repo_path(player.checkpoint)),
            f"goals_vs_{role}": paired_goal_ratio([f["goals_for"] for f in finals],
                                                 [f["goals_for"] for f in player_finals])}
