"""The seam between a task and its physics engine, the same for MJX and for native MuJoCo.

Into physics, before a control step: the actuator controls (`ctrl`), and for the simulations that start
over or are moved by the task's rules, a new state (`Spawn`: qpos, qvel, ctrl and, for a new episode, its
randomised model fields). Out of physics, after the step: a `PhysicsView`, the few fields a task's
`transition` and observations read. Both engines fill it the same way:

- state fields (qpos, qvel, ctrl, time) are the state after the control step;
- derived fields (xpos, xmat, geom and camera poses, actuator_force, contact_force) describe the state
  before the last physics substep, as after `mj_step` and `mjx.step` (after a reset or a move they are
  computed at the new state);
- `diverged` marks a simulation whose step produced a non-finite state, |qvel| above the task's limit, or
  a MuJoCo error or instability warning; its view holds the last good state instead.

A task implements four verbs on top of it (legged.envs.api.MjxEnv): `spawn(rng)`, `first_state(view,
info, rng)`, `prepare(state, action, *args)` (controls) and `transition(state, view, actions)`. MJX runs
them in `MjxEnv.reset` / `step`; the native engine (legged.envs.native) runs the same functions around
`mujoco.batch.Batch`.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class PhysicsView:
    """What a task reads from stepped physics (see the module docstring for when each field is taken)."""

    qpos: jax.Array
    """Generalised positions after the step, (nq,)."""
    qvel: jax.Array
    """Generalised velocities after the step, (nv,)."""
    ctrl: jax.Array
    """Actuator controls applied during the step, (nu,)."""
    xpos: jax.Array
    """Body positions, (nbody, 3)."""
    xmat: jax.Array
    """Body orientations, (nbody, 3, 3)."""
    actuator_force: jax.Array
    """Actuator forces (torques), (nu,)."""
    contact_force: jax.Array
    """Normal contact force on each geom the task watches (feet, then body geoms), (n_watched,)."""
    diverged: jax.Array
    """True when this step diverged (the fields then hold the last good state)."""
    geom_xpos: jax.Array | None = None
    """Geom positions (ngeom, 3), for cameras; None where the task renders none."""
    geom_xmat: jax.Array | None = None
    """Geom orientations (ngeom, 3, 3), for cameras; None where the task renders none."""
    cam_xpos: jax.Array | None = None
    """Camera positions (ncam, 3), for cameras; None where the task renders none."""
    cam_xmat: jax.Array | None = None
    """Camera orientations (ncam, 3, 3), for cameras; None where the task renders none."""
    camera_rgb: jax.Array | None = None
    """Images of the task's ray camera, (n_cam, H, W, 3) uint8, where the native engine renders them in C
    (MjxEnv.native_ray_camera); None elsewhere."""
    camera_depth: jax.Array | None = None
    """Depth images of the same cameras, (n_cam, H, W) float32 metres; None elsewhere."""

    def replace(self, **changes) -> "PhysicsView":
        """A copy with some fields replaced."""
        return dataclasses.replace(self, **changes)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class Spawn:
    """A new physical state for one simulation: the start of an episode."""

    qpos: jax.Array
    """Generalised positions, (nq,)."""
    qvel: jax.Array
    """Generalised velocities, (nv,)."""
    ctrl: jax.Array
    """Actuator controls, (nu,)."""
    info: dict
    """The episode's bookkeeping (`State.info`), including its randomisation `dr` where the task has one."""


def strong_types(state):
    """`state` with every observation, reward, done, metric and info array of a strong dtype. A value
    computed from Python numbers is "weakly typed" in JAX, and a compiled step fed a state whose types
    differ from the last one's compiles again (a minute for some tasks): both engines pass every State
    through here."""
    strong = lambda tree: jax.tree_util.tree_map(lambda x: jnp.asarray(x).astype(jnp.asarray(x).dtype), tree)
    return state.replace(obs=strong(state.obs), reward=strong(state.reward), done=strong(state.done),
                         metrics=strong(state.metrics), info=strong(state.info))


CAMERA_FIELDS = ("geom_xpos", "geom_xmat", "cam_xpos", "cam_xmat")
"""Derived fields only the camera renderers read."""


def view_of_mjx(data, contact_force: jax.Array, diverged, cameras: bool = True) -> PhysicsView:
    """The PhysicsView of an MJX data (`contact_force` read by the task's contact reader)."""
    extra = {k: getattr(data, k) for k in CAMERA_FIELDS} if cameras else {}
    return PhysicsView(qpos=data.qpos, qvel=data.qvel, ctrl=data.ctrl, xpos=data.xpos, xmat=data.xmat,
                       actuator_force=data.actuator_force, contact_force=contact_force,
                       diverged=jnp.asarray(diverged, bool), **extra)


def is_diverged(qpos, qvel, limit: float, xp=jnp):
    """True when qpos or qvel has a non-finite value or some |qvel| exceeds `limit` (last axis reduced);
    jax.numpy or numpy (`xp`)."""
    finite = xp.all(xp.isfinite(qpos), -1) & xp.all(xp.isfinite(qvel), -1)
    return ~(finite & xp.all(xp.abs(qvel) < limit, -1))


def select_envs(mask, on_true, on_false):
    """Per-environment choice between two batched pytrees: `on_true` where mask (n,) is set (both engines' resets
    of finished environments)."""
    def pick(a, b):
        m = mask.reshape(mask.shape + (1,) * (a.ndim - 1))
        return jnp.where(m, a, b)
    return jax.tree_util.tree_map(pick, on_true, on_false)


def reject_divergence(data, previous, limit: float):
    """(bad, data): `bad` when stepped MJX `data` diverged (is_diverged); `data` is then replaced by
    `previous`, the last good state, so that a diverged environment never spreads NaNs."""
    bad = is_diverged(data.qpos, data.qvel, limit)
    return bad, jax.tree_util.tree_map(lambda new, old: jnp.where(bad, old, new), data, previous)
