"""`legged eval`: a trained policy on held-out worlds, in MJX or in native MuJoCo, as task metrics."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np
from tqdm import tqdm

from legged.envs.confined import ConfinedConfig
from legged.envs.native import NativeRunner
from legged.envs.vector import VectorEnv
from policies.policy_io import actor_observation

HELD_OUT_SEED_OFFSET = 1_000_003
"""Evaluation worlds use world_seed + this: never the worlds the policy trained on."""


def held_out(env_config):
    """The env config with held-out worlds (confined tasks) and no time-limit change."""
    if isinstance(env_config, ConfinedConfig):
        return dataclasses.replace(env_config, world_seed=env_config.world_seed + HELD_OUT_SEED_OFFSET)
    return env_config


def summarize(finals: list[dict], confined: bool) -> dict:
    """Task metrics over finished episodes (`finals`: each episode's statistics at its last step)."""
    out = {"episodes": len(finals), "episode_return": float(np.mean([f["return"] for f in finals])),
           "episode_length_steps": float(np.mean([f["length"] for f in finals]))}
    terms = sorted(k for k in finals[0] if k.startswith("reward/"))
    out["reward_terms"] = {k[7:]: float(np.mean([f[k] for f in finals])) for k in terms}
    if "goals_for" in finals[0]:  # soccer, from the learner's side against the evaluation opponent
        goals_for = np.array([f["goals_for"] for f in finals])
        goals_against = np.array([f["goals_against"] for f in finals])
        out.update(goals_for_per_episode=float(goals_for.mean()), goals_against_per_episode=float(goals_against.mean()),
                   win_rate=float((goals_for > goals_against).mean()),
                   fall_rate=float(np.mean([f["fell"] > 0 for f in finals])))
    if confined:
        success = np.array([f["success"] > 0 for f in finals])
        out["success_rate"] = float(success.mean())
        out["time_to_goal_s"] = float(np.mean([f["time_to_goal_s"] for f, s in zip(finals, success) if s])) \
            if success.any() else None
        out["collisions_per_episode"] = float(np.mean([f["collisions"] for f in finals]))
        out["final_distance_m"] = float(np.mean([f["final_distance_m"] for f in finals]))
    return out


def evaluate_mjx(env, policy, episodes: int, seed: int, num_envs: int = 16, progress: bool = True) -> list[dict]:
    """Run the policy in `num_envs` MJX environments until `episodes` episodes have finished."""
    vector = VectorEnv.of(env, min(num_envs, episodes))
    batch = vector.reset(jax.random.PRNGKey(seed))
    obs, finals = batch.state.obs, []
    bar = tqdm(total=episodes, desc="eval (MJX)", unit="episode", disable=not progress)
    while len(finals) < episodes:
        batch, result = vector.step(batch, policy.act(actor_observation(obs)))
        obs = result.obs
        done = np.asarray(result.done)
        for i in np.flatnonzero(done)[: episodes - len(finals)]:
            finals.append({k: float(np.asarray(v)[i]) for k, v in result.finished.items()})
            bar.update()
    bar.close()
    return finals


def evaluate_native(env, policy, episodes: int, seed: int, progress: bool = True) -> list[dict]:
    """Run the policy with native MuJoCo physics (sim-to-sim), one episode after another."""
    if not hasattr(env, "transition") or hasattr(env, "game"):
        raise ValueError("--native is not available for the soccer tasks: evaluate them in MJX, or step the game "
                         "natively with legged.soccer.parallel_env.SoccerParallelEnv (PettingZoo)")
    runner, finals = NativeRunner(env), []
    keys = jax.random.split(jax.random.PRNGKey(seed), episodes)
    for k in tqdm(range(episodes), desc="eval (native MuJoCo)", unit="episode", disable=not progress):
        state = runner.reset(keys[k])
        sums = {"return": 0.0, "length": 0.0}
        while True:
            state = runner.step(policy.act(np.asarray(state.obs["state"])[None])[0])
            sums["return"] += float(state.reward)
            sums["length"] += 1.0
            for name, value in state.metrics.items():
                if name.startswith("reward/"):
                    sums[name] = sums.get(name, 0.0) + float(value)
            if float(state.done) > 0:
                break
        finals.append({**sums, **{n: float(v) for n, v in state.metrics.items() if not n.startswith("reward/")}})
    return finals
