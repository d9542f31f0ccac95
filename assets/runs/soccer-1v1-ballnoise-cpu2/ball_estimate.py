"""Where a vision student's ball estimate falls short: the ball the placo command reads (a pilot too), by source.

Plays games of the student against the placo player (native physics, deterministic actions) and reports, over
the frames with the ball within 1 m of the student, the RMS error of the ball's position by where it came from
(sighted in this frame, remembered by the tracker for up to 1 s, the network's estimate) and of the ball's
velocity (the network's estimate: the tracker keeps no velocity); then the same frames split by the ball's
distance and bearing: how often it was not sighted in that frame, how often the network guessed it, and the RMS.

    .venv/bin/python assets/runs/soccer-1v1-ballnoise-cpu2/ball_estimate.py assets/policies/op3-soccer-1v1-vision 777 32
"""
import dataclasses
import sys

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.vector import VectorEnv
from legged.soccer.observe import PROPRIO_SIZE
from legged.soccer.vision.tracker import tracker_inputs
from policies.evaluate import held_out, soccer_opponent
from policies.policy_io import actor_observation, load_policy
from policies.training import build_env

run, seed, games = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
policy, config = load_policy(run, None)
env = build_env(dataclasses.replace(config, env=held_out(config.task, config.env)))
opponent = (soccer_opponent("placo", env),)
vector = VectorEnv.of(env, games, "native", 2)
batch = vector.reset(jax.random.fold_in(jax.random.PRNGKey(seed), 0), None)
policy.reset()
obs, playing = batch.state.obs, np.ones(games, bool)
known = jax.jit(jax.vmap(lambda t: tracker_inputs(t, env._goal_xy[0], env._goal_xy[1])))
used = jax.jit(jax.vmap(env.used_estimate))
frames = []
while playing.any():
    action = np.asarray(policy.act(actor_observation(obs, policy.inputs)))
    truth = np.asarray(batch.state.info["game_obs"]["features"])[:, 0, PROPRIO_SIZE:]
    estimate = np.asarray(used(batch.state, jnp.asarray(action)))
    tracked = np.asarray(known(batch.state.info["tracker"]))
    fresh, age = tracked[:, 5] > 0.5, np.asarray(batch.state.info["tracker"])[:, 16]
    source = np.where(~fresh, 2, np.where(age == 0, 0, 1))  # sighted now, remembered, the network's
    frames.append(np.stack([np.linalg.norm(truth[:, :2], axis=-1), source,
                            np.linalg.norm(estimate[:, :2] - truth[:, :2], axis=-1),
                            np.linalg.norm(estimate[:, 3:5] - truth[:, 3:5], axis=-1),
                            np.linalg.norm(truth[:, 3:5], axis=-1), np.arctan2(truth[:, 1], truth[:, 0])], -1)[playing])
    batch, result = vector.step(batch, jnp.asarray(action), *opponent)
    obs, done = result.obs, np.asarray(result.done)
    policy.reset(done)
    playing &= ~done
distance, source, position, velocity, speed, bearing = np.concatenate(frames).T
near = distance < 1.0
rms = lambda x, m: float(np.sqrt(np.mean(x[m] ** 2)))
print(f"ball within 1 m in {near.mean():.1%} of the frames; there, position RMS {rms(position, near):.3f} m, "
      f"velocity RMS {rms(velocity, near):.3f} m/s (true speed RMS {rms(speed, near):.3f} m/s)")
for k, name in enumerate(["sighted in this frame", "remembered (tracker, up to 1 s)", "the network's estimate"]):
    m = near & (source == k)
    print(f"  {name:32s} {m.sum() / near.sum():6.1%} of those frames, position RMS {rms(position, m):.3f} m")
print("frames with the ball within 1 m, by distance (m) and |bearing| (rad):")
for lo, hi in [(0, 0.25), (0.25, 0.5), (0.5, 1.0)]:
    for blo, bhi in [(0, 0.4), (0.4, 0.75), (0.75, 3.2)]:
        m = near & (distance >= lo) & (distance < hi) & (np.abs(bearing) >= blo) & (np.abs(bearing) < bhi)
        if m.sum():
            print(f"  d {lo:.2f}-{hi:.2f} |bearing| {blo:.2f}-{bhi:.2f}: {m.sum()/near.sum():6.1%} of near; "
                  f"not sighted {np.mean(source[m] > 0):6.1%}, guessed {np.mean(source[m] == 2):6.1%}, "
                  f"pos RMS {rms(position, m):.3f}")
