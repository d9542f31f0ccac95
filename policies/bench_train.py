"""`legged bench train`: a task's training loop timed part by part, beside bare physics measured in the same run.

A fixed number of rsl-rl PPO iterations of a real run (the task's default config, in a temporary run directory)
records where each iteration's wall time went (policies.rsl_backend: the C engine, the task's transition,
policy inference with rsl-rl's storage, the update, writing records and checkpoints). The first iterations,
which compile the environment's functions, are left out. Then bare physics of the same environment (the task's
model and spawns, random PD targets, nothing else: legged.bench's rollout) runs at the same batch and threads in
the same process, so that the loop's speed is a ratio to the physical limit of these cores; and MuJoCo's own
timers profile a physics step from the states the run ended in.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from legged.bench import bench_rollout, machine, mid_episode_states, physics_profile
from policies.config import apply_overrides
from policies.environments import build_env
from policies.recipes import task_config
from policies.run_dir import RunDir
from policies.training import start_run

PARTS = ("physics", "env", "policy", "update", "saving")
"""The parts of an iteration's wall time, as the loop records them (`time_<part>_s`)."""


def loop_split(records: list[dict], warmup: int, per_iteration: int) -> dict:
    """The loop's speed and its time split over the records after the first `warmup` (metrics.jsonl records of
    one run): env-steps/s, seconds per iteration and each part's share of the loop's wall time."""
    timed = records[warmup:]
    if not timed:
        raise ValueError(f"no iteration after the {warmup} warm-up ones: run more iterations")
    # wall_s is read when a record is made, before it is written: the window holds the timed iterations and the
    # writing of the records before them, which is what their time_saving_s fields hold
    wall = timed[-1]["wall_s"] - records[warmup - 1]["wall_s"] if warmup else timed[-1]["wall_s"]
    parts = {p: sum(r.get(f"time_{p}_s") or 0.0 for r in timed) for p in PARTS}
    if all(r.get("time_physics_s") is None for r in timed):
        parts["physics"] = None  # MJX: the physics is compiled into the environment's step
    out = {"iterations": len(timed), "loop_env_steps_per_s": round(len(timed) * per_iteration / wall, 1),
           "seconds_per_iteration": round(wall / len(timed), 4)}
    for p, seconds in parts.items():
        out[f"{p}_s_per_iteration"] = None if seconds is None else round(seconds / len(timed), 4)
        out[f"{p}_share"] = None if seconds is None else round(seconds / wall, 4)
    return out


def bench_train(task: str, iterations: int = 10, num_envs: int = 1024, threads: int = 2, physics: str = "native",
                overrides: tuple[str, ...] = (), seed: int = 0, warmup: int = 2, rollout_seconds: float = 30.0,
                profile_steps: int = 200, progress=None) -> dict:
    """One record: the loop's env-steps/s and time split (loop_split), bare physics' env-steps/s at the same batch
    and threads with the loop's ratio to it, MuJoCo's profile of a physics step (legged.bench.physics_profile),
    and the machine (CPU model, cores)."""
    if iterations <= warmup:
        raise ValueError(f"iterations ({iterations}) must exceed the warm-up iterations ({warmup}) left out")
    say = progress or (lambda msg: None)
    with tempfile.TemporaryDirectory(prefix="legged-bench-train-") as tmp:
        run_dir = Path(tmp) / "run"
        probe = apply_overrides(task_config(task, num_envs=num_envs, physics=physics), list(overrides))
        per_iteration = num_envs * probe.ppo.num_steps_per_env
        say(f"{task}: {iterations} PPO iterations of {num_envs} environments ({physics}, {threads} threads)")
        start_run(task, str(run_dir), num_envs=num_envs, timesteps=iterations * per_iteration, seed=seed,
                  overrides=[f"checkpoint_every={iterations}", *overrides], progress=False,
                  physics=physics, threads=threads)
        records = RunDir(run_dir).metrics()
    record = {"task": task, "physics": physics, "num_envs": num_envs, "threads": threads,
              "per_iteration": per_iteration, "warmup_iterations": warmup, **loop_split(records, warmup, per_iteration)}
    if physics == "native":
        env = build_env(probe)
        say(f"{task}: bare physics at batch {num_envs} for {rollout_seconds:.0f} s")
        bare = bench_rollout(env, num_envs, rollout_seconds, seed, threads)["env_steps_per_s"]
        record.update(rollout_env_steps_per_s=bare, loop_vs_rollout=round(record["loop_env_steps_per_s"] / bare, 3))
        say(f"{task}: MuJoCo's timers over {profile_steps} physics steps of 8 states")
        record["physics_profile"] = physics_profile(env.native_model(), mid_episode_states(env, 8, seed),
                                                    profile_steps)
    record.update(machine())
    return record


def bench_train_median(task: str, repeats: int = 3, **kwargs) -> dict:
    """bench_train `repeats` times in one process: the record of the run with the median loop-to-physics ratio
    (or loop speed, on MJX), with every run's loop and bare-physics env-steps/s beside it."""
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    runs = [bench_train(task, **kwargs) for _ in range(repeats)]
    key = "loop_vs_rollout" if "loop_vs_rollout" in runs[0] else "loop_env_steps_per_s"
    median = sorted(runs, key=lambda r: r[key])[(repeats - 1) // 2]
    return {**median, "repeats": repeats, "median_of": key,
            "runs": [{k: r.get(k) for k in ("loop_env_steps_per_s", "rollout_env_steps_per_s", "loop_vs_rollout")}
                     for r in runs]}


def print_train_table(records: list[dict]) -> None:
    """`legged bench train`'s table: speed, ratio to bare physics and the time split of each task."""
    for r in records:
        ratio = r.get("loop_vs_rollout")
        print(f"{r['task']} ({r['physics']}, {r['num_envs']} envs, {r['threads']} threads, {r['cpu']}): loop "
              f"{r['loop_env_steps_per_s']:,.0f} env-steps/s" + ("" if ratio is None else
              f", bare physics {r['rollout_env_steps_per_s']:,.0f}, ratio {ratio:.2f}"))
        shares = ", ".join(f"{p} {100 * r[f'{p}_share']:.0f}%" for p in PARTS if r.get(f"{p}_share") is not None)
        print(f"  per iteration {r['seconds_per_iteration']:.2f} s: {shares}")
        prof = r.get("physics_profile")
        if prof:
            print(f"  physics step {prof['step_us']:.0f} us (collision {prof['pos_collision_us']:.0f}, constraint "
                  f"{prof['constraint_us']:.0f}); {prof['contacts']:.1f} contacts, {prof['constraint_rows']:.0f} "
                  f"constraint rows, {prof['solver_iterations']:.1f} solver iterations per step")
