"""Native MuJoCo physics for every task: `mujoco.batch.Batch` under the same task verbs as MJX.

`NativePhysics` is the engine's side of the seam (legged.envs.physics): it loads spawned states and
randomised model fields into the C engine, steps every simulation on a thread pool that releases the GIL,
and hands back one batched `PhysicsView`, read in bulk from bound arrays (contact forces from the MJCF
contact sensors of `env.native_model()`). `NativeEnvs` runs the task's own `spawn`, `first_state`,
`prepare` and `transition` (jitted and vmapped) around it, so a task is defined once for both engines.
"""

from __future__ import annotations

import functools
import os
import time

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from brax.envs.base import State
from mujoco.batch import Batch, SimulationError

from legged.envs.api import next_carry
from legged.envs.physics import CAMERA_FIELDS, PhysicsView, is_diverged, select_envs
from legged.sensors.native_raycam import NativeRayCaster
from legged.worlds.mjcf import CONTACT_SLOTS

_UNSTABLE = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL)
"""Warnings with which MuJoCo resets an unstable simulation: a divergence, whatever the state looks like."""


def default_threads() -> int:
    """Physics threads when none are asked for: every core this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def check_threads(threads: int | None) -> int:
    """`threads` checked (>= 1), or default_threads() for None."""
    if threads is None:
        return default_threads()
    if int(threads) < 1:
        raise ValueError(f"threads must be >= 1, got {threads}")
    return int(threads)


class NativePhysics:
    """`num_envs` simulations of a task's native model in a `mujoco.batch.Batch` (numpy in, numpy out)."""

    def __init__(self, env, num_envs: int, threads: int | None = None, cameras: bool = False):
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        self.model = env.native_model()
        self.n_substeps = env.config.n_substeps
        self.limit = env.config.divergence_qvel
        self.batch = Batch(self.model, num_envs, nthread=check_threads(threads))
        b = self.batch
        self._state = {k: b.bind(k) for k in ("qpos", "qvel", "ctrl")}
        fields = ["xpos", "xmat", "actuator_force"] + (list(CAMERA_FIELDS) if env.uses_cameras or cameras else [])
        self._derived = {k: b.bind(k) for k in fields}
        camera = env.native_ray_camera
        self._caster = None if camera is None else NativeRayCaster(self.model, camera, check_threads(threads))
        m = self.model
        names = [mujoco.mj_id2name(env.mj_model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in env.watched_geoms]
        adr = [m.sensor(f"contact_{n}").adr[0] for n in names]
        # normal force of slot k of watched geom g: sensordata[adr_g + 3 k]
        self._normal_index = np.array([[a + 3 * k for k in range(CONTACT_SLOTS)] for a in adr], np.int64)
        self._sensors = b.bind("sensordata") if len(adr) else None
        self._warnings = np.asarray(b.warning)
        self._last: dict | None = None
        self.seconds = 0.0
        """Wall time spent in the C engine so far (steps, and the forward passes of loaded states), for profiles."""

    @property
    def num_envs(self) -> int:
        return self.batch.nsim

    def _read(self, rows: np.ndarray | None = None) -> dict:
        """Every field of the view, copied out of the batch (float32 as JAX uses them); camera images are
        rendered anew for simulations `rows` only (None: all), the others keep their last ones."""
        out = {k: v.astype(np.float32) for k, v in self._state.items()}
        n = self.num_envs
        for k, v in self._derived.items():
            out[k] = v.astype(np.float32).reshape(n, -1, 3, 3) if k.endswith("xmat") else v.astype(np.float32)
        if self._sensors is None:
            out["contact_force"] = np.zeros((n, 0), np.float32)
        else:
            out["contact_force"] = np.abs(self._sensors[:, self._normal_index]).sum(-1).astype(np.float32)
        if self._caster is not None:
            if rows is None or self._last is None:
                rows = np.arange(n)
            images = self._caster.render(*(self._derived[k][rows] for k in CAMERA_FIELDS + ("xpos", "xmat")))
            if len(rows) == n:
                out["camera_rgb"], out["camera_depth"] = images["rgb"], images["depth"]
            else:
                out["camera_rgb"], out["camera_depth"] = self._last["camera_rgb"].copy(), self._last["camera_depth"].copy()
                out["camera_rgb"][rows], out["camera_depth"][rows] = images["rgb"], images["depth"]
        return out

    def _unstable_counts(self) -> np.ndarray:
        return self._warnings[:, list(map(int, _UNSTABLE)), 1].sum(-1)

    def load(self, ids: np.ndarray, qpos, qvel, ctrl, model_fields: dict | None = None, fresh: bool = True) -> dict:
        """Give simulations `ids` new states (rows of qpos, qvel, ctrl for those ids). fresh: a new episode
        (reset first: time 0, no warm start; `model_fields` name -> rows of per-simulation values; derived
        fields computed at the new state). Otherwise (the task's rules moved bodies) only the state is
        written. Returns the whole view."""
        ids = np.asarray(ids, np.int32)
        b = self.batch
        start = time.perf_counter()
        if fresh:
            b.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE)
            for name, values in (model_fields or {}).items():
                b.expand(name)[ids] = values
            if model_fields:
                b.set_const(ids)
        self._state["qpos"][ids] = qpos
        self._state["qvel"][ids] = qvel
        self._state["ctrl"][ids] = ctrl
        if fresh:
            b.forward(ids)
        self.seconds += time.perf_counter() - start
        view = self._read(ids)
        if self._last is None:
            self._last = view
        else:
            for k in view:
                self._last[k][ids] = view[k][ids]
        return view

    def step(self, ctrl: np.ndarray) -> tuple[dict, np.ndarray]:
        """One control period of every simulation: (view, diverged). `ctrl` is (num_envs, nu), or a schedule
        (num_envs, n_substeps, nu) stepped in runs of physics steps over which no simulation's controls change. A
        diverged simulation (MuJoCo error or instability, non-finite or too fast state) shows its last good state;
        its episode must restart."""
        if ctrl.ndim == 2:
            runs = [(0, self.n_substeps, ctrl)]
        else:
            changes = np.flatnonzero(np.any(ctrl[:, 1:] != ctrl[:, :-1], axis=(0, 2))) + 1
            edges = [0, *changes.tolist(), self.n_substeps]
            runs = [(a, b, ctrl[:, a]) for a, b in zip(edges[:-1], edges[1:])]
        before = self._unstable_counts()
        failed = np.zeros(self.num_envs, bool)
        start = time.perf_counter()
        for first, stop, controls in runs:
            self._state["ctrl"][:] = controls
            try:
                self.batch.step(nstep=stop - first)
            except SimulationError as exc:
                failed[exc.ids] = True
        self.seconds += time.perf_counter() - start
        view = self._read()
        bad = failed | (self._unstable_counts() > before) | is_diverged(view["qpos"], view["qvel"], self.limit, np)
        if bad.any():
            for k in view:
                view[k][bad] = self._last[k][bad]
        self._last = view
        return view, bad


@jax.jit
def _select_rows(mask, fresh, state):
    """`fresh` where `mask` (num_envs,) is set, else `state`."""
    return select_envs(mask, fresh, state)


@jax.jit
def _scatter_rows(state, rows_state, rows):
    """`state` with environments `rows` replaced by the rows of `rows_state` (same tree)."""
    return jax.tree_util.tree_map(lambda whole, part: whole.at[rows].set(part), state, rows_state)


def as_view(fields: dict, diverged) -> PhysicsView:
    """A batched PhysicsView (JAX arrays) from NativePhysics output."""
    return PhysicsView(diverged=jnp.asarray(diverged), **{k: jnp.asarray(v) for k, v in fields.items()})


class NativeEnvs:
    """`num_envs` episodes of a task with native physics: the task's own verbs, jitted and vmapped, around
    NativePhysics. No automatic resets here (legged.envs.vector.VectorEnv adds them). cameras: the views
    carry geom and camera poses even where the task's observations render none (viewers)."""

    def __init__(self, env, num_envs: int, threads: int | None = None, cameras: bool = False):
        self.env, self.num_envs = env, num_envs
        self.physics = NativePhysics(env, num_envs, threads, cameras)
        def spawn(keys, carry):  # split as MjxEnv.reset splits its key
            split = jax.vmap(jax.random.split)(keys)
            return jax.vmap(env.spawn)(split[:, 0], carry), split[:, 1]

        self._spawn = jax.jit(spawn)
        self._carry = jax.jit(jax.vmap(functools.partial(next_carry, env)))
        self._first = jax.jit(jax.vmap(env.start_episode))
        self._prepare = jax.jit(lambda state, action, *args: jax.vmap(lambda s, a: env.prepare(s, a, *args))(state, action))
        self._transition = jax.jit(jax.vmap(env.advance))
        self._warm = False

    def spawn(self, keys: jax.Array, carry: dict | None = None):
        """(Spawns, observation keys) for reset keys (one per environment), split as MjxEnv.reset does."""
        return self._spawn(keys, carry)

    def reset(self, keys: jax.Array, ids: np.ndarray | None = None, state: State | None = None,
              carry: dict | None = None) -> State:
        """Start new episodes from reset `keys` [num_envs] in environments `ids` (all by default); with
        `state`, the others keep theirs and the new episodes inherit `env.carry` of the ones in `state`
        (else `carry`, batched, or nothing). The same keys give the same first states as MJX's `reset`."""
        every = state is None or ids is None
        ids = np.arange(self.num_envs) if every else np.asarray(ids)
        if state is not None and carry is None:
            carry = self._carry(state.info)
        few = min(self.num_envs, max(16, self.num_envs // 8))  # one compiled size for a few resets
        if every or len(ids) > few:
            spawn, k_obs = self.spawn(keys, carry)
            rows = lambda x: np.asarray(x)[ids]
            fields = self.env.native_model_fields(spawn.info, ids)
            view = self.physics.load(ids, rows(spawn.qpos), rows(spawn.qvel), rows(spawn.ctrl), fields)
            fresh = self._first(as_view(view, np.zeros(self.num_envs, bool)), spawn.info, k_obs)
            if every:
                if not self._warm and self.num_envs > 1:  # compile both partial-reset paths now, not mid-run,
                    self._warm = True  # then put back the physics of the episodes they restarted
                    self.reset(keys, np.arange(1), fresh)
                    self.reset(keys, np.arange(min(few + 1, self.num_envs)), fresh)
                    self.load(fresh)
                return fresh
            mask = np.zeros(self.num_envs, bool)
            mask[ids] = True
            return _select_rows(jnp.asarray(mask), fresh, state)
        # a few environments: spawn and observe only those, in a sub-batch of one fixed size (padded)
        rows = np.concatenate([ids, np.full(few - len(ids), ids[0])])
        pick = jnp.asarray(rows)
        spawn, k_obs = self.spawn(keys[pick], jax.tree_util.tree_map(lambda x: x[pick], carry))
        own = lambda x: np.asarray(x)[:len(ids)]
        fields = self.env.native_model_fields(spawn.info, np.arange(len(ids)))
        view = self.physics.load(ids, own(spawn.qpos), own(spawn.qvel), own(spawn.ctrl), fields)
        fresh = self._first(as_view({k: v[rows] for k, v in view.items()}, np.zeros(few, bool)), spawn.info, k_obs)
        return _scatter_rows(state, fresh, jnp.asarray(rows))

    def load(self, state: State) -> State:
        """Continue from a batched State of the task made by either engine (e.g. MJX's reset): its physical
        state and randomisation go into the C engine; the returned State holds the native view."""
        data = state.pipeline_state
        ids = np.arange(self.num_envs)
        fields = self.env.native_model_fields(state.info, ids)
        view = self.physics.load(ids, np.asarray(data.qpos), np.asarray(data.qvel), np.asarray(data.ctrl), fields)
        return state.replace(pipeline_state=as_view(view, np.zeros(self.num_envs, bool)))

    def data(self, i: int) -> mujoco.MjData:
        """Environment i's physics as a forward-computed MjData (for renderers and inspection)."""
        data = self.physics.batch.get_data(i)
        mujoco.mj_forward(self.physics.model, data)
        return data

    def controls(self, state: State, action: jax.Array, *args) -> jax.Array:
        """The actuator controls the task's `prepare` gives for batched actions: (num_envs, nu), or with a schedule
        (action latency) (num_envs, n_substeps, nu)."""
        return self._prepare(state, action, *args)[0]

    def step(self, state: State, action: jax.Array, *args) -> State:
        """One control step of every environment (the task's `prepare`, native physics, `transition`);
        bodies the task's rules moved (info['teleported']) are written back to the engine."""
        ctrl, actions = self._prepare(state, action, *args)
        view, bad = self.physics.step(np.asarray(ctrl))
        nxt = self._transition(state, as_view(view, bad), actions)
        if "teleported" in nxt.info:
            moved = np.flatnonzero(np.asarray(nxt.info["teleported"]))
            if len(moved):
                v = nxt.pipeline_state
                self.physics.load(moved, np.asarray(v.qpos)[moved], np.asarray(v.qvel)[moved],
                                  np.asarray(v.ctrl)[moved], fresh=False)
        return nxt
