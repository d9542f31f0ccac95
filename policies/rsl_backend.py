"""Training with rsl-rl's PPO (PyTorch) on the MJX environments, with run directories and resume."""

from __future__ import annotations

import math
import time

import jax
import numpy as np
import psutil
import torch
from rsl_rl.algorithms import PPO, Distillation
from torch.utils.tensorboard import SummaryWriter
from tqdm import tqdm

from legged.envs.native import default_threads
from legged.envs.vector import VectorEnv
from policies.algorithms import (  # noqa: F401 (build_ppo, dummy_observations: re-exports)
    attach_information_bottleneck,
    attach_teacher_kl,
    build_algorithm,
    build_ppo,
    dummy_observations,
    privileged_slices,
)
from policies.checkpoints import load_rsl_checkpoint as load_checkpoint
from policies.checkpoints import save_rsl_checkpoint as save_checkpoint
from policies.config import DISTILL_ALGOS, TrainConfig
from policies.distributed import Launch, init_torch_processes
from policies.latent_models import latent_features
from policies.probe import probe_r2
from policies.rsl_vecenv import RslVecEnv
from policies.run_dir import RunDir, TrainingDiverged, check_compatible
from policies.students import load_teacher, start_student
from policies.training_hooks import TrainingHooks
from policies.warm_start import SourceRun, rollout_statistics, source_levels, warm_start


def _saved_rows(payload: dict | None, key: str, launch, num_envs: int):
    """This process's rows of a checkpoint's per-environment entry `key` (every process's, in rank order), or None
    when there is none or it was saved for another number of environments (they start afresh)."""
    rows = None if payload is None else payload.get(key)
    return None if rows is None or len(rows) != num_envs else launch.own_rows(rows.numpy())


def train_rsl(env, config: TrainConfig, run: RunDir, resume: bool = False, progress: bool = True,
              hooks: TrainingHooks | None = None) -> dict:
    """Train (or continue training) `env` with rsl-rl (PPO or a distillation); returns the last metrics record.

    The loop is the same for every task: what a task family adds (opponents, the game a pilot plays in) comes
    through `hooks` (policies.training_hooks; the defaults add nothing). Under torchrun every process runs this
    with its share of the environments (policies.distributed); only rank 0 logs and writes checkpoints.
    """
    hooks = hooks or TrainingHooks()
    ppo = config.ppo
    launch = Launch.from_env()
    local_envs = launch.envs_per_process(config.num_envs)
    device = init_torch_processes(launch, config.device)
    per_iteration = config.num_envs * ppo.num_steps_per_env
    iterations = math.ceil(config.timesteps / per_iteration)
    payload, iteration, step = None, 0, 0
    obs_sizes = env.observation_dims()
    if resume:
        path = run.latest_checkpoint()
        payload = load_checkpoint(path)
        check_compatible(payload["obs_sizes"], payload["num_actions"], env, path)
        iteration, step = payload["iteration"], payload["step"]
    torch.manual_seed(config.seed + launch.rank)
    threads = config.threads or default_threads()
    if config.physics == "native":
        torch.set_num_threads(threads)
    vector = VectorEnv.of(hooks.played_env(env), local_envs, config.physics, threads)
    key = jax.random.fold_in(jax.random.fold_in(jax.random.PRNGKey(config.seed), iteration), launch.rank)
    hib = config.algo in ("hib", "hib-no-ib")
    levels = _saved_rows(payload, "curriculum_levels", launch, config.num_envs)
    source = SourceRun(config.init_from) if payload is None and config.init_from else None  # a warm start's
    if source is not None:  # a fine-tune of the same task goes on at its source's levels
        levels = _saved_rows({"curriculum_levels": source_levels(source, config.task, config.num_envs)},
                             "curriculum_levels", launch, config.num_envs)
        if levels is not None and progress and launch.is_main:
            print(f"curriculum: from the levels of {config.init_from} (mean {levels.mean():.2f})")
    ramp = (lambda at: min(1.0, at / config.randomization_ramp)) if config.randomization_ramp else None
    first_scale = None  # the first episodes' randomisation scale: the ramp's, or the curriculum's (0 when new)
    if ramp is not None:
        first_scale = ramp(step)
    elif config.randomization_curriculum:
        scales = _saved_rows(payload, "randomization_scales", launch, config.num_envs)
        first_scale = 0.0 if scales is None else scales
    venv = hooks.wrap(RslVecEnv(vector, seed=int(jax.random.randint(key, (), 0, 2**30)), device=device,
                                latent_noise=config.latent.latent_dim if hib else 0, levels=levels,
                                dr_scale=first_scale, dr_step=config.randomization_curriculum))
    if config.random_episode_start:  # episodes end on different iterations
        generator = torch.Generator().manual_seed(config.seed + launch.rank + 7919 * iteration)
        venv.episode_length_buf = torch.randint(0, env.config.episode_steps, (local_envs,), generator=generator)
    hooks.start(venv, payload, iteration, launch.rank)
    alg = start_algorithm(env, config, venv, payload, iteration, launch, device, progress, hooks, source)
    if launch.distributed:
        alg.broadcast_parameters()  # every process starts from rank 0's networks
    writer = SummaryWriter(str(run.path / "tb")) if launch.is_main else None
    record = {}
    bar = tqdm(total=iterations * per_iteration, initial=step, unit="step", unit_scale=True,
               desc=f"{config.task} rsl", disable=not (progress and launch.is_main))
    obs = venv.get_observations()
    alg.train_mode()
    layout = env.observation_layout() if config.algo != "ppo" and hasattr(env, "observation_layout") else None
    if layout is not None and not privileged_slices(layout):  # no randomised dynamics to probe (soccer)
        layout = None
    if resume and launch.is_main:
        run.forget_after(step)
    earlier = run.metrics() if resume else []
    wall0 = time.perf_counter() - ((earlier[-1].get("wall_s") or 0.0) if earlier else 0.0)  # resumed runs go on
    startup = {"startup_s": process_seconds()}  # this process's start-up, on its first record
    clock = time.perf_counter
    saving = 0.0  # seconds the last iteration's record and checkpoint took to write
    try:
        while iteration < iterations:
            t0 = clock()
            physics0 = venv.physics_seconds()
            stepping = 0.0
            reward_sum = torch.zeros((), device=device)
            hooks.before_rollout(venv)
            scale = None if ramp is None else ramp(step)  # the randomisation of this rollout's new episodes
            if scale is not None:
                venv.set_randomization_scale(scale)
            with torch.inference_mode():
                for _ in range(ppo.num_steps_per_env):
                    actions = alg.act(obs)
                    t_env = clock()
                    obs, rewards, dones, extras = venv.step(actions)
                    stepping += clock() - t_env
                    alg.process_env_step(obs, rewards, dones, extras)
                    reward_sum += rewards.mean()
                    hooks.after_step(dones)
                t_update = clock()
                alg.compute_returns(obs)
            diagnostics = {}
            if layout is not None and (iteration + 1) % config.checkpoint_every == 0:
                diagnostics = probe_rollout(alg, layout)
            losses = alg.update()
            timing = _timing(t0, t_update, clock(), stepping, venv.physics_seconds(), physics0, saving)
            extension = getattr(alg, "symmetry", None)
            if hasattr(extension, "means"):  # HIB's information bottleneck, a kl student's pull to its teacher
                diagnostics.update(extension.means())
            if hasattr(extension, "end_iteration"):
                extension.end_iteration()
            diverged = non_finite(losses, alg)
            iteration += 1
            hooks.after_update(alg, iteration)
            spread = launch.spread(alg.save(), device) if launch.distributed else None
            if spread:
                raise TrainingDiverged(f"the {launch.world_size} training processes hold different networks after "
                                       f"update {iteration} (fingerprints differ by {spread:.3g}); nothing was saved "
                                       "after it. A part of the update runs in one process only.")
            step += per_iteration
            elapsed = time.perf_counter() - t0
            record = {"step": step, "iteration": iteration, "episode_return": None, "episode_length": None,
                      **venv.episode_stats.means(),
                      "reward_per_step": float(reward_sum) / ppo.num_steps_per_env,
                      "steps_per_s": per_iteration / elapsed, "wall_s": time.perf_counter() - wall0,
                      "learning_rate": alg.learning_rate,
                      "action_std": float(alg.get_policy().output_std.detach().mean()),
                      **{f"loss_{k}": float(v) for k, v in losses.items() if k != "symmetry"}, **diagnostics,
                      **timing, **hooks.record(venv), **({} if spread is None else {"process_spread": spread}),
                      **({} if scale is None else {"randomization_scale": scale}),
                      **({"randomization_scale": venv.randomization_scales().mean().item()}
                         if config.randomization_curriculum else {}),
                      **startup}
            startup = {}
            bar.update(per_iteration)
            bar.set_postfix(ret=_short(record["episode_return"]), sps=f"{record['steps_per_s']:.0f}")
            if diverged:
                if launch.is_main:
                    run.log(record, writer)
                last = run.checkpoints()
                raise TrainingDiverged(
                    f"training diverged at iteration {iteration} ({diverged}); nothing was saved after it. "
                    + (f"The last good checkpoint is {last[-1]}: resume with `legged train --resume {run.path}`"
                       " (perhaps after lowering ppo.learning_rate in its config.yaml)" if last else
                       "No checkpoint was written yet."))
            t_save = clock()
            checkpoint = iteration % config.checkpoint_every == 0 or iteration == iterations
            # every process takes part in gathering each environment's row; rank 0 saves them all
            levels = venv.curriculum_levels() if checkpoint else None
            levels = None if levels is None else launch.gather_rows(levels, device)
            scales = launch.gather_rows(venv.randomization_scales(), device) if (
                checkpoint and config.randomization_curriculum) else None
            if not launch.is_main:
                continue
            run.log(record, writer)
            if checkpoint:
                save_checkpoint(run, alg, iteration, step, obs_sizes, env.action_size, extra=hooks.saved_state(),
                                curriculum_levels=levels, randomization_scales=scales)
            saving = clock() - t_save
    finally:
        bar.close()
        if writer is not None:
            writer.close()
    return record


def start_algorithm(env, config: TrainConfig, venv, payload: dict | None, iteration: int, launch: Launch,
                    device: str, progress: bool, hooks: TrainingHooks, source: SourceRun | None = None):
    """The run's rsl-rl algorithm (PPO or a distillation) with its networks: a resumed checkpoint's (`payload`),
    a teacher-pulled student's, a warm start's (`source`, config.init_from's run read once; it may roll the
    environments out, through `hooks`, to measure inputs the source run did not have), or new ones."""
    teacher = load_teacher(config, env) if config.algo in DISTILL_ALGOS else None
    alg = build_algorithm(config, venv.get_observations(), venv.num_envs, env.action_size, device, launch,
                          teacher=None if teacher is None else teacher[0])
    if config.algo in ("hib", "hib-no-ib"):
        attach_information_bottleneck(alg, config, env.observation_layout(), seed=config.seed + 7 * iteration)
    if config.algo == "kl":
        attach_teacher_kl(alg, config, *teacher, venv.get_observations(), env.action_size, iteration)
    if payload is not None:
        alg.load(payload["alg"], None, strict=True)
        if isinstance(alg, Distillation):  # its schedule (policies.students.MixedDAgger) goes on, at the config's rate
            alg.num_updates = iteration
            alg.learning_rate = config.distill.learning_rate
            for group in alg.optimizer.param_groups:
                group["lr"] = config.distill.learning_rate
        if launch.is_main:
            torch.set_rng_state(payload["torch_rng"])
    elif teacher is not None:  # kl: a fresh student (or distill.student_init's), pulled towards its teacher
        start_student(alg, config, *teacher)
    elif config.init_from:
        note = warm_start(alg, source or SourceRun(config.init_from), env, venv.get_observations(), config.task,
                          observe=lambda warmed: rollout_statistics(venv, warmed.actor, hooks))
        if progress and launch.is_main:
            print(note)
    return alg


def _timing(start: float, update: float, end: float, stepping: float, physics: float | None,
            physics0: float | None, saving: float) -> dict:
    """Where an iteration's wall time went, in seconds: `time_physics_s` in MuJoCo's C engine (native physics
    only), `time_env_s` in the environment's steps beyond it (the task's transition, observations, rewards,
    resets; on MJX the physics too), `time_policy_s` in the rest of the rollout (the actor's inference, rsl-rl's
    storage, the hooks), `time_update_s` in the returns and the networks' update, and `time_saving_s` in writing
    the PREVIOUS iteration's record and checkpoint (this one's are written after its record)."""
    in_engine = None if physics is None else physics - physics0
    return {"time_physics_s": in_engine, "time_env_s": stepping - (in_engine or 0.0),
            "time_policy_s": update - start - stepping, "time_update_s": end - update, "time_saving_s": saving}


def probe_rollout(alg, layout: dict) -> dict:
    """The linear probe of the policy's latent (policies.probe) on the rollout just collected."""
    steps, envs = alg.storage.observations.batch_size[:2]
    obs = alg.storage.observations.flatten(0, 1)
    features = latent_features(alg.get_policy(), obs)
    if features is None:
        return {}
    targets = torch.cat([obs["privileged_state"][:, s] for s in privileged_slices(layout)], dim=-1)
    environments = np.tile(np.arange(envs), steps)  # fitted on the even environments, scored on the odd
    return {"probe_r2": probe_r2(features.numpy(), targets.numpy(), environments)}


def non_finite(losses: dict, alg) -> str:
    """'' when every loss and parameter is finite, else a short description of what is not."""
    bad = [f"loss_{k}={float(v)}" for k, v in losses.items() if not math.isfinite(float(v))]
    nets = (("actor", alg.actor), ("critic", alg.critic)) if isinstance(alg, PPO) else (("student", alg.student),)
    for name, net in nets:
        if not all(bool(torch.isfinite(p).all()) for p in net.parameters()):
            bad.append(f"{name} parameters not finite")
    return ", ".join(bad)


def process_seconds() -> float:
    """Seconds since this process started (imports, environment build and compilation so far)."""
    return time.time() - psutil.Process().create_time()


def _short(value) -> str:
    return "-" if value is None else f"{value:.2f}"
