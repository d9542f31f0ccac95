"""Recording rollouts of an environment (MJX or native physics) into Trajectories (joint positions, rewards, metrics, overlays).

The environment runs vmapped over a small batch, compiled once per Recorder. An environment whose episode
ends is frozen at its last state. Without a policy every action is zero: Go1 is held at its default pose
by its PD controller.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.native import NativeEnvs
from legged.envs.physics import select_envs
from web.trajectory import Trajectory

Act = Callable[[dict], np.ndarray]
"""A policy: actor observations (n, obs) -> actions (n, actions), numpy in and out."""


@dataclasses.dataclass(frozen=True)
class RecorderConfig:
    """How rollouts are recorded."""

    num_envs: int = 1
    """Environments rolled out side by side (each its own world tile, or offset sideways on flat ground)."""
    spacing: float = 1.0
    """Sideways distance between robots drawn on a scene without height fields, metres."""
    distinct_tiles: bool = True
    """On tiled terrains, pick reset keys so that the environments start in different worlds."""
    physics: str = "mjx"
    """Physics engine of the rollouts: mjx or native (MuJoCo's C engine, the same task code)."""


class Recorder:
    """Rolls out `env` (a legged.envs environment) for `num_envs` environments and records what it sees."""

    def __init__(self, env, task: str, config: RecorderConfig = RecorderConfig(), env_args: tuple = ()):
        """env_args go to every step (a soccer opponent: legged.soccer.learner.LearnerView.step)."""
        if not 1 <= config.num_envs <= 16:
            raise ValueError(f"num_envs must be between 1 and 16 for the dashboard, got {config.num_envs}")
        self.env, self.task, self.config = env, task, config
        self.has_path = hasattr(env, "path_of")
        self.has_scans = hasattr(env, "scan_world_points")
        self.has_head_camera = hasattr(env, "camera_images")  # soccer: the learner's head camera
        self.has_estimate = getattr(env, "estimates_world", False)  # a vision player's estimate of the game
        self._estimate = jax.jit(jax.vmap(env.estimate_points)) if self.has_estimate else None
        self.has_sightings = getattr(getattr(env, "config", None), "vision_sightings", False)  # its camera's detector
        self._sightings = jax.jit(jax.vmap(env.sighting_points)) if self.has_sightings else None
        self.has_tracker = getattr(getattr(env, "config", None), "vision_tracker", False) and \
            hasattr(env, "tracked_points")  # where its tracker puts it (not in drills)
        self._tracked = jax.jit(jax.vmap(env.tracked_points)) if self.has_tracker else None
        if config.physics == "native":
            native = NativeEnvs(env, config.num_envs, cameras=self.has_head_camera)
            extras, frozen = jax.jit(self._with_extras), jax.jit(self._frozen)
            self._reset = lambda keys: extras(native.reset(keys))
            self._step = lambda state, action: frozen(state, native.step(state, action, *env_args))
        elif config.physics == "mjx":
            step = jax.vmap(lambda state, action: env.step(state, action, *env_args))
            self._reset = jax.jit(lambda keys: self._with_extras(jax.vmap(env.reset)(keys)))
            self._step = jax.jit(lambda state, action: self._frozen(state, step(state, action)))
        else:
            raise ValueError(f"unknown physics {config.physics!r}; one of mjx, native")
        flat_ground = env.mj_model.nhfield == 0
        n = config.num_envs
        self.offsets = np.zeros((n, 3))
        if flat_ground:
            self.offsets[:, 1] = (np.arange(n) - (n - 1) / 2) * config.spacing

    # ------------------------------------------------------------------ compiled parts
    def _extras(self, state) -> dict:
        out = {}
        if self.has_scans:
            out["scan"] = self.env.scan_world_points(state.pipeline_state)
        if self.has_path:
            out["path"], out["path_len"] = self.env.path_of(state.info)
        if self.has_head_camera:
            out["head_rgb"] = self.env.camera_images(state.pipeline_state)
        return out

    def _with_extras(self, state):
        return state, jax.vmap(self._extras)(state)

    def _frozen(self, state, nxt):
        """The stepped states, but finished episodes stay frozen at their last state; with extras."""
        return self._with_extras(select_envs(state.done > 0, state, nxt))

    # ------------------------------------------------------------------ recording
    def reset_keys(self, seed: int) -> jax.Array:
        """One reset key per environment; on tiled terrains, chosen so that each starts in its own world."""
        n = self.config.num_envs
        keys = jax.random.split(jax.random.PRNGKey(seed), n)
        tiles = getattr(getattr(self.env, "terrain", None), "num_tiles", 1)
        if not (self.config.distinct_tiles and self.has_path and n > 1 and tiles >= n):
            return keys
        chosen, seen, candidates = [], set(), jax.random.PRNGKey(seed)
        for _ in range(64):  # 64 batches of candidates: ample for n <= number of tiles
            candidates, sub = jax.random.split(candidates)
            batch = jax.random.split(sub, n)
            for key, tile in zip(batch, np.asarray(self._reset(batch)[0].info["tile"])):
                if int(tile) not in seen and len(chosen) < n:
                    seen.add(int(tile))
                    chosen.append(key)
            if len(chosen) == n:
                return jnp.stack(chosen)
        return keys

    def record(self, steps: int, seed: int, act: Act | None = None, info: dict | None = None,
               progress: Callable[[int, int], None] | None = None) -> Trajectory:
        """Roll out `steps` control steps from the reset of `seed` (zero actions without `act`)."""
        if steps < 1:
            raise ValueError(f"steps must be >= 1, got {steps}")
        env, n = self.env, self.config.num_envs
        state, extras = self._reset(self.reset_keys(seed))
        zeros = np.zeros((n, env.action_size), np.float32)
        frames = [self._frame(state, extras)]
        for k in range(steps):
            action = zeros if act is None else np.asarray(act({name: np.asarray(v) for name, v in state.obs.items()}),
                                                          np.float32)
            if self.has_estimate:  # made from what it saw at this frame
                frames[-1]["estimate"] = np.asarray(self._estimate(state, action), np.float32)
            state, extras = self._step(state, action)
            frames.append(self._frame(state, extras))
            if progress is not None:
                progress(k + 1, steps)
            if bool(np.all(frames[-1]["done"])):
                break
        info = dict(info or {})
        info.setdefault("policy", "default controller" if act is None else "policy")
        return self._trajectory(frames, extras, state, seed, info)

    def _frame(self, state, extras) -> dict:
        frame = {"qpos": np.asarray(state.pipeline_state.qpos, np.float32), "reward": np.asarray(state.reward),
                 "done": np.asarray(state.done) > 0,
                 "metrics": {k: np.asarray(v, np.float32) for k, v in state.metrics.items()}}
        if "scan" in extras:
            frame["scan"] = np.asarray(extras["scan"], np.float32)
        if self.has_path:
            frame["waypoint"] = np.asarray(state.info["waypoint"], np.int32)
        if "head_rgb" in extras:
            frame["camera"] = np.asarray(extras["head_rgb"], np.uint8)
        if self.has_sightings:
            frame["sighting"] = np.asarray(self._sightings(state), np.float32)
        if self.has_tracker:
            frame["tracked"] = np.asarray(self._tracked(state), np.float32)
        return frame

    def _trajectory(self, frames: list[dict], extras, state, seed: int, info: dict) -> Trajectory:
        stack = lambda key: np.stack([f[key] for f in frames])
        metrics = {k: np.stack([f["metrics"][k] for f in frames]) for k in frames[0]["metrics"]}
        out = dict(model=self.env.mj_model, dt=float(self.env.dt), qpos=stack("qpos"),
                   reward=stack("reward").astype(np.float32), done=stack("done"), metrics=metrics,
                   offsets=self.offsets.copy(), info=dict(info, task=self.task, seed=int(seed)))
        if "scan" in frames[0]:
            scans = stack("scan")
            out.update(floor_scan=scans[:, :, 0], ceiling_scan=scans[:, :, 1])
        if self.has_path:
            out.update(paths=np.asarray(extras["path"], np.float32), path_len=np.asarray(extras["path_len"]),
                       waypoint=stack("waypoint"), goal=np.asarray(state.info["goal"], np.float32))
        if "camera" in frames[0]:
            out["camera"] = stack("camera")
        if "estimate" in frames[0]:
            frames[-1].setdefault("estimate", frames[-2]["estimate"])  # the last frame acts no more
            out["estimates"] = stack("estimate")
        if "sighting" in frames[0]:
            out["sightings"] = stack("sighting")
        if "tracked" in frames[0]:
            out["tracked"] = stack("tracked")
        return Trajectory(**out)
