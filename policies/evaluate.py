"""`legged eval`: a trained policy on held-out worlds, in MJX or in native MuJoCo, as task metrics."""

from __future__ import annotations

import dataclasses
import math

import jax
import mujoco
import numpy as np
from scipy.stats import binomtest, norm
from tqdm import tqdm

from legged.envs.curriculum import level_carry
from legged.envs.vector import VectorEnv
from legged.robots.models import checked_model
from legged.tasks import task_entry
from policies.algorithms import privileged_slices
from policies.environments import build_env, soccer_opponent, steer_with_pilot  # noqa: F401 (the last two: re-exports)
from policies.policy_io import actor_observation
from policies.probe import probe_r2

HELD_OUT_SEED_OFFSET = 1_000_003
"""Evaluation worlds use world_seed + this: never the worlds the policy trained on."""


def whole_episodes(env_config, **changes):
    """The confined env config with `changes` and no stall timeout: an evaluated or navigated episode runs to its
    time limit (training ends a stalled one early as a failure)."""
    return dataclasses.replace(env_config, stall_timeout_s=math.inf, **changes)


def held_out(task: str, env_config):
    """The env config with held-out worlds (confined tasks) or terrain (rough ground: every level, no
    curriculum), and no time-limit change."""
    if task_entry(task).kind == "confined":  # whole episodes: a stalled robot is not cut short as in training
        return whole_episodes(env_config, world_seed=env_config.world_seed + HELD_OUT_SEED_OFFSET)
    if hasattr(env_config, "terrain_seed"):
        return dataclasses.replace(env_config, terrain_seed=env_config.terrain_seed + HELD_OUT_SEED_OFFSET,
                                   curriculum=False)
    return env_config


def ood_config(env_config):
    """The env config out of the training distribution: friction 0.1-0.25, a 4 kg payload, motor
    strength 0.7-0.8 and pushes 1.5 times as strong; ValueError for tasks without dynamics randomisation."""
    r = getattr(env_config, "randomization", None)
    if r is None or not hasattr(r, "push_velocity"):
        raise ValueError("--ood changes the dynamics randomisation of Go1 tasks; this task has none")
    return dataclasses.replace(env_config, randomization=dataclasses.replace(
        r, enabled=True, friction=(0.1, 0.25), base_mass_offset=(4.0, 4.0), motor_strength=(0.7, 0.8),
        push_velocity=1.5 * r.push_velocity))


def nominal_config(env_config):
    """The env config with domain randomisation and observation noise off: each robot model as it is (its own
    masses, gains, joints and contacts; no pushes, latency or sensor errors)."""
    return dataclasses.replace(env_config, randomization=dataclasses.replace(env_config.randomization, enabled=False),
                               noise=dataclasses.replace(env_config.noise, enabled=False))


MODEL_RANGES = ("joint_damping", "joint_armature", "joint_frictionloss", "contact_softness", "contact_timeconst",
                "contact_margin", "contact_spin")
"""Randomisation ranges that replace a model's own values: off when a policy runs on another model (`on_robot`)."""


def on_robot(config, robot: str, physics: str | None = None):
    """The run config `config` with its task's robot model chosen (`--robot`: project, a reference name or an
    MJCF path; legged.robots.models), the model checked now (and that MJX runs it, for `physics` mjx); ValueError
    naming the cause. On a model other than the project's, the randomisation keeps that model's own joint and foot
    parameters (MODEL_RANGES off); the rest of it (masses, gains, latency, pushes, ...) stays as the run has it."""
    if robot in ("", "project"):
        return config
    if not task_entry(config.task).robot_models:
        raise ValueError(f"--robot {robot}: {config.task} runs on the project's {task_entry(config.task).robot.name} "
                         f"model only")
    checked_model(task_entry(config.task).robot, robot, config.env.ctrl_dt, physics)
    # the model's own joints and feet, not draws that would replace them (a run trained with those ranges)
    drawn = {f.name for f in dataclasses.fields(config.env.randomization)}
    own = dataclasses.replace(config.env.randomization, **{k: None for k in MODEL_RANGES if k in drawn})
    return dataclasses.replace(config, env=dataclasses.replace(config.env, robot_model=robot, randomization=own))


RATIO_FIGURES = ("tracking_error_mps", "falls_per_episode", "episodes_with_a_fall", "episode_return",
                 "goals_for_per_episode", "goals_against_per_episode", "win_rate", "success_rate", "time_to_goal_s",
                 "collisions_per_episode")
"""The figures `legged eval --compare-robots` gives as ratios to the first robot model's."""


def robot_ratios(reports: dict, first: str) -> dict:
    """Each robot model's RATIO_FIGURES over the model `first`'s (confined tasks: per difficulty); None where the
    first model's figure is 0 or missing."""
    def ratios(mine: dict, base: dict) -> dict:
        out = {}
        for key, value in mine.items():
            if isinstance(value, dict) and isinstance(base.get(key), dict):
                out[key] = ratios(value, base[key])
            elif key in RATIO_FIGURES and isinstance(value, (int, float)):
                ref = base.get(key)
                out[key] = round(value / ref, 4) if isinstance(ref, (int, float)) and ref else None
        return {k: v for k, v in out.items() if v != {}}

    return {name: ratios(report, reports[first]) for name, report in reports.items() if name != first}


def estimate_errors(finals: list[dict]) -> dict:
    """A vision player that estimates the game: the RMS position errors of its estimate (metres) by part, averaged
    over the episodes, and `ball_near` (the ball when near, legged.soccer.vision.estimates.NEAR_BALL_M) pooled over the
    steps it was near (None if it never was); {} for other players."""
    estimates = sorted(k for k in finals[0]
                       if k.startswith("estimate_") and k.endswith("_m") and k != "estimate_ball_near_m")
    out = {k[9:-2]: float(np.mean([f[k] for f in finals])) for k in estimates}
    if "estimate_ball_near_m" in finals[0]:
        steps = np.array([f["estimate_ball_near_steps"] for f in finals])
        sq = np.array([f["estimate_ball_near_m"] ** 2 for f in finals]) * steps
        out["ball_near"] = float(np.sqrt(sq.sum() / steps.sum())) if steps.sum() > 0 else None
        out["ball_near_share"] = float(steps.sum() / np.sum([f["length"] for f in finals]))
    return out


def fall_figures(finals: list[dict]) -> dict:
    """Falls counted as they happened (legged.envs.events) over finished episodes: `falls` (all of them),
    `falls_per_episode`, `episodes_with_a_fall` (the share with at least one), `seconds_down_per_episode`, and where
    the player has a get-up skill `getups_started_per_episode` and `getups_completed_per_episode`; {} for
    episodes without fall counts."""
    if "events/falls" not in finals[0]:
        return {}
    falls = np.array([f["events/falls"] for f in finals])
    out = {"falls": int(round(falls.sum())), "falls_per_episode": float(falls.mean()),
           "episodes_with_a_fall": float(np.mean(falls > 0)),
           "seconds_down_per_episode": float(np.mean([f["events/seconds_down"] for f in finals]))}
    if "events/getups_started" in finals[0]:
        for kind in ("started", "completed"):
            out[f"getups_{kind}_per_episode"] = float(np.mean([f[f"events/getups_{kind}"] for f in finals]))
    return out


def summarize(finals: list[dict], confined: bool) -> dict:
    """Task metrics over finished episodes (`finals`: each episode's statistics at its last step)."""
    out = {"episodes": len(finals), "episode_return": float(np.mean([f["return"] for f in finals])),
           "episode_length_steps": float(np.mean([f["length"] for f in finals]))}
    terms = sorted(k for k in finals[0] if k.startswith("reward/"))
    out["reward_terms"] = {k[7:]: float(np.mean([f[k] for f in finals])) for k in terms}
    if "elliptic_cone" in finals[0]:  # the share of robots that drew elliptic friction cones
        out["elliptic_cone_share"] = float(np.mean([f["elliptic_cone"] for f in finals]))
    out.update(fall_figures(finals))
    if "tracking_error_mps" in finals[0]:  # velocity tracking: mean |commanded - actual| planar base velocity
        out["tracking_error_mps"] = float(np.mean([f["tracking_error_mps"] for f in finals]))
    if "goals_for" in finals[0]:  # soccer, from the learner's side against the evaluation opponent
        goals_for = np.array([f["goals_for"] for f in finals])
        goals_against = np.array([f["goals_against"] for f in finals])
        out.update(goals_for_per_episode=float(goals_for.mean()), goals_against_per_episode=float(goals_against.mean()),
                   win_rate=float((goals_for > goals_against).mean()))
    errors = estimate_errors(finals)
    if errors:
        out["estimate_rms_m"] = errors
    if confined:
        success = np.array([f["success"] > 0 for f in finals])
        out["success_rate"] = float(success.mean())
        out["success_rate_ci95"] = wilson_interval(int(success.sum()), len(success))
        out["time_to_goal_s"] = float(np.mean([f["time_to_goal_s"] for f, s in zip(finals, success) if s])) \
            if success.any() else None
        out["collisions_per_episode"] = float(np.mean([f["collisions"] for f in finals]))
        out["collisions_per_success"] = float(np.mean([f["collisions"] for f, s in zip(finals, success) if s])) \
            if success.any() else None
        out["final_distance_m"] = float(np.mean([f["final_distance_m"] for f in finals]))
        if "overspeed_mps" in finals[0]:  # the speed limit: mean speed and mean excess over the limit, per step
            out["mean_speed_mps"] = float(np.mean([f["mean_speed_mps"] for f in finals]))
            out["overspeed_mps"] = float(np.mean([f["overspeed_mps"] for f in finals]))
    return out


def paired_goal_ratio(goals, baseline_goals, resamples: int = 2000, seed: int = 0) -> dict:
    """A player's goals over a baseline's in the same games (`goals[i]` and `baseline_goals[i]`: game i, started
    alike): the ratio of their sums, with a 95% bootstrap interval that resamples whole games, both players'
    together (deterministic for a `seed`); the ratio and interval are None when the baseline scored nothing."""
    goals, baseline_goals = np.asarray(goals, float), np.asarray(baseline_goals, float)
    if goals.shape != baseline_goals.shape or goals.ndim != 1 or len(goals) == 0:
        raise ValueError(f"paired goals need one count per game for both players: got {goals.shape} and "
                         f"{baseline_goals.shape}")
    out = {"games": len(goals), "goals": int(goals.sum()), "baseline_goals": int(baseline_goals.sum()),
           "ratio": None, "ratio_ci95": None}
    if baseline_goals.sum() == 0:
        return out
    games = np.random.default_rng(seed).integers(0, len(goals), (resamples, len(goals)))
    mine, theirs = goals[games].sum(1), baseline_goals[games].sum(1)
    ratios = mine[theirs > 0] / theirs[theirs > 0]
    out["ratio"] = round(float(goals.sum() / baseline_goals.sum()), 4)
    out["ratio_ci95"] = [round(float(q), 4) for q in np.percentile(ratios, [2.5, 97.5])]
    return out


def wilson_interval(successes: int, trials: int, z: float = 1.96) -> list[float]:
    """The Wilson score interval of a success rate at `z` standard errors (1.96: 95%), rounded to 4 decimals
    (sound at 0 and at 100%, unlike the normal one); [0, 1] without trials."""
    if trials == 0:
        return [0.0, 1.0]
    interval = binomtest(successes, trials).proportion_ci(confidence_level=1 - 2 * norm.sf(z), method="wilson")
    return [round(float(interval.low), 4), round(float(interval.high), 4)]


def confined_eval_config(env_config, difficulty: int, episodes: int, world_seed: int | None):
    """The env config of a fixed confined evaluation: `episodes` held-out worlds of one difficulty (seed
    `world_seed`, by default the training seed + HELD_OUT_SEED_OFFSET), one episode per world, no curriculum, whole
    episodes (no stall timeout)."""
    seed = env_config.world_seed + HELD_OUT_SEED_OFFSET if world_seed is None else world_seed
    return whole_episodes(env_config, world_seed=seed, num_worlds=episodes, difficulties=(difficulty,),
                          curriculum=False)


def one_tile_each(first: int, count: int, tiles: int) -> dict:
    """Carry of evaluation episodes first..first+count: episode k plays tile k (mod the number of tiles)."""
    return level_carry(np.zeros(count), np.arange(first, first + count) % tiles)


def state_player_game(config):
    """The held-out game of the state soccer run with `config`, its features true (a pilot trained on estimate
    errors plays without them): what a student is compared with in the same games."""
    env = held_out(config.task, config.env)
    if getattr(env, "estimate_noise", None) is not None:
        env = dataclasses.replace(env, estimate_noise=dataclasses.replace(env.estimate_noise, enabled=False))
    return build_env(dataclasses.replace(config, env=env))


def mjx_cone_envs(env) -> dict[float, object]:
    """The environments an MJX evaluation runs, keyed by the friction-cone draw whose episodes each serves (0: the
    model's own cone, 1: elliptic). Native MuJoCo gives each robot the cone its randomisation draws
    (`RandomizationConfig.elliptic_share`); MJX compiles one cone into its programs, so where a pyramidal model draws
    elliptic cones for some robots, the episodes run once per cone and each keeps the run of its own draw."""
    randomization = getattr(env.config, "randomization", None)
    share = getattr(randomization, "elliptic_share", None)
    elliptic = int(mujoco.mjtCone.mjCONE_ELLIPTIC)
    if not getattr(randomization, "enabled", False) or not share or int(env.mj_model.opt.cone) == elliptic:
        return {0.0: env}
    other = env.with_cone(elliptic)
    return {1.0: other} if share >= 1 else {0.0: env, 1.0: other}


def evaluate(env, policy, episodes: int, seed: int, physics: str = "mjx", num_envs: int = 16,
             threads: int | None = None, progress: bool = True, per_world: bool = False,
             probe: list | None = None, env_args: tuple = ()) -> list[dict]:
    """Run the deterministic policy for exactly `episodes` episodes, each to its end: `num_envs` environments
    at a time, each contributing its first episode only (counting the first episodes to finish would favour
    short ones, i.e. falls). The episodes' reset keys depend on `seed` and `num_envs` only, not on the physics
    engine: both engines start the same episodes, with the same robots (in MJX, each with the friction cone it drew:
    `mjx_cone_envs`). Each episode's statistics hold `elliptic_cone` (1: its robot drew an elliptic cone) where the
    task draws cones. per_world (confined tasks): episode k plays world k of the terrain (see
    `confined_eval_config`). `probe`, a list, receives (policy features, privileged state, episode ids) of every 10th
    step of the episodes (see `latent_probe`). `env_args` go to every step (a soccer opponent)."""
    runs = mjx_cone_envs(env) if physics == "mjx" else {None: env}
    if len(runs) == 1:
        return _episodes(next(iter(runs.values())), policy, episodes, seed, physics, num_envs, threads, progress,
                         per_world, probe, env_args, None)
    finals = {drawn: _episodes(run, policy, episodes, seed, physics, num_envs, threads, progress, per_world, probe,
                               env_args, drawn) for drawn, run in runs.items()}
    first = finals[0.0]
    return [finals[f["elliptic_cone"]][k] for k, f in enumerate(first)]


def _episodes(env, policy, episodes: int, seed: int, physics: str, num_envs: int, threads: int | None,
              progress: bool, per_world: bool, probe: list | None, env_args: tuple, cone: float | None) -> list[dict]:
    """`evaluate` in one engine with one model; `cone` (a friction-cone draw, or None: any): the episodes this run
    serves, the only ones it probes."""
    num_envs = min(num_envs, episodes)
    vector = VectorEnv.of(env, num_envs, physics, threads)
    finals: list[dict] = []
    label = physics if cone is None else f"{physics}, {'elliptic' if cone else 'own'} cones"
    bar = tqdm(total=episodes, desc=f"eval ({label})", unit="episode", disable=not progress)
    for first in range(0, episodes, num_envs):
        carry = one_tile_each(first, num_envs, env.terrain.num_tiles) if per_world else None
        batch = vector.reset(jax.random.fold_in(jax.random.PRNGKey(seed), first), carry)
        drawn = _cone_draws(batch.state.info, num_envs)
        served = np.ones(num_envs, bool) if cone is None or drawn is None else drawn == cone
        policy.reset()
        obs, pending = batch.state.obs, np.ones(num_envs, bool)
        pending[episodes - first:] = False  # the last round may need fewer environments
        chunk: dict[int, dict] = {}
        steps = 0
        while pending.any():
            if probe is not None and steps % 10 == 0 and getattr(policy, "features", None) is not None:
                features = policy.features({k: np.asarray(v) for k, v in obs.items()})
                probed = pending & served
                if features is not None and probed.any():
                    probe.append((features[probed], np.asarray(obs["privileged_state"])[probed],
                                  first + np.flatnonzero(probed)))  # the episodes' ids
            steps += 1
            batch, result = vector.step(batch, jax.numpy.asarray(policy.act(actor_observation(obs, policy.inputs))),
                                        *env_args)
            obs = result.obs
            ended = np.asarray(result.done) & pending
            policy.reset(np.asarray(result.done))
            if ended.any():
                stats = {k: np.asarray(v) for k, v in result.finished.items()}
                for i in np.flatnonzero(ended):
                    chunk[i] = {k: float(v[i]) for k, v in stats.items()}
                    if drawn is not None:
                        chunk[i]["elliptic_cone"] = float(drawn[i])
                pending &= ~ended
                bar.update(int(ended.sum()))
        finals.extend(chunk[i] for i in sorted(chunk))
    bar.close()
    return finals


def _cone_draws(info: dict, num_envs: int) -> np.ndarray | None:
    """Each environment's friction-cone draw (1: elliptic) in a reset batch's `info`, or None where the task draws
    none."""
    dr = info.get("dr") if isinstance(info, dict) else None
    if not isinstance(dr, dict) or "elliptic" not in dr:
        return None
    return np.broadcast_to(np.asarray(dr["elliptic"], np.float32), (num_envs,)).copy()


def latent_probe(samples: list, layout: dict) -> float | None:
    """Linear-probe R^2 (policies.probe) from the policy's features to the randomised dynamics over the
    samples `evaluate` collected; None without samples or without randomisation."""
    slices = privileged_slices(layout)
    if not samples or not slices:
        return None
    features, privileged, episodes = (np.concatenate(parts) for parts in zip(*samples))
    targets = np.concatenate([privileged[:, s] for s in slices], axis=1)
    return probe_r2(features, targets, episodes)
