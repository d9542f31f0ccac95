"""Soccer throughput: MJX env-steps per second for 1v1 and 2v2, with and without the head cameras, at
several batch sizes, beside native MuJoCo on the same model and dm_control's soccer (the peer) in the
same run."""

from __future__ import annotations

import dataclasses
import sys
import time

import jax
import jax.numpy as jnp

from legged.bench import native_steps_per_s, time_calls
from legged.envs import make

TASK_OF_TEAM_SIZE = {1: "soccer-1v1", 2: "soccer-2v2"}
PEER_BATCH = 1
"""dm_control environments timed per setting: its 'batch' is a Python loop, so its rate does not depend on it."""


def soccer_env(players_per_team: int, camera: bool):
    """The soccer env of a team size, with or without every agent's head camera in its observations."""
    env = make(TASK_OF_TEAM_SIZE[players_per_team])
    return type(env)(dataclasses.replace(env.config, vision=camera)) if camera else env


def bench_soccer(team_sizes=(1, 2), cameras=(False, True), batches=(1, 16), seconds: float = 3.0,
                 peer: bool = True, peer_steps: int = 20, progress=None) -> list[dict]:
    """One record per (team size, camera, batch): ours, native MuJoCo's and (with `peer`) dm_control's
    BoxHead soccer at the same team size and camera setting, measured once per setting on one env (its
    batch would be a Python loop over envs) and compared with every batch size."""
    say = progress or (lambda msg: None)
    records = []
    for team_size in team_sizes:
        for camera in cameras:
            env = soccer_env(team_size, camera)
            name = TASK_OF_TEAM_SIZE[team_size] + ("+camera" if camera else "")
            native = native_steps_per_s(env, min(seconds, 2.0))
            peer_record = None
            if peer:  # dm_control steps its envs one after another: one measurement serves every batch size
                from legged.soccer.peer_dm_control import measure_dm_control_soccer

                say(f"{name}: dm_control peer ({PEER_BATCH} env, {peer_steps} steps)")
                cam_size = (env.config.camera.width, env.config.camera.height)
                peer_record = measure_dm_control_soccer(team_size, camera, PEER_BATCH, steps=peer_steps,
                                                        camera_size=cam_size)
            reset, step = jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step))
            for batch in batches:
                say(f"{name}: batch {batch}: compiling")
                t0 = time.perf_counter()
                state = jax.block_until_ready(reset(jax.random.split(jax.random.PRNGKey(0), batch)))
                reset_s = time.perf_counter() - t0
                action = jnp.zeros((batch, env.n_agents, env.action_size))
                t0 = time.perf_counter()
                compiled = step.lower(state, action).compile()
                compile_s = time.perf_counter() - t0
                say(f"{name}: batch {batch}: timing for {seconds:.0f} s")
                state, calls, elapsed = time_calls(lambda s: compiled(s, action), compiled(state, action), seconds)
                rate = calls * batch / elapsed
                record = {"task": name, "team_size": team_size, "n_agents": env.n_agents, "camera": camera,
                          "camera_size": [env.config.camera.width, env.config.camera.height] if camera else None,
                          "batch": batch, "env_steps_per_s": round(rate, 1),
                          "agent_steps_per_s": round(rate * env.n_agents, 1), "compile_s": round(compile_s, 2),
                          "reset_compile_s": round(reset_s, 2), "native_steps_per_s": round(native, 1),
                          "ctrl_dt": env.dt, "sim_dt": env.config.sim_dt, "backend": jax.default_backend(),
                          "finite": bool(jnp.all(jnp.isfinite(state.pipeline_state.qpos)))}
                if peer_record is not None:
                    p = peer_record
                    record.update(peer=p["peer"], peer_env_steps_per_s=round(p["env_steps_per_s"], 2),
                                  peer_batch=PEER_BATCH, peer_steps_timed=p["steps"],
                                  ratio_vs_peer=round(rate / p["env_steps_per_s"], 2))
                records.append(record)
    return records


def print_soccer_table(records: list[dict], file=sys.stdout) -> None:
    """Human-readable table of soccer benchmark records."""
    print(f"{'task':20s} {'batch':>6s} {'env steps/s':>12s} {'compile s':>10s} {'native/s':>9s} "
          f"{'peer/s':>9s} {'ratio':>8s}", file=file)
    for r in records:
        print(f"{r['task']:20s} {r['batch']:6d} {r['env_steps_per_s']:12.1f} {r['compile_s']:10.1f} "
              f"{r['native_steps_per_s']:9.0f} {r.get('peer_env_steps_per_s', float('nan')):9.2f} "
              f"{r.get('ratio_vs_peer', float('nan')):8.2f}", file=file)
