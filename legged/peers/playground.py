#!/usr/bin/env python3
"""MuJoCo Playground's Go1 joystick environments timed on this machine: the peer of `legged bench env`.

Run it with the peer's Python (legged.peers.setup_playground.sh builds that environment offline); it
imports nothing from legged. For each environment name and batch size it compiles jit(vmap(step)) with
zero actions (both programs: from the reset's state and from a stepped one) and prints one JSON line: env, batch,
env_steps_per_s, compile_s, ctrl_dt, sim_dt.

    $PEER_DIR/venv/bin/python playground.py 64,256 --envs Go1JoystickRoughTerrain --seconds 3
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path


def main() -> int:
    parser = argparse.ArgumentParser(description="time MuJoCo Playground Go1 envs (MJX)")
    parser.add_argument("batches", help="comma-separated batch sizes")
    parser.add_argument("--envs", default="Go1JoystickRoughTerrain", help="comma-separated Playground env names")
    parser.add_argument("--seconds", type=float, default=3.0, help="timed seconds per (env, batch)")
    parser.add_argument("--menagerie", default=str(Path(os.environ.get("PEER_DIR", Path.home() / ".cache/legged-peer"))
                                                   / "assets" / "mujoco_menagerie"),
                        help="folder holding unitree_go1/ (so that Playground does not clone Menagerie)")
    args = parser.parse_args()
    batches = [int(b) for b in args.batches.split(",") if b.strip()]

    import jax
    import jax.numpy as jnp
    from mujoco_playground._src import mjx_env

    mjx_env.MENAGERIE_PATH = Path(args.menagerie)  # offline: read the Go1 assets from a local copy
    from mujoco_playground import registry

    for name in args.envs.split(","):
        config = registry.get_default_config(name)
        config.impl = "jax"  # Playground's default (warp) needs a CUDA GPU
        env = registry.load(name, config=config)
        reset, step = jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step))
        for batch in batches:
            print(f"[playground] {name}: batch {batch}: compiling", file=sys.stderr, flush=True)
            state = reset(jax.random.split(jax.random.PRNGKey(0), batch))
            action = jnp.zeros((batch, env.action_size))
            # two calls before timing: the first step's output state differs in type from the reset's (Playground's
            # info fields), so the second call compiles step again; timing from it measured that compilation
            t0 = time.perf_counter()
            for _ in range(2):
                state = jax.block_until_ready(step(state, action))
            compile_s = time.perf_counter() - t0
            calls, t0 = 0, time.perf_counter()
            while time.perf_counter() - t0 < args.seconds:
                state = step(state, action)
                calls += 1
                if calls % 4 == 0:
                    jax.block_until_ready(state)
            jax.block_until_ready(state)
            elapsed = time.perf_counter() - t0
            print(json.dumps({"env": name, "batch": batch, "env_steps_per_s": round(calls * batch / elapsed, 1),
                              "compile_s": round(compile_s, 2), "ctrl_dt": float(env.dt),
                              "sim_dt": float(env.sim_dt)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
