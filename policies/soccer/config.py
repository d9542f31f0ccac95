"""The soccer section of a training run's config (TrainConfig.soccer): the skills a player commands, its opponents,
drills, pilots; the checks that need the rest of the run's config; and the migration of configs written before
the section existed, whose soccer keys sat at the top level (`walker: RUN`, `--set selfplay.scripted_fraction=0.7`).

This module does not import policies.config (which imports it): `check_soccer` reads the TrainConfig it is given.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

from legged.soccer.vision.estimates import label_groups
from policies.config_io import ConfigError


@dataclasses.dataclass(frozen=True)
class SelfPlayConfig:
    """Who the soccer learner plays against (soccer tasks only; the learner is agent 0, see LearnerView)."""

    opponent: Literal["auto", "scripted", "self-play"] = "auto"
    """self-play: frozen snapshots of the learner drive the other robots (rsl backend, state tasks);
    scripted: the fixed script; auto: self-play where it applies, else scripted (Brax, vision tasks)."""
    snapshot_every: int = 10
    """Iterations between snapshots of the learner's actor into the pool."""
    pool_size: int = 8
    """Snapshots kept (the oldest is dropped)."""
    scripted_fraction: float = 0.2
    """Chance that a draw picks the script instead of a snapshot (always, while the pool is empty)."""
    draw_per_game: bool = True
    """A drawn opponent plays until a game ends (in any environment), so that one with a memory (the placo
    player's walk and kick) plays whole games; false: a new draw every iteration (what runs before 2026-11-26
    did; their configs lack the field and resume with the new default)."""
    script: Literal["placo", "standing"] = "placo"
    """The script: the placo player (walks to the ball and kicks it) or the standing goalkeeper."""


@dataclasses.dataclass(frozen=True)
class SoccerTrainConfig:
    """Settings of soccer runs only (TrainConfig.soccer; the other tasks ignore them, the checks refuse them set)."""

    drill: str = ""
    """Soccer-1v1 tasks, rsl backend: train on a drill (legged.soccer.drills) instead of the game: `empty-goal`
    (the ball 1-2 m before the opponent goal, nobody defending, episodes end at a goal), or '' for the game."""
    selfplay: SelfPlayConfig = SelfPlayConfig()
    """Opponents of the soccer tasks (ignored by the others)."""
    walker: str = ""
    """Soccer tasks: run directory of an op3-walk policy; the learner then commands velocities that this frozen
    walker turns into joint actions (legged.soccer.walker). '' : the learner drives the joints itself."""
    command_prior: str = ""
    """Soccer tasks with a walker: `placo` makes the learner's actions corrections added to the placo player's
    walking command (to the spot behind the ball, lined up on the goal); '' : its actions are the command."""
    getup: str = ""
    """Soccer tasks with a walker: how a fallen robot gets up, `script` (ROBOTIS' scripted get-up) or the run
    directory of an op3-getup policy (needs env.end_on_fall=never, so that a fall does not end the game, and
    env.scene.limb_floor_contacts=true, as in its training). '' : fallen robots stay down."""
    pilot: str = ""
    """Vision students that estimate the game (command_prior=placo): run directory of a state soccer player whose
    corrections, at the student's estimate, steer it instead of its own (LearnerView.steer_with); eval, view,
    drill and export load it with the student. Not for training. '' : the student's own corrections."""
    steered_student: str = ""
    """State soccer players (command_prior=placo): run directory of a vision student that estimates the game;
    this player then trains as its pilot, in its camera game on its frozen estimate (policies.soccer.steered)."""


SOCCER_KEYS = ("drill", "selfplay", "walker", "command_prior", "getup", "pilot", "steered_student")
"""The keys that moved from the top level of a TrainConfig into `soccer` (SoccerTrainConfig's fields then): an
older config.yaml holding them there, or an override naming one (the cards' `--set walker=RUN`, `--set
selfplay.scripted_fraction=0.7`), is read as `soccer.<key>`. The one list of them: load_config and apply_overrides
(policies.config) migrate through nest_soccer_keys and soccer_override_path."""

TRAINING_DRILLS = ("empty-goal",)
"""Drills a run can train on (walk and getup measure skills whose commands or scripts its policy does not see)."""


def nest_soccer_keys(data: dict) -> dict:
    """A config's plain form (a run's config.yaml) with the SOCCER_KEYS found at its top level, where configs
    written before TrainConfig.soccer hold them, moved into `soccer`; ConfigError for a key given in both places."""
    moved = {k: data[k] for k in SOCCER_KEYS if k in data}
    if not moved:
        return data
    section = data.get("soccer")
    if section is None:
        section = {}
    if not isinstance(section, dict):
        raise ConfigError(f"soccer: expected a mapping of the soccer settings, got {section!r}")
    twice = sorted(set(moved) & set(section))
    if twice:
        raise ConfigError(f"{twice[0]} is given twice, at the top level (where configs written before the soccer "
                          f"section held it) and as soccer.{twice[0]}: keep soccer.{twice[0]} only")
    rest = {k: v for k, v in data.items() if k not in moved}
    return {**rest, "soccer": {**section, **moved}}


def soccer_override_path(path: str) -> str:
    """An override's path with a leading SOCCER_KEYS key moved into `soccer` (`walker` -> `soccer.walker`,
    `selfplay.scripted_fraction` -> `soccer.selfplay.scripted_fraction`); any other path as it is."""
    return f"soccer.{path}" if path.split(".", 1)[0] in SOCCER_KEYS else path


def check_soccer(cfg, entry) -> None:
    """ConfigError naming the first soccer setting (`cfg.soccer`, a resolved TrainConfig's; `entry` its task's
    registry entry) that this run cannot use, or a vision student's setting that its algorithm cannot learn."""
    s, sp, soccer = cfg.soccer, cfg.soccer.selfplay, entry.kind == "soccer"
    if s.drill:
        _check_drill(cfg, entry)
    if soccer and sp.opponent == "self-play" and (cfg.backend == "brax" or entry.vision):
        raise ConfigError("soccer.selfplay.opponent=self-play needs the rsl backend and a state task (snapshots of "
                          "the learner are MLPs on the state features); use soccer.selfplay.opponent=scripted")
    if sp.snapshot_every < 1 or sp.pool_size < 1 or not 0.0 <= sp.scripted_fraction <= 1.0:
        raise ConfigError("soccer.selfplay: snapshot_every and pool_size must be >= 1, scripted_fraction in [0, 1]")
    if sp.script not in ("placo", "standing"):
        raise ConfigError(f"soccer.selfplay.script must be 'placo' or 'standing', got {sp.script!r}")
    if s.walker and (not soccer or cfg.backend != "rsl"):
        raise ConfigError(f"soccer.walker (an op3-walk run the learner commands) is for soccer tasks with the rsl "
                          f"backend, not {cfg.task} with {cfg.backend}")
    if s.command_prior not in ("", "placo") or (s.command_prior and not s.walker):
        raise ConfigError(f"soccer.command_prior must be '' or 'placo' (with soccer.walker=OP3_WALK_RUN: "
                          f"corrections to the placo player's walking command), got {s.command_prior!r}"
                          + ("" if s.walker else " without a walker"))
    if s.getup and (not s.walker or getattr(cfg.env, "end_on_fall", None) != "never"
                    or not cfg.env.scene.limb_floor_contacts):
        raise ConfigError("soccer.getup (script or an op3-getup run that stands fallen players up) needs "
                          "soccer.walker=OP3_WALK_RUN, env.end_on_fall=never (else a fall ends the game before "
                          "anyone gets up) and env.scene.limb_floor_contacts=true (the skill pushes up with its arms "
                          "and legs)")
    if s.pilot and not cfg.estimates_world:
        raise ConfigError(f"soccer.pilot (a state soccer run steering a vision student from its estimate of the "
                          f"game) needs a vision student that estimates the game (a soccer vision task, a walker, "
                          f"soccer.command_prior=placo); this run is {cfg.task} with command_prior "
                          f"{s.command_prior!r}")
    if s.pilot in ("placo", "scripted", "self", "teacher", "none"):
        raise ConfigError(f"soccer.pilot={s.pilot}: a pilot is the run directory of a state soccer player trained "
                          f"with soccer.command_prior=placo")
    if s.steered_student and (entry.vision or not s.command_prior or cfg.backend != "rsl" or cfg.algo != "ppo"):
        raise ConfigError(f"soccer.steered_student (a vision student this player learns to steer) needs a state "
                          f"soccer task with soccer.command_prior=placo, trained by rsl ppo; this run is {cfg.task}, "
                          f"command_prior {s.command_prior!r}, {cfg.backend} {cfg.algo}")
    if cfg.estimates_world and cfg.algo not in ("dagger", "kl"):
        raise ConfigError(f"soccer.command_prior=placo on a vision task makes the player estimate the ball, goals "
                          f"and opponent as actions, which only a distilled student learns (legged distill ... "
                          f"--method dagger|kl), not --algo {cfg.algo}")
    if cfg.distill.label_weights:
        _check_label_weights(cfg)


def _check_drill(cfg, entry) -> None:
    """ConfigError unless `cfg.soccer.drill` is a drill this run can train on."""
    drill = cfg.soccer.drill
    if drill not in TRAINING_DRILLS:
        raise ConfigError(f"soccer.drill must be '' (the game) or one of {', '.join(TRAINING_DRILLS)}, got "
                          f"{drill!r}")
    if entry.kind != "soccer" or cfg.env.scene.players_per_team != 1 or cfg.backend != "rsl":
        raise ConfigError(f"soccer.drill={drill} trains a soccer-1v1 player (soccer-1v1 or soccer-1v1-vision) with "
                          f"the rsl backend, not {cfg.task} with {cfg.backend}")


def _check_label_weights(cfg) -> None:
    """ConfigError unless `distill.label_weights` names label groups of this student with weights >= 0."""
    if not cfg.estimates_world or cfg.algo != "dagger":
        raise ConfigError("distill.label_weights weighs the labels of a dagger student that estimates the game "
                          "(legged distill ... --task soccer-1v1-vision --method dagger --set "
                          "soccer.command_prior=placo)")
    groups = label_groups(cfg.env.scene.players_per_team)
    unknown = sorted(set(cfg.distill.label_weights) - set(groups))
    if unknown:
        raise ConfigError(f"distill.label_weights: no label group(s) {unknown}; the groups are {', '.join(groups)}")
    bad = {k: w for k, w in cfg.distill.label_weights.items() if not 0.0 <= w <= 1e3}
    if bad:
        raise ConfigError(f"distill.label_weights must be in [0, 1000], got {bad}")
