"""`legged drill walk|empty-goal|getup --player placo|script|RUN`: a soccer player's skills measured one at a time
(legged.soccer.drills), in MJX or native MuJoCo, with or without the game's domain randomisation."""

from __future__ import annotations

import dataclasses

import numpy as np

from legged.robots import OP3
from legged.robots.models import checked_model, model_path
from legged.robots.op3 import OP3_CTRL_DT
from legged.skills.config import GetUpConfig
from legged.skills.env import GetUpSkillEnv, WalkSkillEnv
from legged.soccer.config import SoccerConfig
from legged.soccer.drills import DrillConfig, DrillEnv
from legged.tasks import task_entry
from policies.environments import steer_with_pilot
from policies.evaluate import estimate_errors, evaluate, fall_figures
from policies.policy_io import GETUP_SCRIPT as SCRIPT  # `--player script`: the get-up script open loop
from policies.policy_io import load_policy, load_walker
from policies.provenance import checkpoint_record, frozen_runs, repo_path, sealed
from policies.run_dir import RunDir, check_policy

SKILL_DRILLS = {"op3-walk": "walk", "op3-getup": "getup"}
"""Skill tasks (legged.skills) and the drill each plays, in its own observations."""


@dataclasses.dataclass
class BuiltInPlayer:
    """Stands in for a trained policy where the environment drives the player itself (the placo player)."""

    action_size: int
    """Size of the (ignored) actions."""
    inputs: tuple[str, ...] = ("state",)
    """Observation groups it reads (none, really)."""

    def act(self, obs) -> np.ndarray:
        state = obs["state"] if isinstance(obs, dict) else obs
        return np.zeros((len(state), self.action_size), np.float32)

    def reset(self, done=None) -> None:
        """Nothing to forget."""


def check_player(spec: str, drill: DrillConfig) -> None:
    """ValueError (or RunDirError) naming why `--player spec` cannot do `drill`, before anything is built."""
    if spec == "placo":
        return
    if spec == SCRIPT:
        if drill.name != "getup":
            raise ValueError(f"--player script plays ROBOTIS' scripted get-up: the getup drill only, not {drill.name}")
        return
    config = RunDir(spec).load_config()  # RunDirError naming the path if it is not a run
    if config.task in SKILL_DRILLS:
        if drill.name != SKILL_DRILLS[config.task]:
            raise ValueError(f"--player {spec}: an {config.task} policy does the {SKILL_DRILLS[config.task]} drill, "
                             f"not {drill.name}")
        return
    if task_entry(config.task).kind != "soccer" or config.env.scene.players_per_team != 1:
        raise ValueError(f"--player {spec}: a drill player is placo, a skill run ({', '.join(SKILL_DRILLS)}) or a "
                         f"run of soccer-1v1 or soccer-1v1-vision, not {config.task}")
    if config.env.vision_tracker_inputs:
        raise ValueError(f"--player {spec} reads what its tracker knows (env.vision_tracker_inputs); drills play "
                         f"without the tracker (a drill does not start the player on its kick-off spot): measure it "
                         f"in games (`legged eval {spec} --opponent placo`)")
    if drill.name in ("walk", "getup"):
        raise ValueError(f"--player {spec}: the {drill.name} drill needs placo or an "
                         f"{next(t for t, d in SKILL_DRILLS.items() if d == drill.name)} run; {config.task} "
                         f"policies are not trained for it")


def drill_player(spec: str, env: DrillEnv, checkpoint: str | None = None):
    """The player `--player` names (checked by `check_player`): `placo`, or a run whose policy (its newest
    checkpoint, or `checkpoint`) plays agent 0."""
    if spec in ("placo", SCRIPT):
        return BuiltInPlayer(env.action_size)
    policy, _ = load_policy(spec, checkpoint)
    check_policy(policy, env)
    return policy


def players_view(trained: SoccerConfig) -> SoccerConfig:
    """The drills' game (SoccerConfig's defaults) with what a player trained on `trained` sees and how: its head
    camera (size, lens, tilt), the vision flags (heading, sightings, gaze), the velocity estimate its walker may
    read. Not its tracker (vision_tracker): a drill
    does not start the player on its kick-off spot, which the tracker needs."""
    scene = dataclasses.replace(SoccerConfig().scene, head_camera_tilt_deg=trained.scene.head_camera_tilt_deg,
                                head_camera_fovy_deg=trained.scene.head_camera_fovy_deg)
    return dataclasses.replace(SoccerConfig(), vision=trained.vision, camera=trained.camera, scene=scene,
                               vision_heading=trained.vision_heading, vision_sightings=trained.vision_sightings,
                               vision_sighted_ball=trained.vision_sighted_ball, vision_gaze=trained.vision_gaze,
                               velocity_in_state=trained.velocity_in_state)


def drill_env(player: str, drill: DrillConfig, randomize: bool, robot: str = "project") -> DrillEnv:
    """The drill's environment for `player`: the drill itself (commanding the run's walker if it has one), or
    for a skill run (legged.skills) its task set up as the drill; the game's randomisation on or off; every
    robot on the OP3 model `robot` (project, menagerie or an MJCF path: legged.robots.models)."""
    run = None if player in ("placo", SCRIPT) else RunDir(player).load_config()
    with_randomization = lambda config: dataclasses.replace(
        config, robot_model=robot, randomization=dataclasses.replace(config.randomization, enabled=randomize))
    if run is not None and run.task == "op3-walk":  # the run's own config (what it trained on), drill commands
        return WalkSkillEnv(with_randomization(dataclasses.replace(
            run.env, command_seconds=drill.command_seconds, command_low=drill.command_low,
            command_high=drill.command_high, episode_seconds=20.0)))
    if player == SCRIPT or (run is not None and run.task == "op3-getup"):  # the script: the reference, no policy
        base = GetUpConfig() if run is None else run.env
        return GetUpSkillEnv(with_randomization(dataclasses.replace(base, episode_seconds=drill.getup_seconds)))
    walker = None
    if run is not None and run.soccer.walker:  # a soccer player that commands a walking skill
        walker = load_walker(run.soccer.walker, run.soccer.getup, run.soccer.command_prior)
    game = SoccerConfig() if run is None else players_view(run.env)
    env = DrillEnv(drill, with_randomization(game), placo=player == "placo", walker=walker,
                   teacher_prior=run is not None and run.game_gives_placo_command)  # a vision student's observations
    if run is not None and run.soccer.pilot:  # a vision student steered by a state player from its estimate
        steer_with_pilot(env, run.soccer.pilot)
    return env


def run_drill(name: str, player: str, episodes: int, seed: int, physics: str = "native", threads: int | None = None,
              randomize: bool = False, progress: bool = True, num_envs: int = 16,
              checkpoint: str | None = None, seconds: float | None = None, robot: str = "project") -> dict:
    """Run `episodes` episodes of drill `name` with `player` (a run: its newest checkpoint, or `checkpoint`),
    each `seconds` long (default: DrillConfig's), on the OP3 model `robot`; returns its figures (see
    legged.soccer.drills)."""
    lengths = {} if seconds is None else {"getup_seconds" if name == "getup" else "episode_seconds": seconds}
    drill = DrillConfig(name=name, **lengths)
    check_player(player, drill)
    checked_model(OP3, robot, OP3_CTRL_DT, physics)  # a bad model: one line, before any policy loads
    env = drill_env(player, drill, randomize, robot)
    policy = drill_player(player, env, checkpoint)
    finals = evaluate(env, policy, episodes, seed, physics, num_envs, threads, progress=progress)
    errors = estimate_errors(finals)  # a vision player that estimates the game
    played = repo_path(policy.checkpoint) if hasattr(policy, "checkpoint") else None  # a run's checkpoint
    report = {"drill": name, "player": player, "checkpoint": played, "episodes": len(finals), "physics": physics,
              "seed": seed, "randomized": randomize, "robot": robot,
              "episode_seconds": float(np.mean([f["time_s"] for f in finals])), **fall_figures(finals)}
    if errors:
        report["estimate_rms_m"] = errors
    if getattr(env, "state_pilot", None) is not None:
        report["pilot"] = env.pilot_name
    if name == "walk":
        walk = ("speed_mps", "tracking_error_mps", "smoothed_tracking_error_mps", "smoothed_yaw_rate_error_radps")
        report.update({k: float(np.mean([f[k] for f in finals])) for k in walk})
    elif name == "getup":
        stood = np.array([f["stood"] > 0 for f in finals])
        report.update(success_rate=float(stood.mean()),
                      time_to_stand_s=float(np.mean([f["time_to_stand_s"] for f in finals if f["stood"] > 0]))
                      if stood.any() else None)
    else:
        scored = np.array([f["goals_for"] > 0 for f in finals])
        report.update(goal_rate=float(scored.mean()),
                      time_to_goal_s=float(np.mean([f["time_s"] for f in finals if f["goals_for"] > 0]))
                      if scored.any() else None)
    runs = {} if played is None else dict(policy=checkpoint_record(policy),
                                          **frozen_runs(RunDir(player).load_config()))
    return sealed(report, runs, {robot: model_path(OP3, robot) or OP3.mjcf_path})
