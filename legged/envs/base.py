"""The shared legged-robot environment: PD control, randomisation, observations, rewards, terminations.

Tasks subclass `LeggedEnv` and implement four hooks (`_task_reset`, `_command`, `_exteroception`,
`_task_step`). The engine verbs (`spawn`, `first_state`, `prepare`, `transition`; legged.envs.physics)
are the same code whether physics runs in MJX (`reset`/`step`, legged.envs.api) or in native MuJoCo
(legged.envs.native).
"""

from __future__ import annotations

import abc
import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from brax.envs.base import State
from mujoco import mjx

from legged.envs.api import MjxEnv
from legged.envs.config import EnvConfig
from legged.envs.engine_models import EngineModels
from legged.envs.events import fall_events
from legged.envs.physics import PhysicsView, Spawn
from legged.envs.math import quat_from_yaw, rotate_inv, up_z
from legged.envs.motor import motor_limits, servo_gains, within_motor_curve
from legged.envs.rewards import penalty_terms, step_reward
from legged.envs.randomize import (CONE_DR, MODEL_DR, check_latency, draw, late_controls, nominal_draw,
                                   weakened)
from legged.robots.models import robot_model
from legged.robots.spec import RobotSpec
from legged.sensors.heightscan import surface_height
from legged.worlds.mjcf import SceneOptions, compile_scene
from legged.worlds.terrain import Terrain


PAST_PARTS = ("joint_pos", "joint_vel", "last_action")
"""The `state` entries `EnvConfig.past_steps` remembers, in the order they appear as past_<name>."""


class LeggedEnv(EngineModels, MjxEnv, abc.ABC):
    """A Brax-compatible MJX environment for one legged robot on a terrain."""

    def __init__(self, robot: RobotSpec, terrain: Terrain, scene: SceneOptions, config: EnvConfig):
        robot = robot_model(robot, config.robot_model, config.ctrl_dt)
        if len(robot.feet_geoms) != len(robot.feet_sites):
            raise ValueError(f"{robot.source} {robot.name} model: {len(robot.feet_geoms)} foot collision geoms for "
                             f"{len(robot.feet_sites)} feet; this task reads one per foot (name one per foot "
                             f"{', '.join(robot.feet_sites)})")
        if robot.timestep is not None:  # the model's own physics step (a whole number per control step)
            config = dataclasses.replace(config, sim_dt=robot.timestep)
        if config.randomization.enabled and config.randomization.contact_spin is not None:
            scene = dataclasses.replace(scene, foot_condim=6)  # spin and roll friction drawn on condim-6 feet
        if config.randomization.enabled:
            check_latency(config.randomization.latency_s, config.sim_dt, config.ctrl_dt)
        self.robot, self.terrain, self.config, self.scene = robot, terrain, config, scene
        self.n_substeps = config.n_substeps
        self.mj_model = compile_scene(terrain, robot, scene)
        self.mj_model.opt.timestep = config.sim_dt
        m = self.mj_model
        joints = [m.joint(n) for n in robot.joint_names]
        self._qadr = np.array([m.jnt_qposadr[j.id] for j in joints])
        self._joint_range = np.array([m.jnt_range[j.id] for j in joints])
        self._vadr = np.array([m.jnt_dofadr[j.id] for j in joints])
        if list(m.actuator_trnid[:, 0]) != [j.id for j in joints]:
            raise ValueError(f"{robot.mjcf_path}: actuators must drive {robot.joint_names} in that order")
        self._trunk = m.body(robot.root_body).id
        self._default_pose = jnp.asarray(robot.default_pose, jnp.float32)
        self._ctrl_range = jnp.asarray(m.actuator_ctrlrange, jnp.float32)
        self._force_limit, self._motor_speeds = motor_limits(m, robot, np.arange(m.nu), config.motor_curve)
        self._feet = np.array([m.geom(g).id for g in robot.feet_geoms])
        self._body_geoms = np.array([m.geom(g).id for g in robot.body_geoms])
        self._calf_bodies = np.array(list(dict.fromkeys(m.geom_bodyid[m.geom(g).id] for g in robot.calf_geoms)))
        # A model whose trunk has other collision geoms than the project's pools their forces into the project's
        # trunk slots, so that observations keep their size on every model (RobotSpec.body_slots).
        self._body_pool = None
        if robot.body_slot_count:
            self._body_pool = jnp.asarray(np.eye(robot.num_body_slots, dtype=np.float32)[list(robot.body_slots)])
        self._floor = jnp.asarray(terrain.floor)
        self._ceiling = jnp.asarray(terrain.ceiling)
        self._origin = jnp.asarray(terrain.origin, jnp.float32)
        self._base_fields = {k: jnp.asarray(getattr(m, k)) for k in (
            "body_mass", "body_inertia", "body_ipos", "pair_friction", "actuator_gainprm", "actuator_biasprm",
            "dof_damping", "dof_armature", "dof_frictionloss", "pair_solref", "pair_solimp", "pair_margin")}
        self._base_fields["joint_dofs"] = jnp.asarray(np.eye(m.nv, dtype=np.float32)[self._vadr])
        self._base_fields["cone"] = jnp.asarray(m.opt.cone, jnp.int32)
        self._base_fields["foot_pairs"] = jnp.asarray(np.isin(m.pair_geom1, self._feet) | np.isin(m.pair_geom2, self._feet),
                                                      jnp.float32)
        self._nominal_dr = nominal_draw(self._base_fields, self._base_fields["pair_friction"][0, 0], m.opt.impratio)
        self._weight = float(m.body_subtreemass[self._trunk] * 9.81)
        self._foot_bodies = np.array(m.geom_bodyid[self._feet])
        self._foot_offsets = jnp.asarray(m.geom_pos[self._feet], jnp.float32)
        for name in ("history_steps", "past_steps"):
            if getattr(config, name) < 0:
                raise ValueError(f"{name} must be >= 0 (0: none), got {getattr(config, name)}")
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

    def _task_failed(self, data, info: dict) -> jax.Array:
        """Whether the episode must end now as the policy's failure (not bootstrapped, like a fall), e.g. it stood
        still too long; default never."""
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
        kick = jax.random.uniform(rng, (2,), minval=-c.push_velocity, maxval=c.push_velocity) * info["dr_scale"]
        return data.replace(qvel=data.qvel.at[0:2].add(jnp.where(pushed, kick, 0.0))), pushed

    # ----------------------------------------------------------------- randomisation and physics
    def randomize(self, rng: jax.Array) -> dict:
        """Sample dynamics randomisation parameters (legged.envs.randomize.draw)."""
        m = self.mj_model
        nominal_friction = self._base_fields["pair_friction"][0, 0]
        return draw(self.config.randomization, rng, m.nbody, m.nu, self.config.sim_dt, self.n_substeps,
                    nominal_friction)

    def joint_targets(self, action: jax.Array) -> jax.Array:
        """PD targets (actuator controls) for an action."""
        a = jnp.clip(action, -self.config.action_clip, self.config.action_clip)
        target = self._default_pose + self.robot.action_scale * a
        return jnp.clip(target, self._ctrl_range[:, 0], self._ctrl_range[:, 1])

    # ----------------------------------------------------------------- engine verbs and read-outs
    def slot_forces(self, forces: jax.Array) -> jax.Array:
        """Watched-geom normal forces (feet, then trunk geoms) as the observations hold them: feet, then the trunk
        geoms pooled into the project model's trunk slots where the model's differ."""
        if self._body_pool is None:
            return forces
        n = len(self._feet)
        return jnp.concatenate([forces[..., :n], forces[..., n:] @ self._body_pool], -1)

    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        """A new episode; a carried `dr_scale` (a training run's randomisation ramp or curriculum,
        TrainConfig.randomization_ramp and randomization_curriculum) moves its randomisation that part of the way
        from the nominal robot to the draw, pushes included; a carried `dr_step` (the curriculum's) stays in `info`
        for the next episode's scale (legged.envs.api.next_carry)."""
        rng, k_dr, k_task = jax.random.split(rng, 3)
        dr = self.randomize(k_dr)
        ramped = carry is not None and "dr_scale" in carry
        scale = carry["dr_scale"] if ramped else jnp.float32(1.0)
        if ramped and self.config.randomization.enabled:
            dr = weakened(dr, self._nominal_dr, scale)
        pos, yaw, task_info = self._task_reset(k_task, carry)
        qpos = jnp.zeros(self.mj_model.nq).at[0:3].set(pos).at[3:7].set(quat_from_yaw(yaw))
        qpos = qpos.at[self._qadr].set(self._default_pose)
        info = dict(rng=rng, dr=dr, last_action=jnp.zeros(self.action_size), last_qvel=jnp.zeros(self.action_size),
                    step=jnp.int32(0), collisions=jnp.float32(0.0), touching=jnp.zeros(1 + len(self._calf_bodies), bool),
                    truncation=jnp.float32(0.0), dr_scale=scale, **task_info)
        if ramped and "dr_step" in carry:  # a randomisation curriculum: the scale moves with each episode's outcome
            info["dr_step"] = carry["dr_step"]
        if self.pushes:
            info["teleported"] = jnp.bool_(False)
        return Spawn(qpos=qpos, qvel=jnp.zeros(self.mj_model.nv), ctrl=self._default_pose, info=info)

    def first_state(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        obs, info = self._observe(view, info, rng)
        metrics = self.zero_metrics(view, info, info["last_action"])
        return State(view, obs, jnp.float32(0.0), jnp.float32(0.0), metrics, info)

    def prepare(self, state: State, action: jax.Array) -> tuple[jax.Array, jax.Array]:
        """Joint targets for the control step; with action latency, a schedule (n_substeps, nu) whose first
        `latency` physics steps keep the previous control step's targets (legged.envs.randomize.late_controls)."""
        targets = self._servo_targets(state, action)
        latency = state.info["dr"].get("latency")
        if latency is None:
            return targets, action
        # the previous step's action, within the motors' torque-speed lines at the joints' state now
        previous = self._servo_targets(state, state.info["last_action"])
        return late_controls(previous, targets, latency, self.n_substeps), action

    def _servo_targets(self, state: State, action: jax.Array) -> jax.Array:
        """The joint targets of `action`, kept within the motors' torque-speed lines with `motor_curve`."""
        targets = self.joint_targets(action)
        return self._within_motor_curve(state, targets) if self.config.motor_curve else targets

    def _within_motor_curve(self, state: State, targets: jax.Array) -> jax.Array:
        """Joint targets whose PD torque, at the joint angles and velocities the control step starts from (with the
        episode's gains), stays on the motors' side of their torque-speed lines (EnvConfig.motor_curve)."""
        data, dr = state.pipeline_state, state.info["dr"]
        q, qd = data.qpos[self._qadr], data.qvel[self._vadr]
        kp, kd = servo_gains(self._base_fields["actuator_gainprm"], self._base_fields["actuator_biasprm"], dr["kp"],
                             dr["kd"], dr["strength"])
        return within_motor_curve(targets, q, qd, kp, kd, self._force_limit, self._motor_speeds)

    # ----------------------------------------------------------------- shared transition
    def transition(self, state: State, data: PhysicsView, action: jax.Array) -> State:
        """Next State from the view of stepped physics (MJX or native); pure and jittable."""
        cfg = self.config
        bad = data.diverged
        forces = jnp.where(bad, 0.0, self.slot_forces(data.contact_force))
        info = dict(state.info)
        info["rng"], k_noise, k_push = jax.random.split(info["rng"], 3)
        info["step"] = info["step"] + 1
        action = jnp.where(bad, 0.0, jnp.clip(action, -cfg.action_clip, cfg.action_clip))  # the action applied
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
        failed = self._task_failed(data, info)
        done = fell | failed | success | time_out | bad
        reward = step_reward(terms, fell | failed, cfg.only_positive_rewards, cfg.failure_penalty)
        reward = jnp.where(bad, 0.0, reward)
        ended_well = (time_out | success) if self.success_is_truncation else (time_out & ~success)
        info["truncation"] = (ended_well & ~fell & ~failed & ~bad).astype(jnp.float32)
        info["last_action"], info["last_qvel"] = action, qd
        obs, info = self._observe(data, info, k_noise)
        metrics = {f"reward/{k}": v for k, v in terms.items()}
        metrics.update(task_metrics, diverged=bad.astype(jnp.float32), fell=fell.astype(jnp.float32),
                       collisions=info["collisions"], base_height=height, **fall_events(fell, fell, self.dt))
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
        return penalty_terms(self.penalty_scales, self.joint_angles(data), self._joint_range, qd,
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
        state = []
        if self.config.velocity_in_state:  # as a state estimator gives it
            state.append(("lin_vel", rotate_inv(rot, data.qvel[0:3]), jnp.full(3, noise.lin_vel)))
        state.append(("gravity", rotate_inv(rot, jnp.array([0.0, 0.0, -1.0])), jnp.full(3, noise.gravity)))
        if self.config.gyro_in_state:
            state.append(("gyro", data.qvel[3:6], jnp.full(3, noise.gyro)))
        state += [("command", cmd, jnp.zeros_like(cmd)),
                  ("joint_pos", q, jnp.full_like(q, noise.joint_pos)),
                  ("joint_vel", qd, jnp.full_like(qd, noise.joint_vel)),
                  ("last_action", info["last_action"], jnp.zeros(self.action_size))]
        if self.config.past_steps:  # as observed then (noise and biases included): no noise of their own
            past = info.get("past")
            if past is None:  # a new episode: its first values repeated
                past = jnp.broadcast_to(jnp.stack([q, qd, info["last_action"]])[:, None],
                                        (3, self.config.past_steps, q.shape[0]))
            state += [(f"past_{n}", past[i].reshape(-1), jnp.zeros(past[i].size))
                      for i, n in enumerate(PAST_PARTS)]
        state.append(("exteroception", ext, ext_noise))
        dr = info["dr"]
        privileged = [("base_lin_vel", rotate_inv(rot, data.qvel[0:3])), ("base_ang_vel", data.qvel[3:6]),
                      ("contact_forces", self.slot_forces(data.contact_force) / self._weight),
                      ("dynamics", jnp.stack([dr["friction"], dr["base_mass"], dr["kp"], dr["kd"]])),
                      ("com", dr["com"]), ("motor_strength", dr["strength"]),
                      ("task", self._task_privileged(data, info))]
        drawn = [jnp.atleast_1d(dr[k] * (self.config.sim_dt if k == "latency" else 1)).astype(jnp.float32)
                 for k in MODEL_DR if k in dr]  # the latency in seconds: a physics step's length varies by model
        if drawn:  # the model randomisation, where a run draws it (after the older entries, which keep their place)
            privileged.append(("model_dynamics", jnp.concatenate(drawn)))
        cone = [jnp.log(dr[k]) / jnp.log(100.0) if k == "impratio" else dr[k] for k in CONE_DR if k in dr]
        if cone:  # the solver's friction cone (impratio on a log scale: 0 at 1, 1 at 100)
            privileged.append(("friction_cone", jnp.stack(cone).astype(jnp.float32)))
        return state, privileged

    def _observe(self, data: PhysicsView, info, rng) -> tuple[dict, dict]:
        """(observations, info): `state`, `privileged_state` and, with `history_steps`, `history` (the last
        states, kept in info['history']; a new episode's history repeats its first state)."""
        state_parts, privileged_parts = self._observation_parts(data, info)
        clean = jnp.concatenate([v for _, v, _ in state_parts])
        state = clean + self._sensor_bias(state_parts, info["dr"])
        if self.config.noise.enabled:
            scales = jnp.concatenate([n for _, _, n in state_parts])
            state = state + scales * jax.random.uniform(rng, clean.shape, minval=-1, maxval=1)
        privileged = jnp.concatenate([clean] + [v for _, v in privileged_parts])
        obs = {"state": state, "privileged_state": privileged}
        if self.config.history_steps:
            past = info.get("history")
            if past is None:
                past = jnp.broadcast_to(state, (self.config.history_steps,) + state.shape)
            history = jnp.concatenate([past[1:], state[None]])
            info = dict(info, history=history)
            obs["history"] = history.reshape(-1)
        if self.config.past_steps:
            info = dict(info, past=self._remember(state_parts, state, info))
        return obs, info

    def _remember(self, state_parts: list, state: jax.Array, info) -> jax.Array:
        """The `past_steps` memory after this step: the oldest entry dropped, this step's observed joint angles,
        joint velocities and last action appended (3 x past_steps x joints)."""
        start, now = 0, {}
        for name, value, _ in state_parts:
            now[name] = state[start:start + value.shape[0]]
            start += value.shape[0]
        current = jnp.stack([now[n] for n in PAST_PARTS])
        past = info.get("past")
        if past is None:
            return jnp.broadcast_to(current[:, None], (3, self.config.past_steps) + current.shape[1:])
        return jnp.concatenate([past[:, 1:], current[:, None]], axis=1)

    @staticmethod
    def _sensor_bias(state_parts: list, dr: dict) -> jax.Array | float:
        """The episode's constant sensor biases laid out like `state`: encoder offsets on the joint angles, the
        IMU's on the projected gravity and the angular velocity (0. where none is drawn)."""
        biased = {"joint_pos": "encoder_offset", "gravity": "gravity_bias", "gyro": "gyro_bias"}
        if not any(biased[n] in dr for n, _, _ in state_parts if n in biased):
            return 0.0
        return jnp.concatenate([dr[biased[n]] if biased.get(n) in dr else jnp.zeros_like(v) for n, v, _ in state_parts])

    def _spawned_view(self, rng: jax.Array) -> tuple[PhysicsView, dict]:
        """(view, info) of a spawned episode with zeros for every derived field: its shapes, for tracing
        observations without an engine (native-only robot models have no MJX model)."""
        spawn = self.spawn(rng)
        m = self.mj_model
        view = PhysicsView(qpos=spawn.qpos, qvel=spawn.qvel, ctrl=spawn.ctrl, xpos=jnp.zeros((m.nbody, 3)),
                           xmat=jnp.zeros((m.nbody, 3, 3)), actuator_force=jnp.zeros(m.nu),
                           contact_force=jnp.zeros(len(self.watched_geoms)), diverged=jnp.bool_(False))
        return view, spawn.info

    @property
    def observation_size(self) -> dict:
        """Shape of each observation (traced once from a spawned episode, without compiling or an engine)."""
        if self.__dict__.get("_obs_size") is None:
            def first(rng):
                view, info = self._spawned_view(rng)
                return self.start_episode(view, info, rng).obs
            shapes = jax.eval_shape(first, jax.random.PRNGKey(0))
            self._obs_size = {k: v.shape for k, v in shapes.items()}
        return self._obs_size

    def observation_layout(self) -> dict:
        """Named slices of each observation: {"state": [(name, size), ...], "privileged_state": [...]}
        (the privileged one begins with the clean `state`), traced without compiling."""
        if self.__dict__.get("_layout") is None:
            names = {}
            def sizes(key):
                view, info = self._spawned_view(key)
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
