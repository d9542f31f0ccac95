"""dm_control's multi-agent soccer (BoxHead walkers) as a throughput peer for our MJX soccer benchmark.

dm_control steps one CPU MuJoCo model per environment on one thread, so a "batch" of its environments is a
Python loop over them. The numbers here are what that peer does on this machine with random actions, with or
without each player's egocentric camera rendered every control step.
"""

import os
import time

import numpy as np

PEER = "dm_control soccer BoxHead"
CAMERA_OBSERVABLE = "egocentric_camera"


def _camera_observables(task):
    """Every camera observable of every entity in the task (walkers, pitch, ball)."""
    from dm_control.composer.observation import observable as observable_lib

    found = []
    for entity in task.root_entity.iter_entities():
        for obs in entity.observables.as_dict().values():
            if isinstance(obs, observable_lib.MJCFCamera):
                found.append(obs)
    return found


def dm_control_soccer(team_size: int, camera: bool, seed: int = 0, time_limit: float = 10.0,
                      camera_size: tuple[int, int] = (40, 30)):
    """A dm_control soccer environment with BoxHead walkers (team_size per team: 1 or 2); with camera=True each
    player's egocentric camera observable is enabled at camera_size (width, height); every other camera
    observable is disabled. MUJOCO_GL defaults to egl, which only takes effect if dm_control's rendering has
    not been imported yet in this process."""
    if team_size not in (1, 2):
        raise ValueError(f"team_size must be 1 or 2, not {team_size}")
    # dm_control picks its GL backend when its rendering module is first imported.
    os.environ.setdefault("MUJOCO_GL", "egl")
    from dm_control import composer
    from dm_control.locomotion import soccer

    # soccer.load builds the same game but gives BoxHead its default 28x28 camera, so the players are built
    # here with the camera resolution (BoxHead takes it as (width, height)).
    players = []
    for team, rgba, prefix in ((soccer.Team.HOME, soccer.RGBA_BLUE, "home"),
                               (soccer.Team.AWAY, soccer.RGBA_RED, "away")):
        for i in range(team_size):
            walker = soccer.BoxHead(name=f"{prefix}{i}", walker_id=i, marker_rgba=rgba,
                                    camera_resolution=tuple(camera_size))
            players.append(soccer.Player(team, walker))
    task = soccer.Task(players=players,
                       arena=soccer.RandomizedPitch(min_size=(32, 24), max_size=(48, 36)),
                       ball=soccer.SoccerBall())
    for obs in _camera_observables(task):
        obs.enabled = False
    if camera:
        for player in players:
            player.walker.observables.get_observable(CAMERA_OBSERVABLE).enabled = True
    # Without stripping, every observation keeps a leading buffer axis of 1: the camera would be (1, h, w, 3).
    return composer.Environment(task=task, time_limit=time_limit, random_state=seed,
                                strip_singleton_obs_buffer_dim=True)


def _random_actions(specs, rng):
    return [rng.uniform(s.minimum, s.maximum, size=s.shape).astype(s.dtype) for s in specs]


def measure_dm_control_soccer(team_size: int, camera: bool, batch_size: int, steps: int = 50, seed: int = 0,
                              camera_size=(40, 30)) -> dict:
    """env-steps per second of `batch_size` dm_control soccer environments stepped one after another with
    random actions (dm_control is single-threaded CPU MuJoCo: a 'batch' is a Python loop).

    Construction and the first reset of every environment are not timed. Inside the timed loop an episode
    that ends (goal scored or time limit) is reset, and that reset IS counted in the time without counting
    as a step; dm_control recompiles the MJCF model on every reset (the pitch size is re-drawn), so resets are
    costly. Actions are drawn uniformly within `env.action_spec()` (one spec per player) from a seeded numpy
    generator, inside the timed loop. With camera=True each player's camera is rendered once per control step.

    Returns a dict with keys: peer, team_size, n_agents, camera, batch_size, steps (env steps timed, per env),
    env_steps_per_s, agent_steps_per_s, control_dt, physics_dt, camera_size (or None), dm_control_version,
    mujoco_version, plus resets (episode resets inside the timed loop, all envs) and camera_obs_shape (the
    shape of the first player's camera image in the last timestep, (height, width, 3); None without camera).
    """
    from importlib import metadata

    import mujoco

    envs = [dm_control_soccer(team_size, camera, seed=seed + i, camera_size=camera_size)
            for i in range(batch_size)]
    timestep = [env.reset() for env in envs][-1]
    specs = [env.action_spec() for env in envs]
    n_agents = len(specs[0])
    rng = np.random.default_rng(seed)
    resets = 0
    start = time.perf_counter()
    for _ in range(steps):
        for env, spec in zip(envs, specs):
            timestep = env.step(_random_actions(spec, rng))
            if timestep.last():
                env.reset()
                resets += 1
    elapsed = time.perf_counter() - start
    env_steps_per_s = steps * batch_size / elapsed
    physics = envs[0].physics
    return {
        "peer": PEER,
        "team_size": team_size,
        "n_agents": n_agents,
        "camera": bool(camera),
        "batch_size": batch_size,
        "steps": steps,
        "env_steps_per_s": env_steps_per_s,
        "agent_steps_per_s": env_steps_per_s * n_agents,
        "control_dt": float(envs[0].control_timestep()),
        "physics_dt": float(physics.timestep()),
        "camera_size": tuple(camera_size) if camera else None,
        "dm_control_version": metadata.version("dm_control"),
        "mujoco_version": mujoco.__version__,
        "resets": resets,
        "camera_obs_shape": tuple(timestep.observation[0][CAMERA_OBSERVABLE].shape) if camera else None,
    }
