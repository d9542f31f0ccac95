"""Starting and resuming training runs (what `legged train` calls); the backends do the training."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import jax

from legged.tasks import task_entry
from policies.config import ConfigError, TrainConfig, apply_overrides
from policies.distributed import Launch, init_jax_processes
from policies.environments import build_env  # looked up when a run starts: tests replace it with a small env
from policies.recipes import task_config
from policies.rsl_backend import train_rsl
from policies.run_dir import RunDir, checkpoint_step
from policies.slim import refuse_slimmed
from policies.soccer.hooks import SoccerHooks, SteeredHooks
from policies.soccer.steered import steered_env
from policies.training_hooks import TrainingHooks


def refuse_pilot(config: TrainConfig) -> None:
    """ConfigError if `config` names a pilot and does not distil by DAgger: a piloted vision student is played
    (eval, view, drill, export) and can learn its estimate by DAgger in the games its pilot steers (the labels
    do not depend on who acts), but PPO and kl would learn corrections the pilot throws away."""
    if config.soccer.pilot and config.algo != "dagger":
        raise ConfigError(f"soccer.pilot={config.soccer.pilot}: a state pilot steers a trained vision student in "
                          f"eval, view, drill and export, and in DAgger (--method dagger); train or distil by "
                          f"{config.algo} without it (--set soccer.pilot=)")


def _train(config: TrainConfig, run: RunDir, resume: bool, progress: bool) -> dict:
    if config.backend == "brax":
        from policies.brax_backend import train_brax  # Brax's PPO takes a second to import: brax runs only

        return train_brax(build_env(config), config, run, resume=resume, progress=progress)
    env, hooks = training_env(config)
    return train_rsl(env, config, run, resume=resume, progress=progress, hooks=hooks)


def training_env(config: TrainConfig) -> tuple:
    """(environment, TrainingHooks) of an rsl run: the task's environment and what its family adds to the loop
    (soccer: opponents; a pilot: its vision student's game, policies.soccer.steered)."""
    if config.soccer.steered_student:
        env = steered_env(config)
        return env, SteeredHooks(config, env)
    env = build_env(config)
    return env, SoccerHooks(config, env) if task_entry(config.task).kind == "soccer" else TrainingHooks()


def _prepare(config: TrainConfig) -> bool:
    """Check the device split before anything is written; True in the process that writes the run."""
    if config.backend == "brax":
        from policies.brax_backend import check_devices  # Brax's PPO takes a second to import: brax runs only

        init_jax_processes()
        check_devices(config)
        return jax.process_index() == 0
    launch = Launch.from_env()
    launch.envs_per_process(config.num_envs)
    return launch.is_main


def start_run(task: str, run_dir: str | None, backend: str = "rsl", num_envs: int | None = None,
              timesteps: int = 1_000_000, seed: int = 0, overrides: list[str] = (), progress: bool = True,
              physics: str = "mjx", threads: int = 0, init_from: str = "", algo: str = "ppo") -> dict:
    """Resolve the config (the task's recipe, then the arguments, then `overrides`; num_envs None: the recipe's or
    TrainConfig's), create the run directory, train; returns the last metrics record."""
    config = task_config(task, backend, num_envs=num_envs, timesteps=timesteps, seed=seed, physics=physics,
                         threads=threads, init_from=init_from, algo=algo)
    config = apply_overrides(config, list(overrides))
    refuse_pilot(config)
    if config.init_from and not (Path(config.init_from) / "config.yaml").is_file():  # only when starting
        raise ConfigError(f"init_from: {config.init_from} is not a run directory (no config.yaml)")
    main = _prepare(config)
    run = RunDir(run_dir or Path("runs") / f"{task}-{time.strftime('%Y%m%d-%H%M%S')}")
    if main:
        run.create(config)
    if progress and main:
        print(f"[train] run directory {run.path}", flush=True)
    try:
        return _train(config, run, resume=False, progress=progress)
    except Exception:
        if main:
            run.discard_unstarted()  # a run that never started must not block the same command's retry
        raise


def resume_run(run_dir: str, progress: bool = True, timesteps: int | None = None, threads: int = 0) -> dict:
    """Continue a run from its last checkpoint with its own config, appending to its metrics. `timesteps`: a new
    total for the run (past its last checkpoint; saved in its config); `threads`: this session's CPU threads."""
    run = RunDir(run_dir)
    config = run.load_config()
    refuse_pilot(config)
    latest = run.latest_checkpoint()
    refuse_slimmed(latest, config.task)  # fail now if there is nothing to resume from
    if timesteps is not None:
        step = checkpoint_step(latest)
        if timesteps <= step:
            raise ConfigError(f"--timesteps {timesteps:,} is not past {run.path}'s last checkpoint (step {step:,}); "
                              f"give the run's new total")
        config = replace(config, timesteps=timesteps)
        run.save_config(config)
    if threads:
        config = replace(config, threads=threads)
    run.clean_stale()
    _prepare(config)
    return _train(config, run, resume=True, progress=progress)
