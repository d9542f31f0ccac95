"""`legged demo`: a generated tunnel, an OMPL body-pose plan through it, and Go1 held by its default
controller in MJX and native MuJoCo."""

from __future__ import annotations

import json
import time

import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.native import NativeEnvs
from legged.robots import GO1
from legged.worlds import Terrain, generate_world, write_world


def _engines(env, physics) -> dict:
    """name -> (batched reset from keys, batched step) of each chosen physics engine."""
    out = {}
    if "mjx" in physics:
        out["mjx"] = (jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step)))
    if "native" in physics:
        native = NativeEnvs(env, 1)
        out["native"] = (native.reset, native.step)
    return out


def run_demo(out: str, seconds: float, seed: int, difficulty: int, view: dict | None = None,
             physics=("mjx", "native")) -> int:
    """Write a world, then step the waypoint-following env with zero actions on each of `physics`.

    With `view` ({'host': ..., 'port': ...}) the dashboard is served on the demo's world afterwards.
    """
    if view is not None:
        from web.source import check_port

        check_port(view["host"], view["port"])  # fail before the demo's minute of work
    world = generate_world(seed, difficulty)
    files = write_world(world, GO1, out)
    print(f"[demo] world seed={seed} difficulty={difficulty}: {world.summary()['size_m']} m, "
          f"min clearance {world.min_clearance:.2f} m -> {files['xml']}")
    from planners import HeightMaps, PlannerConfig, plan_path

    plan = plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, PlannerConfig())
    print(f"[demo] {plan.planner} planned {len(plan.waypoints)} body-pose waypoints, {plan.length_m:.2f} m, "
          f"in {plan.plan_time_s:.2f} s (lowest body height {plan.waypoints[:, 2].min():.3f} m)")
    env = ConfinedEnv(ConfinedConfig(mode="waypoints"), terrain=Terrain.from_worlds([world]), paths=[plan.waypoints])
    engines = _engines(env, physics)
    print(f"[demo] compiling the task for {' and '.join(engines)} physics (MJX: about a minute on a laptop CPU) ...",
          flush=True)
    t0 = time.perf_counter()
    key, action = jax.random.PRNGKey(seed), jnp.zeros((1, env.action_size))
    states = {name: e[1](e[0](key[None]), action) for name, e in engines.items()}  # the same first state in each
    jax.block_until_ready(list(states.values()))
    print(f"[demo] compiled in {time.perf_counter() - t0:.0f} s")
    gap = 0.0
    for _ in tqdm(range(int(seconds / env.dt) - 1), desc="demo steps", unit="step"):
        states = {name: engines[name][1](state, action) for name, state in states.items()}
        if len(states) == 2:
            gap = max(gap, float(jnp.abs(states["mjx"].pipeline_state.qpos - states["native"].pipeline_state.qpos).max()))
    state = jax.tree_util.tree_map(lambda x: x[0], next(iter(states.values())))
    report = {
        "world": files,
        "plan": {"waypoints": len(plan.waypoints), "length_m": round(plan.length_m, 3), "planner": plan.planner},
        "physics": list(states),
        "simulated_s": round(float(state.info["step"]) * env.dt, 2),
        "base_height_m": round(float(state.metrics["base_height"]), 4),
        "fell": bool(state.metrics["fell"]),
        "distance_to_goal_m": round(float(state.metrics["final_distance_m"]), 3),
        "observation": {k: int(v.shape[0]) for k, v in state.obs.items()},
        "max_qpos_gap_mjx_vs_native": round(gap, 6) if len(states) == 2 else None,
        "reward_terms": {k: round(float(v), 5) for k, v in state.metrics.items() if k.startswith("reward/")},
    }
    print(json.dumps(report, indent=2))
    print("[demo] Go1 stands at its default pose under zero action. Open the scene in MuJoCo's viewer with:\n"
          f"       python -m mujoco.viewer --mjcf={files['xml']}")
    ok = bool(np.isfinite(gap)) and not report["fell"]
    if view is not None:
        _serve(env, seed, view)
    return 0 if ok else 1


def _serve(env: ConfinedEnv, seed: int, view: dict) -> None:
    """Serve the dashboard on the demo's world (rolling out the default controller) until Ctrl-C."""
    from web.app import Dashboard, DashboardConfig
    from web.source import RolloutSource

    dashboard = Dashboard(DashboardConfig(host=view["host"], port=view["port"], seed=seed, steps=250),
                          source=RolloutSource(env, "confined-waypoints (demo world)"))
    print(f"[demo] dashboard at {dashboard.start()} (the first rollout compiles for about a minute; Ctrl-C stops)",
          flush=True)
    dashboard.wait()
