"""The shared legged-robot environment: PD control, randomisation, observations, rewards, terminations.

Tasks subclass `LeggedEnv` and implement four hooks (`_task_reset`, `_command`, `_exteroception`,
`_task_step`). The engine verbs (`spawn`, `first_state`, `prepare`, `transition`; legged.envs.physics)
are the same code whether physics runs in MJX (`reset`/`step`, legged.envs.api) or in native MuJoCo
(legged.envs.native).
"""

from __future__ import annotations

import abc

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from brax.envs.base import State
from mujoco import mjx

from legged.envs.api import MjxEnv
from legged.envs.config import EnvConfig
from legged.envs.contacts import MjxContactReader
from legged.envs.physics import PhysicsView, Spawn
from legged.envs.math import quat_from_yaw, rotate_inv, up_z
from legged.envs.rewards import penalty_terms
from legged.robots.spec import RobotSpec
from legged.sensors.heightscan import surface_height
from legged.worlds.mjcf import SceneOptions, compile_scene
from legged.worlds.terrain import Terrain


def randomized_fields(base: dict, dr: dict, trunk: int, xp=jnp) -> dict:
    """Model fields after applying randomisation parameters `dr` to the nominal fields `base`.

    One function for both engines: jax.numpy for MJX models (per environment, under vmap) and numpy for
    native ones, where `dr` may carry a leading batch axis (one row per simulation).
    """
    scale = dr["mass_scale"]                                       # [..., nbody]
    is_trunk = xp.arange(scale.shape[-1]) == trunk
    mass = base["body_mass"] * scale
    mass_trunk = mass[..., trunk] + dr["base_mass"]
    ratio = xp.where(is_trunk, (mass_trunk / mass[..., trunk])[..., None], 1.0)
    inertia = base["body_inertia"] * (scale * ratio)[..., None]
    mass = xp.where(is_trunk, mass_trunk[..., None], mass)
    ipos = base["body_ipos"] + is_trunk[:, None] * xp.asarray(dr["com"])[..., None, :]
    pairs = base["pair_friction"]
    friction = xp.concatenate([xp.broadcast_to(xp.asarray(dr["friction"])[..., None, None], mass.shape[:-1] + (len(pairs), 2)),
                               xp.broadcast_to(pairs[:, 2:], mass.shape[:-1] + pairs[:, 2:].shape)], axis=-1)
    gain0, bias0 = base["actuator_gainprm"], base["actuator_biasprm"]
    strength = dr["strength"]                                      # [..., nu]
    kp = gain0[:, 0] * xp.asarray(dr["kp"])[..., None] * strength
    kd = -bias0[:, 2] * xp.asarray(dr["kd"])[..., None] * strength
    lead = strength.shape[:-1]
    gain = xp.concatenate([kp[..., None], xp.broadcast_to(gain0[:, 1:], lead + gain0[:, 1:].shape)], axis=-1)
    bias = xp.concatenate([xp.broadcast_to(bias0[:, :1], lead + (len(bias0), 1)), -kp[..., None], -kd[..., None],
                           xp.broadcast_to(bias0[:, 3:], lead + bias0[:, 3:].shape)], axis=-1)
    return dict(body_mass=mass, body_inertia=inertia, body_ipos=ipos, pair_friction=friction,
                actuator_gainprm=gain, actuator_biasprm=bias)


class LeggedEnv(MjxEnv, abc.ABC):
    """A Brax-compatible MJX environment for one legged robot on a terrain."""

    def __init__(self, robot: RobotSpec, terrain: Terrain, scene: SceneOptions, config: EnvConfig):
        self.robot, self.terrain, self.config, self.scene = robot, terrain, config, scene
        self.n_substeps = config.n_substeps
        self.mj_model = compile_scene(terrain, robot, scene)
        self.mj_model.opt.timestep = config.sim_dt
        self.mjx_model = mjx.put_model(self.mj_model)
        m = self.mj_model
        joints = [m.joint(n) for n in robot.joint_names]
        self._qadr = np.array([m.jnt_qposadr[j.id] for j in joints])
        self._vadr = np.array([m.jnt_dofadr[j.id] for j in joints])
        if list(m.actuator_trnid[:, 0]) != [j.id for j in joints]:
            raise ValueError(f"{robot.mjcf_path}: actuators must drive {robot.joint_names} in that order")
        self._trunk = m.body(robot.root_body).id
        self._default_pose = jnp.asarray(robot.default_pose, jnp.float32)
        self._ctrl_range = jnp.asarray(m.actuator_ctrlrange, jnp.float32)
        self._feet = np.array([m.geom(g).id for g in robot.feet_geoms])
        self._body_geoms = np.array([m.geom(g).id for g in robot.body_geoms])
        self._calf_bodies = np.array([m.geom_bodyid[m.geom(g).id] for g in robot.calf_geoms])
        self._contacts = MjxContactReader(m, self.mjx_model, np.concatenate([self._feet, self._body_geoms]))
        self._floor = jnp.asarray(terrain.floor)
        self._ceiling = jnp.asarray(terrain.ceiling)
        self._origin = jnp.asarray(terrain.origin, jnp.float32)
        self._base_fields = {k: jnp.asarray(getattr(m, k)) for k in (
            "body_mass", "body_inertia", "body_ipos", "pair_friction", "actuator_gainprm", "actuator_biasprm")}
        self._weight = float(m.body_subtreemass[self._trunk] * 9.81)
        self._foot_bodies = np.array(m.geom_bodyid[self._feet])
        self._foot_offsets = jnp.asarray(m.geom_pos[self._feet], jnp.float32)
        if config.history_steps < 0:
            raise ValueError(f"history_steps must be >= 0 (0: no history observation), got {config.history_steps}")
        push = config.randomization
        if push.push_interval_s < 0 or push.push_velocity < 0:
            raise ValueError(f"push_interval_s and push_velocity must be >= 0, got {push.push_interval_s} and "
                             f"{push.push_velocity}")

    # ----------------------------------------------------------------- task hooks
    @abc.abstractmethod
    def _task_reset(self, rng: jax.Array, carry: dict | None) -> tuple[jax.Array, jax.Array, dict]:
        """Spawn position (3,), yaw, and the task's entries of `info` (`carry`: see MjxEnv.spawn)."""

    @abc.abstractmethod
    def _command(self, data, info: dict) -> jax.Array:
        """The command part of the observation."""

    @abc.abstractmethod
    def _exteroception(self, data, info: dict) -> tuple[jax.Array, jax.Array]:
        """Clean exteroceptive observation (e.g. height scans) and its noise scale (same shape)."""

    @abc.abstractmethod
    def _task_step(self, data, info: dict, action: jax.Array) -> tuple[dict, jax.Array, dict, dict]:
        """Weighted reward terms, success flag, task metrics and updated info after a physics step."""

    @property
    def command_names(self) -> tuple[str, ...]:
        """Names of the command's components (observation layouts, warm starts)."""
        return ()

    def _task_privileged(self, data, info: dict) -> jax.Array:
        """Extra privileged observation of the task (default: none)."""
        return jnp.zeros(0)

    @property
    def success_is_truncation(self) -> bool:
        """Whether reaching the task's goal ends the episode as a truncation (its value bootstrapped) rather
        than as a terminal state; default no."""
        return False

    def _task_truncated(self, data, info: dict) -> jax.Array:
        """Whether the episode must end now without being the policy's fault (a truncation, like the time
        limit), e.g. the robot walked off the terrain; default never."""
        return jnp.bool_(False)

    # ----------------------------------------------------------------- helpers for tasks
    def floor_height(self, xy):
        """Exact floor height under world points xy (..., 2)."""
        return surface_height(self._floor, self._origin, self.terrain.resolution, xy)

    def ceiling_height(self, xy):
        """Exact ceiling height over world points xy (..., 2)."""
        return surface_height(self._ceiling, self._origin, self.terrain.resolution, xy, anti_diagonal=True)

    def base_rotation(self, data) -> jax.Array:
        """World-from-body rotation matrix of the base."""
        return data.xmat[self._trunk]

    def base_yaw(self, data) -> jax.Array:
        """Heading of the base."""
        rot = self.base_rotation(data)
        return jnp.arctan2(rot[1, 0], rot[0, 0])

    def joint_angles(self, data) -> jax.Array:
        """Actuated joint positions in policy order."""
        return data.qpos[self._qadr]

    def joint_velocities(self, data) -> jax.Array:
        """Actuated joint velocities in policy order."""
        return data.qvel[self._vadr]

    def feet_positions(self, data) -> jax.Array:
        """World positions of the foot geoms' centres, (n_feet, 3)."""
        rot = data.xmat[self._foot_bodies]
        return data.xpos[self._foot_bodies] + jnp.einsum("fij,fj->fi", rot, self._foot_offsets)

    @property
    def pushes(self) -> bool:
        """Whether episodes are pushed (randomisation on and a push interval set)."""
        c = self.config.randomization
        return c.enabled and c.push_interval_s > 0 and c.push_velocity > 0

    def _push(self, data: PhysicsView, info: dict, rng: jax.Array) -> tuple[PhysicsView, jax.Array]:
        """(view, pushed): every `push_interval_s` the body gets a random horizontal velocity kick (the engine
        then loads the changed velocity: info['teleported'])."""
        c = self.config.randomization
        period = max(1, int(round(c.push_interval_s / self.dt)))
        pushed = (info["step"] % period == 0) & ~data.diverged
        kick = jax.random.uniform(rng, (2,), minval=-c.push_velocity, maxval=c.push_velocity)
        return data.replace(qvel=data.qvel.at[0:2].add(jnp.where(pushed, kick, 0.0))), pushed

    # ----------------------------------------------------------------- randomisation and physics
    def randomize(self, rng: jax.Array) -> dict:
        """Sample dynamics randomisation parameters (nominal values when disabled)."""
        c, nb, nu = self.config.randomization, self.mj_model.nbody, self.mj_model.nu
        if not c.enabled:
            return dict(friction=jnp.float32(self._base_fields["pair_friction"][0, 0]), mass_scale=jnp.ones(nb),
                        base_mass=jnp.float32(0.0), com=jnp.zeros(3), strength=jnp.ones(nu),
                        kp=jnp.float32(1.0), kd=jnp.float32(1.0))
        k = jax.random.split(rng, 7)
        u = lambda key, r, shape=(): jax.random.uniform(key, shape, minval=r[0], maxval=r[1])
        return dict(friction=u(k[0], c.friction), mass_scale=u(k[1], c.link_mass_scale, (nb,)),
                    base_mass=u(k[2], c.base_mass_offset), com=u(k[3], (-c.com_offset, c.com_offset), (3,)),
                    strength=u(k[4], c.motor_strength, (nu,)), kp=u(k[5], c.kp_scale), kd=u(k[6], c.kd_scale))

    def model_with(self, dr: dict):
        """The MJX model with randomisation `dr` applied (the nominal model when disabled)."""
        if not self.config.randomization.enabled:
            return self.mjx_model
        return self.mjx_model.replace(**randomized_fields(self._base_fields, dr, self._trunk))

    def joint_targets(self, action: jax.Array) -> jax.Array:
        """PD targets (actuator controls) for an action."""
        a = jnp.clip(action, -self.config.action_clip, self.config.action_clip)
        target = self._default_pose + self.robot.action_scale * a
        return jnp.clip(target, self._ctrl_range[:, 0], self._ctrl_range[:, 1])

    # ----------------------------------------------------------------- engine verbs and read-outs
    def mjx_model_for(self, info: dict):
        return self.model_with(info["dr"])

    def native_model_fields(self, info: dict, rows: np.ndarray) -> dict:
        if not self.config.randomization.enabled:
            return {}
        dr = jax.tree_util.tree_map(lambda x: np.asarray(x)[rows], info["dr"])
        nominal = {k: np.array(v) for k, v in self._base_fields.items()}
        return randomized_fields(nominal, dr, self._trunk, xp=np)

    @property
    def watched_geoms(self) -> np.ndarray:
        return np.concatenate([self._feet, self._body_geoms])

    def native_model(self) -> mujoco.MjModel:
        """The scene with a contact sensor on every watched geom, for the native engine."""
        names = tuple(self.robot.feet_geoms) + tuple(self.robot.body_geoms)
        model = compile_scene(self.terrain, self.robot, self.scene, contact_sensors=names)
        model.opt.timestep = self.config.sim_dt
        return model

    def contact_forces(self, data) -> jax.Array:
        """Normal contact force on each foot, then on each body geom (N), of an MJX data."""
        return self._contacts(data)

    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        rng, k_dr, k_task = jax.random.split(rng, 3)
        dr = self.randomize(k_dr)
        pos, yaw, task_info = self._task_reset(k_task, carry)
        qpos = jnp.zeros(self.mj_model.nq).at[0:3].set(pos).at[3:7].set(quat_from_yaw(yaw))
        qpos = qpos.at[self._qadr].set(self._default_pose)
        info = dict(rng=rng, dr=dr, last_action=jnp.zeros(self.action_size), last_qvel=jnp.zeros(self.action_size),
                    step=jnp.int32(0), collisions=jnp.float32(0.0), touching=jnp.zeros(1 + len(self._calf_bodies), bool),
                    truncation=jnp.float32(0.0), **task_info)
        if self.pushes:
            info["teleported"] = jnp.bool_(False)
        return Spawn(qpos=qpos, qvel=jnp.zeros(self.mj_model.nv), ctrl=self._default_pose, info=info)

    def first_state(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        obs, info = self._observe(view, info, rng)
        metrics = self.zero_metrics(view, info, info["last_action"])
        return State(view, obs, jnp.float32(0.0), jnp.float32(0.0), metrics, info)

    def prepare(self, state: State, action: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.joint_targets(action), action

    # ----------------------------------------------------------------- shared transition
    def transition(self, state: State, data: PhysicsView, action: jax.Array) -> State:
        """Next State from the view of stepped physics (MJX or native); pure and jittable."""
        cfg = self.config
        bad = data.diverged
        forces = jnp.where(bad, 0.0, data.contact_force)
        info = dict(state.info)
        info["rng"], k_noise, k_push = jax.random.split(info["rng"], 3)
        info["step"] = info["step"] + 1
        action = jnp.where(bad, 0.0, action)
        if self.pushes:
            data, info["teleported"] = self._push(data, info, k_push)

        terms, success, task_metrics, info = self._task_step(data, info, action)
        body_touch = forces[len(self._feet):] > 1e-6
        knee_touch = self._knee_contacts(data)
        collisions = jnp.sum(body_touch) + jnp.sum(knee_touch)  # contacts this step (the penalty)
        touching = jnp.concatenate([jnp.any(body_touch)[None], knee_touch])  # trunk, each knee
        info["collisions"] = info["collisions"] + jnp.sum(touching & ~info["touching"])  # contacts that begin
        info["touching"] = touching
        qd = self.joint_velocities(data)
        terms.update(self._penalties(data, info, action, qd, collisions))

        base = data.xpos[self._trunk]
        height = base[2] - self.floor_height(base[:2])
        fell = (height < cfg.fall_height) | (up_z(self.base_rotation(data)) < cfg.flip_up_z)
        time_out = (info["step"] >= cfg.episode_steps) | self._task_truncated(data, info)
        done = fell | success | time_out | bad
        reward = sum(terms.values())
        if cfg.only_positive_rewards:
            reward = jnp.maximum(reward, 0.0)
        reward = jnp.where(bad, 0.0, reward)
        ended_well = (time_out | success) if self.success_is_truncation else (time_out & ~success)
        info["truncation"] = (ended_well & ~fell & ~bad).astype(jnp.float32)
        info["last_action"], info["last_qvel"] = action, qd
        obs, info = self._observe(data, info, k_noise)
        metrics = {f"reward/{k}": v for k, v in terms.items()}
        metrics.update(task_metrics, diverged=bad.astype(jnp.float32), fell=fell.astype(jnp.float32),
                       collisions=info["collisions"], base_height=height)
        return state.replace(pipeline_state=data, obs=obs, reward=reward.astype(jnp.float32),
                             done=done.astype(jnp.float32), metrics=metrics, info=info)

    def _knee_contacts(self, data) -> jax.Array:
        """Whether each knee touches floor or ceiling, checked exactly against the height maps (2 cm radius)."""
        knees = data.xpos[self._calf_bodies]
        low = knees[:, 2] - 0.02 < self.floor_height(knees[:, :2])
        high = knees[:, 2] + 0.02 > self.ceiling_height(knees[:, :2])
        return low | high

    def _penalties(self, data, info, action, qd, collisions) -> dict:
        """Penalty terms shared by all tasks (scales from the task config's `penalties`)."""
        return penalty_terms(self.penalty_scales, self.joint_angles(data), self.mj_model.jnt_range[1:], qd,
                             info["last_qvel"], self.dt, data.actuator_force, action, info["last_action"], collisions)

    @property
    @abc.abstractmethod
    def penalty_scales(self):
        """The task's PenaltyScales."""

    # ----------------------------------------------------------------- observations
    def _observation_parts(self, data: PhysicsView, info) -> tuple[list, list]:
        """Named pieces of `state` as (name, clean value, noise scale) and of `privileged_state` after the
        clean `state` as (name, value), in order."""
        noise = self.config.noise
        rot = self.base_rotation(data)
        q = self.joint_angles(data) - self._default_pose
        qd = self.joint_velocities(data)
        ext, ext_noise = self._exteroception(data, info)
        cmd = self._command(data, info)
        state = [("gravity", rotate_inv(rot, jnp.array([0.0, 0.0, -1.0])), jnp.full(3, noise.gravity))]
        if self.config.gyro_in_state:
            state.append(("gyro", data.qvel[3:6], jnp.full(3, noise.gyro)))
        state += [("command", cmd, jnp.zeros_like(cmd)),
                  ("joint_pos", q, jnp.full_like(q, noise.joint_pos)),
                  ("joint_vel", qd, jnp.full_like(qd, noise.joint_vel)),
                  ("last_action", info["last_action"], jnp.zeros(self.action_size)),
                  ("exteroception", ext, ext_noise)]
        dr = info["dr"]
        privileged = [("base_lin_vel", rotate_inv(rot, data.qvel[0:3])), ("base_ang_vel", data.qvel[3:6]),
                      ("contact_forces", data.contact_force / self._weight),
                      ("dynamics", jnp.stack([dr["friction"], dr["base_mass"], dr["kp"], dr["kd"]])),
                      ("com", dr["com"]), ("motor_strength", dr["strength"]),
                      ("task", self._task_privileged(data, info))]
        return state, privileged

    def _observe(self, data: PhysicsView, info, rng) -> tuple[dict, dict]:
        """(observations, info): `state`, `privileged_state` and, with `history_steps`, `history` (the last
        states, kept in info['history']; a new episode's history repeats its first state)."""
        state_parts, privileged_parts = self._observation_parts(data, info)
        clean = jnp.concatenate([v for _, v, _ in state_parts])
        state = clean
        if self.config.noise.enabled:
            scales = jnp.concatenate([n for _, _, n in state_parts])
            state = clean + scales * jax.random.uniform(rng, clean.shape, minval=-1, maxval=1)
        privileged = jnp.concatenate([clean] + [v for _, v in privileged_parts])
        obs = {"state": state, "privileged_state": privileged}
        if self.config.history_steps:
            past = info.get("history")
            if past is None:
                past = jnp.broadcast_to(state, (self.config.history_steps,) + state.shape)
            history = jnp.concatenate([past[1:], state[None]])
            info = dict(info, history=history)
            obs["history"] = history.reshape(-1)
        return obs, info

    def observation_layout(self) -> dict:
        """Named slices of each observation: {"state": [(name, size), ...], "privileged_state": [...]}
        (the privileged one begins with the clean `state`), traced without compiling."""
        if self.__dict__.get("_layout") is None:
            names = {}
            def sizes(key):
                view, info, _ = self.spawned_mjx(key)
                parts, privileged = self._observation_parts(view, info)
                names["state"] = [n for n, _, _ in parts]
                names["privileged"] = [n for n, _ in privileged]
                return [v for _, v, _ in parts], [v for _, v in privileged]
            shapes = jax.eval_shape(sizes, jax.random.PRNGKey(0))
            state = []
            for n, v in zip(names["state"], shapes[0]):
                size = int(np.prod(v.shape))
                if n == "command" and len(self.command_names) == size:
                    state += [(f"command/{c}", 1) for c in self.command_names]
                else:
                    state.append((n, size))
            privileged = [(f"state/{n}", k) for n, k in state]
            privileged += [(n, int(np.prod(v.shape))) for n, v in zip(names["privileged"], shapes[1])]
            self._layout = {"state": state, "privileged_state": privileged}
        return self._layout
