"""The environment base every task here shares: Brax `Env` properties and MJX stepping of the four verbs.

A task implements `spawn`, `first_state`, `prepare` and `transition` (the seam of legged.envs.physics)
plus a few engine read-outs (`mjx_model_for`, `contact_forces`, `native_model_fields`); `reset` and
`step` here run them with MJX, and legged.envs.native runs the same four with native MuJoCo.
"""

from __future__ import annotations

import abc

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import Env, State
from mujoco import mjx

from legged.envs.physics import PhysicsView, Spawn, reject_divergence, strong_types, view_of_mjx


def layout_slices(entries: list[tuple[str, int]]) -> dict[str, slice]:
    """Name -> slice of each entry of an observation's layout ([(name, size), ...], as `observation_layout()`
    lists them), in order."""
    out, start = {}, 0
    for name, size in entries:
        out[name], start = slice(start, start + size), start + size
    return out


class MjxEnv(Env, abc.ABC):
    """Brax Env over the four task verbs; `self.config` (ctrl_dt, n_substeps, divergence_qvel), `self.robot`,
    `self.mj_model` and `self.mjx_model` come from the subclass."""

    # ----------------------------------------------------------------- the task's verbs
    @abc.abstractmethod
    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        """A new episode's physical state and info (randomisation included). `carry` is what the episode
        inherits from the environment's previous one (`carry`), or what an evaluator asks for; None at the
        first reset."""

    @abc.abstractmethod
    def first_state(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        """The first State of an episode from the view of its forward-computed spawn."""

    @abc.abstractmethod
    def prepare(self, state: State, action: jax.Array, *args) -> tuple[jax.Array, jax.Array]:
        """(ctrl for physics, actions as `transition` sees them) for a control step: ctrl (nu,) for the whole step,
        or a schedule (n_substeps, nu) with one row per physics step."""

    @abc.abstractmethod
    def transition(self, state: State, view: PhysicsView, actions: jax.Array) -> State:
        """The next State from stepped physics; its `pipeline_state` is the view after the task's rules (which
        may move bodies: then `info['teleported']` is set and the engine loads the view's qpos, qvel, ctrl)."""

    def carry(self, info: dict) -> dict:
        """What the next episode of an environment inherits from the one that just ended (its `info`), e.g. a
        curriculum level; {} by default."""
        return {}

    def mastered(self, info: dict) -> jax.Array:
        """Whether the episode that just ended (its `info`) met the task well enough for a randomisation curriculum
        to make the next one harder (legged.envs.api.next_carry); by default, that it ran to its time limit."""
        return info["truncation"] > 0.5

    # ----------------------------------------------------------------- engine read-outs
    def mjx_model_for(self, info: dict):
        """The MJX model of an episode (its randomisation applied)."""
        return self.mjx_model

    def contact_forces(self, data) -> jax.Array:
        """Normal force on each watched geom (`watched_geoms`) of an MJX data."""
        return jnp.zeros(0)

    def native_model_fields(self, info: dict, rows: np.ndarray) -> dict:
        """Model fields (name -> numpy array, one row per entry of `rows`) of the episodes `rows` of a batched
        `info`, for native MuJoCo; {} when nominal."""
        return {}

    def native_model(self):
        """The MjModel the native engine steps: `mj_model` plus read-out sensors where the task needs them."""
        return self.mj_model

    @property
    def watched_geoms(self) -> np.ndarray:
        """Geom ids whose normal contact force `PhysicsView.contact_force` reports."""
        return np.zeros(0, np.int32)

    @property
    def uses_cameras(self) -> bool:
        """Whether the observations render cameras (the view then carries geom and camera poses)."""
        return False

    @property
    def native_ray_camera(self):
        """The RayCamera (legged.sensors.raycam) the native engine renders with MuJoCo's C ray caster after
        each step, its images then coming in the view (`PhysicsView.camera_rgb`, `camera_depth`); None: the
        observations render in JAX, or not at all."""
        return None

    def mjx_settle(self, model, data):
        """Derived fields of a spawned MJX data (default: mj_forward)."""
        return mjx.forward(model, data)

    # ----------------------------------------------------------------- what both engines call
    def start_episode(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        """`first_state` with canonical (strong) dtypes."""
        return strong_types(self.first_state(view, info, rng))

    def advance(self, state: State, view: PhysicsView, actions: jax.Array) -> State:
        """`transition` with canonical (strong) dtypes."""
        return strong_types(self.transition(state, view, actions))

    # ----------------------------------------------------------------- MJX engine
    def spawned_mjx(self, rng: jax.Array, carry: dict | None = None) -> tuple[PhysicsView, dict, object]:
        """(view, info, MJX data) of a spawned episode, forward-computed in MJX."""
        spawn = self.spawn(rng, carry)
        model = self.mjx_model_for(spawn.info)
        data = mjx.make_data(model).replace(qpos=spawn.qpos, qvel=spawn.qvel, ctrl=spawn.ctrl)
        data = self.mjx_settle(model, data)
        return view_of_mjx(data, self.contact_forces(data), False, self.uses_cameras), spawn.info, data

    def reset(self, rng: jax.Array, carry: dict | None = None) -> State:
        rng, k_obs = jax.random.split(rng)
        view, info, data = self.spawned_mjx(rng, carry)
        return self.start_episode(view, info, k_obs).replace(pipeline_state=data)

    def step(self, state: State, action: jax.Array, *args) -> State:
        ctrl, actions = self.prepare(state, action, *args)
        model = self.mjx_model_for(state.info)
        previous = state.pipeline_state
        if ctrl.ndim == 2:  # a schedule: one row of controls per physics step (e.g. action latency)
            data = jax.lax.scan(lambda d, c: (mjx.step(model, d.replace(ctrl=c)), None), previous, ctrl)[0]
        else:
            data = jax.lax.scan(lambda d, _: (mjx.step(model, d), None), previous.replace(ctrl=ctrl), None,
                                length=self.config.n_substeps)[0]
        bad, data = reject_divergence(data, previous, self.config.divergence_qvel)
        nxt = self.advance(state, view_of_mjx(data, self.contact_forces(data), bad, self.uses_cameras), actions)
        moved = nxt.pipeline_state
        return nxt.replace(pipeline_state=data.replace(qpos=moved.qpos, qvel=moved.qvel, ctrl=moved.ctrl))

    # ----------------------------------------------------------------- Brax Env properties
    @property
    def dt(self) -> float:
        """Control period, seconds."""
        return self.config.ctrl_dt

    @property
    def action_size(self) -> int:
        """Actions per robot (its actuated joints)."""
        return self.robot.num_joints

    @property
    def observation_size(self) -> dict:
        """Shape of each observation (traced once from `reset`, without compiling)."""
        if self.__dict__.get("_obs_size") is None:
            shapes = jax.eval_shape(self.reset, jax.random.PRNGKey(0)).obs
            self._obs_size = {k: v.shape for k, v in shapes.items()}
        return self._obs_size

    def observation_dims(self) -> dict:
        """Size of each observation: an int for vectors, a shape tuple otherwise (e.g. camera images)."""
        return {k: int(s[0]) if len(s) == 1 else tuple(int(d) for d in s) for k, s in self.observation_size.items()}

    def zero_metrics(self, view: PhysicsView, info: dict, actions: jax.Array) -> dict:
        """Zeros shaped like `State.metrics` (traced once, without compiling)."""
        if self.__dict__.get("_metric_shapes") is None:
            probe = State(view, {}, jnp.float32(0), jnp.float32(0), {}, info)
            self._metric_shapes = jax.eval_shape(lambda s, v, a: self.transition(s, v, a).metrics, probe, view, actions)
        return {k: jnp.zeros(s.shape, s.dtype) for k, s in self._metric_shapes.items()}

    @property
    def backend(self) -> str:
        return "mjx"


def next_carry(env, info: dict) -> dict:
    """What the engines hand an environment's next episode: `env.carry(info)` and, where the episode has one, its
    randomisation scale (`dr_scale`: a training run's ramp, legged.envs.base.LeggedEnv.spawn). An episode with a
    `dr_step` (a training run's randomisation curriculum) moves its scale by that step within [0, 1]: up after an
    episode the task counts as mastered (`env.mastered(info)`), down after one that ended in a fall or failure."""
    carry = env.carry(info)
    if "dr_scale" not in info:
        return carry
    scale = info["dr_scale"]
    if "dr_step" in info:
        up = env.mastered(info)
        down = (info["truncation"] < 0.5) & ~up
        scale = jnp.clip(scale + info["dr_step"] * (up.astype(jnp.float32) - down.astype(jnp.float32)), 0.0, 1.0)
        return {**carry, "dr_scale": scale, "dr_step": info["dr_step"]}
    return {**carry, "dr_scale": scale}
