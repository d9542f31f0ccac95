"""Training with Brax PPO (all in JAX, on every local device through pmap) into a run directory.

Brax's own AutoResetWrapper rewinds a finished environment to its first physics state and observation but
keeps the rest of its `info` (our step counter, last action, world tile, randomisation), so after the
first time-out every episode would end after one step. `FullResetWrapper` resets finished environments
completely instead (a fresh `reset` with a new key), keeping only the episode bookkeeping of Brax's
EpisodeWrapper for the transition that ended.

Resume: Brax's `ppo.train` accepts the normaliser, policy and value parameters to start from but not the
optimiser state. `OptimizerStateTap` fills that gap: it watches the training state at the one place
where `ppo.train` hands it over outside of compiled code (its `_strip_weak_type` call around every
training epoch, brax 0.14.2), so checkpoints carry the Adam moments and the adaptive-KL learning rate,
and a resumed run starts from them instead of fresh ones.
"""

from __future__ import annotations

import contextlib
import math
import time

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import Env, State, Wrapper
from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper
from brax.training.agents.ppo import train as brax_ppo
from tqdm import tqdm

from legged.envs.physics import select_envs
from policies.brax_networks import network_factory, params_template
from policies.checkpoints import (BRAX_SUFFIX as CHECKPOINT_SUFFIX, encode_brax_checkpoint as encode_checkpoint, fill,
                                  load_brax_checkpoint as load_checkpoint)
from policies.config import ConfigError, TrainConfig
from policies.run_dir import RunDir, TrainingDiverged, check_compatible


def check_devices(config: TrainConfig) -> None:
    """Brax PPO splits the environments over all devices (of every process): the count must divide evenly."""
    devices = jax.device_count()
    if config.num_envs % devices:
        raise ConfigError(f"num_envs {config.num_envs} is not divisible by the {devices} JAX devices")
    if config.num_envs % config.ppo.num_mini_batches:
        raise ConfigError(f"num_envs {config.num_envs} must be divisible by ppo.num_mini_batches "
                          f"{config.ppo.num_mini_batches} for Brax PPO")


_EPISODE_KEYS = ("episode_metrics", "episode_done", "truncation")
"""Info entries of Brax's EpisodeWrapper that describe the transition that just ended: kept on reset."""


class FullResetWrapper(Wrapper):
    """Batched auto-reset that calls the environment's own reset for finished environments."""

    def reset(self, rng):
        state = self.env.reset(rng)
        state.info["reset_key"] = jax.vmap(lambda k: jax.random.fold_in(k, 1))(rng)
        return state

    def step(self, state, action):
        state = self.env.step(state, action)
        split = jax.vmap(jax.random.split)(state.info["reset_key"])
        done = state.done > 0

        def fresh():
            new = self.env.reset(split[:, 0])
            return new.replace(info={**new.info, **{k: state.info[k] for k in _EPISODE_KEYS},
                                     "reset_key": split[:, 1]})

        kept = state.replace(info={**state.info, "reset_key": split[:, 1]})
        new = jax.lax.cond(done.any(), fresh, lambda: kept)
        return select_envs(done, new.replace(done=state.done, reward=state.reward, metrics=state.metrics), kept)


class UnusedEvalEnv(Env):
    """Stands in for Brax's evaluation environment. `ppo.train` builds its Evaluator, which compiles a
    128-environment reset at once, even with run_evals=False (about 30 s of compilation on a CPU for an
    MJX env); evaluations never run here (`legged eval` does that), so this env's trivial reset is all
    that is compiled."""

    def reset(self, rng):
        zero = jnp.zeros(())
        return State(pipeline_state=None, obs={"state": jnp.zeros(1)}, reward=zero, done=zero, metrics={}, info={})

    def step(self, state, action):
        raise RuntimeError("the stand-in evaluation environment is never stepped (run_evals=False)")

    @property
    def observation_size(self):
        return {"state": (1,)}

    @property
    def action_size(self) -> int:
        return 1

    @property
    def backend(self) -> str:
        return "none"


def wrap_for_training(env, episode_length: int, action_repeat: int, randomization_fn=None):
    """Brax PPO's `wrap_env_fn`: episode bookkeeping, vmap, and full resets (see module docstring)."""
    if randomization_fn is not None:
        raise ConfigError("Brax's randomization_fn is not used: the environments randomise themselves")
    return FullResetWrapper(VmapWrapper(EpisodeWrapper(env, episode_length, action_repeat)))


class OptimizerStateTap:
    """Reads (and on resume, replaces) the optimiser state inside Brax's `ppo.train` (module docstring)."""

    def __init__(self, restore=None):
        self.restore = restore
        """Leaves of the optimiser state to start from (host arrays), or None for Brax's fresh one."""
        self.latest = None
        """Optimiser state after the last training epoch (host arrays, first device's copy)."""

    def _see(self, tree):
        if not (isinstance(tree, tuple) and isinstance(tree[0], brax_ppo.TrainingState)):
            return tree
        state = tree[0]
        if len(tree) == 2 and self.restore is not None:  # the first epoch's input: put the saved state in
            fresh = jax.tree_util.tree_map(lambda x: x[0], state.optimizer_state)
            saved = fill(fresh, self.restore, "optimiser state", "the checkpoint")
            devices = jax.local_devices()[:jax.tree_util.tree_leaves(state.params)[0].shape[0]]
            tree = (state.replace(optimizer_state=jax.device_put_replicated(saved, devices)),) + tree[1:]
            self.restore = None
        elif len(tree) == 3:  # an epoch's output
            self.latest = jax.device_get(jax.tree_util.tree_map(lambda x: x[0], state.optimizer_state))
        return tree

    @contextlib.contextmanager
    def attached(self):
        """Hook into `ppo.train` for the duration of the block."""
        original = brax_ppo._strip_weak_type
        brax_ppo._strip_weak_type = lambda tree: original(self._see(tree))
        try:
            yield self
        finally:
            brax_ppo._strip_weak_type = original


def train_brax(env, config: TrainConfig, run: RunDir, resume: bool = False, progress: bool = True) -> dict:
    """Train (or continue) `env` with Brax PPO; returns the last metrics record."""
    ppo = config.ppo
    obs_sizes = env.observation_dims()
    start_step, restore, tap = 0, None, OptimizerStateTap()
    if resume:
        path = run.latest_checkpoint()
        payload = load_checkpoint(path)
        check_compatible(payload["obs_sizes"], payload["num_actions"], env, path)
        start_step = payload["step"]
        restore = fill(params_template(config, obs_sizes, env.action_size), payload["params_leaves"], "parameters", path)
        tap.restore = payload["optimizer_leaves"]
        if start_step >= config.timesteps:
            records = run.metrics()
            return records[-1] if records else {}
        run.forget_after(start_step)  # a killed run logged past its checkpoint; those reports come again
    per_iteration = config.num_envs * ppo.num_steps_per_env
    per_report = per_iteration * config.checkpoint_every
    remaining = max(config.timesteps - start_step, per_iteration)
    reports = max(math.ceil(remaining / per_report), 1)
    bar = tqdm(total=config.timesteps, initial=start_step, unit="step", unit_scale=True,
               desc=f"{config.task} brax", disable=not progress)
    last = {"time": time.perf_counter(), "step": 0, "record": {}}

    def on_progress(step, metrics):
        # Brax calls this with episode statistics (its metrics logger) and, after every epoch, with
        # training losses; one record per episode report, carrying the latest losses.
        if step == 0:
            return
        if "episode/sum_reward" not in metrics:
            last["losses"] = {k.replace("training/", "loss_"): _get(metrics, k) for k in metrics
                              if k.startswith("training/") and "loss" in k}
            last["trained"] = start_step + int(step)
            return
        now = time.perf_counter()
        record = {"step": start_step + int(step), "episode_return": _get(metrics, "episode/sum_reward"),
                  "episode_length": _get(metrics, "episode/length"),
                  "steps_per_s": (step - last["step"]) / max(now - last["time"], 1e-9)}
        record.update({f"episode_{k[8:].replace('/', '_')}": _get(metrics, k) for k in metrics
                       if k.startswith("episode/reward/") or k[8:] in ("success", "fell", "collisions")})
        record.update(last.get("losses", {}))
        run.log(record)
        bar.update(record["step"] - bar.n)
        bar.set_postfix(ret="-" if record["episode_return"] is None else f"{record['episode_return']:.2f}",
                        sps=f"{record['steps_per_s']:.0f}")
        last.update(time=now, step=step, record=record)

    def on_params(step, make_policy, params):
        if step == 0:
            return
        host = jax.device_get(params)
        if not all(np.all(np.isfinite(x)) for x in jax.tree_util.tree_leaves(host)):
            last = run.checkpoints()
            raise TrainingDiverged(f"training diverged before step {start_step + int(step)} (network parameters not "
                                   "finite); nothing was saved after it. "
                                   + (f"The last good checkpoint is {last[-1]}: resume with `legged train --resume "
                                      f"{run.path}`" if last else "No checkpoint was written yet."))
        meta = {"step": start_step + int(step), "obs_sizes": obs_sizes, "num_actions": env.action_size,
                "task": config.task}
        run.write_checkpoint(start_step + int(step), CHECKPOINT_SUFFIX, encode_checkpoint(meta, host, tap.latest))

    try:
        with tap.attached():
            brax_ppo.train(
                environment=env, num_timesteps=remaining, num_envs=config.num_envs,
                episode_length=env.config.episode_steps, unroll_length=ppo.num_steps_per_env,
                batch_size=config.num_envs // ppo.num_mini_batches, num_minibatches=ppo.num_mini_batches,
                num_updates_per_batch=ppo.num_learning_epochs, learning_rate=ppo.learning_rate,
                learning_rate_schedule="ADAPTIVE_KL", desired_kl=ppo.desired_kl, entropy_cost=ppo.entropy_coef,
                discounting=ppo.gamma, gae_lambda=ppo.lam,
                clipping_epsilon=ppo.clip_param, max_grad_norm=ppo.max_grad_norm, normalize_observations=True,
                normalize_observations_std_eps=ppo.obs_std_floor ** 2,
                network_factory=network_factory(config), seed=config.seed + start_step, num_evals=reports + 1,
                run_evals=False, eval_env=UnusedEvalEnv(), num_eval_envs=1, log_training_metrics=True,
                progress_fn=on_progress, policy_params_fn=on_params,
                wrap_env_fn=wrap_for_training,
                restore_params=restore, restore_value_fn=True)
    finally:
        bar.close()
    if last.get("trained", 0) > last["record"].get("step", 0):  # no episode ended since the last record
        last["record"] = {"step": last["trained"], "episode_return": None, "episode_length": None,
                          **last.get("losses", {})}
        run.log(last["record"])
    return last["record"]


def _get(metrics: dict, key: str):
    value = metrics.get(key)
    return None if value is None else float(np.asarray(value))
