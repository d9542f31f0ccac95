"""Throughput benchmark: MJX env steps per second at several batch sizes, beside native MuJoCo and a peer."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from legged.envs import make


def time_calls(fn, state, seconds: float) -> tuple[object, int, float]:
    """Call fn repeatedly for about `seconds`; returns the last state, calls made and elapsed time."""
    calls, t0 = 0, time.perf_counter()
    while True:
        state = fn(state)
        calls += 1
        if calls % 4 == 0:
            jax.block_until_ready(state)
            if time.perf_counter() - t0 >= seconds:
                break
    jax.block_until_ready(state)
    return state, calls, time.perf_counter() - t0


def native_steps_per_s(env, seconds: float) -> float:
    """Control steps per second of native MuJoCo stepping the same model at the same control rate."""
    model = env.mj_model
    data = mujoco.MjData(model)
    state = jax.jit(env.reset)(jax.random.PRNGKey(0))
    data.qpos[:] = np.asarray(state.pipeline_state.qpos)
    data.ctrl[:] = np.asarray(state.pipeline_state.ctrl)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(env.n_substeps):
            mujoco.mj_step(model, data)
        steps += 1
    return steps / (time.perf_counter() - t0)


def bench_env(task: str, batches: list[int], seconds: float = 3.0, seed: int = 0, progress=None) -> list[dict]:
    """One record per batch size: env_steps_per_s, compile_s, native_steps_per_s, health of the batch."""
    env = make(task)
    native = native_steps_per_s(env, seconds)
    reset, step = jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step))
    records = []
    for batch in batches:
        if progress:
            progress(f"{task}: batch {batch}: compiling")
        keys = jax.random.split(jax.random.PRNGKey(seed), batch)
        t0 = time.perf_counter()
        state = reset(keys)
        jax.block_until_ready(state)
        reset_s = time.perf_counter() - t0
        action = jnp.zeros((batch, env.action_size))
        t0 = time.perf_counter()
        compiled = step.lower(state, action).compile()
        compile_s = time.perf_counter() - t0
        state = compiled(state, action)
        if progress:
            progress(f"{task}: batch {batch}: timing for {seconds:.0f} s")
        state, calls, elapsed = time_calls(lambda s: compiled(s, action), state, seconds)
        records.append({
            "task": task, "batch": batch, "env_steps_per_s": round(calls * batch / elapsed, 1),
            "compile_s": round(compile_s, 2), "reset_compile_s": round(reset_s, 2),
            "native_steps_per_s": round(native, 1), "ctrl_dt": env.dt, "sim_dt": env.config.sim_dt,
            "backend": jax.default_backend(), "finite": bool(jnp.all(jnp.isfinite(state.pipeline_state.qpos))),
            "mean_base_height": round(float(jnp.mean(state.metrics["base_height"])), 4),
        })
    return records


def bench_peer(python: str, script: str, batches: list[int], seconds: float) -> dict[int, dict]:
    """Run MuJoCo Playground's Go1 rough-terrain benchmark (../shared/peers) and index it by batch."""
    cmd = [python, script, ",".join(map(str, batches)), "--envs", "Go1JoystickRoughTerrain",
           "--seconds", str(seconds)]
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise RuntimeError(f"peer benchmark failed ({' '.join(cmd)}):\n{out.stderr[-2000:]}")
    rows = [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]
    return {r["batch"]: r for r in rows}


def attach_peer(records: list[dict], peer: dict[int, dict]) -> None:
    """Add the peer's figure and our/peer ratio to each record measured at a batch the peer also ran."""
    for r in records:
        p = peer.get(r["batch"])
        if p:
            r["peer"] = p["env"]
            r["peer_env_steps_per_s"] = p["env_steps_per_s"]
            r["ratio_vs_peer"] = round(r["env_steps_per_s"] / p["env_steps_per_s"], 3)


def print_table(records: list[dict], file=sys.stdout) -> None:
    """Human-readable table of benchmark records."""
    print(f"{'task':22s} {'batch':>6s} {'env steps/s':>12s} {'compile s':>10s} {'native/s':>9s} {'peer/s':>9s} {'ratio':>6s}",
          file=file)
    for r in records:
        print(f"{r['task']:22s} {r['batch']:6d} {r['env_steps_per_s']:12.0f} {r['compile_s']:10.1f} "
              f"{r['native_steps_per_s']:9.0f} {r.get('peer_env_steps_per_s', float('nan')):9.0f} "
              f"{r.get('ratio_vs_peer', float('nan')):6.2f}", file=file)
