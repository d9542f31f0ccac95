"""Soccer throughput: env-steps per second for 1v1 and 2v2, with and without the head cameras, at several
batch sizes, on MJX and native MuJoCo, beside dm_control's soccer (the peer) in the same run."""

from __future__ import annotations

import dataclasses
import sys

import jax

from legged.bench import bench_vector
from legged.envs.native import check_threads
from legged.soccer.learner import LearnerView
from legged.soccer.peer_dm_control import measure_dm_control_soccer
from legged.tasks import make

TASK_OF_TEAM_SIZE = {1: "soccer-1v1", 2: "soccer-2v2"}
PEER_BATCH = 1
"""dm_control environments timed per setting: its 'batch' is a Python loop, so its rate does not depend on it."""


CASTERS = ("c", "c-unculled", "jax")
"""Ray casters of the head cameras under native physics: MuJoCo's in C (legged.sensors.native_raycam), the same
without culling the geoms outside each camera's view, JAX's."""


def soccer_env(players_per_team: int, camera: bool, caster: str = "c"):
    """The soccer env of a team size, with or without every agent's head camera in its observations (under
    native physics cast by `caster`)."""
    env = make(TASK_OF_TEAM_SIZE[players_per_team])
    if not camera:
        return env
    config = dataclasses.replace(env.config, vision=True,
                                 camera=dataclasses.replace(env.config.camera, native_caster=caster != "jax",
                                                            native_cull=caster == "c"))
    return type(env)(config)


def bench_soccer(team_sizes=(1, 2), cameras=(False, True), batches=(1, 16), seconds: float = 3.0,
                 peer: bool = True, peer_steps: int = 20, physics=("mjx", "native"), threads: int | None = None,
                 progress=None, casters=("c",)) -> list[dict]:
    """One record per (team size, camera, physics, caster, batch): game steps per second of the learner's
    view (agent 0 acting, the others scripted; what training steps: the learner's camera only) on each
    physics engine (with cameras under native physics, once per ray caster in `casters`), beside (with
    `peer`) dm_control's BoxHead soccer at the same team size and camera setting, measured once per setting
    on one env (its batch would be a Python loop over envs) and compared with every record."""
    if peer_steps < 1:
        raise ValueError(f"peer_steps must be >= 1, got {peer_steps}")
    threads = check_threads(threads)
    if not set(casters) <= set(CASTERS) or not casters:
        raise ValueError(f"casters must be some of {', '.join(CASTERS)}, got {casters}")
    say = progress or (lambda msg: None)
    records = []
    for team_size in team_sizes:
        for camera in cameras:
            settings = []  # (physics, ray caster)
            for p in physics:
                settings += [(p, None)] if not camera else [(p, c) for c in casters] if p == "native" else [(p, "jax")]
            views = {caster: LearnerView(soccer_env(team_size, camera, caster or "c")) for _, caster in settings}
            game = next(iter(views.values())).game
            name = TASK_OF_TEAM_SIZE[team_size] + ("+camera" if camera else "")
            peer_record = None
            if peer:  # dm_control steps its envs one after another: one measurement serves every batch size
                say(f"{name}: dm_control peer ({PEER_BATCH} env, {peer_steps} steps)")
                cam_size = (game.config.camera.width, game.config.camera.height)
                peer_record = measure_dm_control_soccer(team_size, camera, PEER_BATCH, steps=peer_steps,
                                                        camera_size=cam_size)
            for batch in batches:
                for p, caster in settings:
                    env = views[caster]
                    say(f"{name}: {p}{f', {caster} ray caster' if caster else ''}, batch {batch}: compiling and "
                        f"timing for {seconds:.0f} s")
                    r = bench_vector(env, p, batch, seconds, 0, threads)
                    rate = r["env_steps_per_s"]
                    record = {"task": name, "team_size": team_size, "n_agents": game.n_agents, "camera": camera,
                              "camera_caster": caster,
                              "camera_size": [game.config.camera.width, game.config.camera.height] if camera else None,
                              "physics": p, "threads": threads if p == "native" else None, "batch": batch, **r,
                              "agent_steps_per_s": round(rate * game.n_agents, 1), "ctrl_dt": game.dt,
                              "sim_dt": game.config.sim_dt, "backend": jax.default_backend()}
                    if peer_record is not None:
                        q = peer_record
                        record.update(peer=q["peer"], peer_env_steps_per_s=round(q["env_steps_per_s"], 2),
                                      peer_batch=PEER_BATCH, peer_steps_timed=q["steps"],
                                      ratio_vs_peer=round(rate / q["env_steps_per_s"], 2))
                    records.append(record)
    return records


def print_soccer_table(records: list[dict], file=sys.stdout) -> None:
    """Human-readable table of soccer benchmark records."""
    print(f"{'task':20s} {'physics':8s} {'caster':>10s} {'batch':>6s} {'env steps/s':>12s} {'compile s':>10s} "
          f"{'peer/s':>9s} {'ratio':>8s}", file=file)
    for r in records:
        print(f"{r['task']:20s} {r['physics']:8s} {r.get('camera_caster') or '-':>10s} {r['batch']:6d} "
              f"{r['env_steps_per_s']:12.1f} {r['compile_s']:10.1f} "
              f"{r.get('peer_env_steps_per_s', float('nan')):9.2f} {r.get('ratio_vs_peer', float('nan')):8.2f}",
              file=file)
