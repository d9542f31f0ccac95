"""Multi-agent MJX soccer: teams of OP3 humanoids, a leading agent axis on actions, observations, rewards.

`SoccerEnv` is Brax-style (`reset(rng) -> State`, `step(state, actions) -> State`, pure, jittable,
vmappable) with actions [n_agents, 20] (joint-position offsets from the default pose, as for every robot
here). `State.obs` holds, per agent (leading axis): `state` (the deployable observation: proprioception
plus the game in the agent's heading frame; proprioception only in vision mode), `privileged_state`
(everything in `state` without noise plus ground truth for critics and teachers), and in vision mode
`camera` ([n_agents, 4, H, W]: RGB and depth from the head camera) and `features` (the state task's
`state` without noise, which a state teacher reads while its vision student learns). `State.reward` is [n_agents];
`State.metrics` holds each weighted reward term as `reward/<term>` [n_agents], the falls and get-ups of the step as
`events/<name>` [n_agents] (legged.envs.events) and the game's statistics.

The game: a goal scores +-1 and play restarts from the kick-off poses (or the episode ends, with
`end_on_goal`); a ball over a line outside a goal is put back at rest just inside that line; a robot
falls when its torso is low or tilted (`end_on_fall` says whose fall ends the episode); the time limit is a
truncation. The engine verbs (legged.envs.physics) are shared by MJX stepping and native MuJoCo stepping
(legged.envs.native); a restart moves bodies in the view and sets `info['teleported']`.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import State
from mujoco import mjx

from legged.envs.api import MjxEnv
from legged.envs.events import fall_events, getup_events
from legged.envs.motor import motor_limits, servo_gains, within_motor_curve
from legged.envs.physics import PhysicsView, Spawn
from legged.envs.randomize import MODEL_DR, check_latency, late_controls
from legged.robots.models import mjx_model_of, robot_model
from legged.robots.op3 import OP3
from legged.robots.spec import RobotSpec
from legged.sensors.native_raycam import render_anywhere
from legged.soccer import observe, randomize, rules
from legged.soccer.config import SoccerConfig
from legged.soccer.layout import SoccerLayout
from legged.soccer.pitch import goal_centres, kickoff_poses
from legged.soccer.placo.player import initial_memory
from legged.soccer.rewards import reward_terms
from legged.soccer.scene import build_soccer_scene
from legged.soccer.vision.cameras import soccer_camera
from legged.soccer.vision.estimate_noise import (blurred, first_error, first_sighting, held_ball, next_error,
                                                 next_sighting)
from legged.soccer.vision.sightings import (BALL_MIN_SHADE, NET_MIN_SHADE, SIGHTED, SIGHTING_SIZE, camera_agents,
                                            pixel_points, sighting)
from legged.soccer.walker import WALKER_STATE_SIZE, getting_up


class SoccerEnv(MjxEnv):
    """A soccer game of `config.scene.players_per_team` OP3s per team, stepped in MJX."""

    def __init__(self, config: SoccerConfig = SoccerConfig(), robot: RobotSpec = OP3):
        robot = robot_model(robot, config.robot_model, config.ctrl_dt)  # the OP3 model every player uses
        if robot.timestep is not None:  # that model's own physics step (a whole number per control step)
            config = dataclasses.replace(config, sim_dt=robot.timestep)
        self.config, self.robot = config, robot
        self.n_substeps = config.n_substeps
        if config.randomization.enabled:
            check_latency(config.randomization.latency_s, config.sim_dt, config.ctrl_dt)
        m = build_soccer_scene(config.scene, robot)
        m.opt.timestep = config.sim_dt
        self.mj_model = m
        self.layout = layout = SoccerLayout.from_model(m, robot)
        self.n_agents = layout.n_agents
        self._team = layout.team
        self._others = observe.others_of(layout)
        self._goals = goal_centres(config.scene)
        self._kickoff = jnp.asarray(kickoff_poses(config.scene), jnp.float32)
        self._qpos0 = jnp.asarray(layout.kickoff_qpos(m, kickoff_poses(config.scene), robot), jnp.float32)
        self._ctrl0 = jnp.asarray(layout.default_ctrl(m, robot), jnp.float32)
        self._default_pose = jnp.asarray(robot.default_pose, jnp.float32)
        self._ctrl_range = jnp.asarray(m.actuator_ctrlrange[layout.actuator_ids], jnp.float32)  # [A, J, 2]
        joint_ids = np.searchsorted(m.jnt_qposadr, layout.joint_qpos_adr)
        self._q_range = jnp.asarray(m.jnt_range[joint_ids], jnp.float32)  # [A, J, 2]
        self._ball_radius = float(config.scene.ball_radius)
        self._dynamics = randomize.SoccerDynamics.of(m, layout)
        self._base_fields = {k: jnp.asarray(getattr(m, k)) for k in randomize.FIELDS}
        self._force_limit, self._motor_speeds = motor_limits(m, robot, layout.actuator_ids, config.motor_curve)
        self.camera = soccer_camera(m, config.camera, layout) if config.vision else None

    @functools.cached_property
    def mjx_model(self):
        """The game in MJX, built on first use (native physics never needs it); an error naming the cause for a
        robot model MJX cannot run."""
        with jax.ensure_compile_time_eval():  # concrete arrays even when first needed inside a traced function
            return mjx_model_of(self.mj_model, self.robot)

    # ----------------------------------------------------------------- engine verbs (reset, step: MjxEnv)
    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        """A new game: robots around their kick-off spots, the ball on the pitch (see SoccerConfig)."""
        k_dr = jax.random.fold_in(rng, 7)  # (the start's keys are those of earlier versions)
        rng, k_start = jax.random.split(rng)
        qpos, qvel = self.start_state(k_start)
        info = self._initial_info(rng)
        if self.config.estimate_noise.enabled:
            info["estimate_error"] = first_error(jax.random.fold_in(rng, 11), self.n_agents, self.n_agents - 1)
        if self.config.estimate_noise.enabled and self.config.estimate_noise.sight:
            info["ball_sighting"] = first_sighting(self.n_agents)
        info["dr"] = randomize.sample(k_dr, self.config.randomization, self.mj_model, self.config.scene.ball_mass,
                                      self.n_agents, self.action_size, self.n_substeps)
        return Spawn(qpos=qpos, qvel=qvel, ctrl=self._ctrl0, info=info)

    def mjx_model_for(self, info: dict):
        """The MJX model with the episode's randomisation applied (the nominal one when it is off)."""
        if not self.config.randomization.enabled:
            return self.mjx_model
        return self.mjx_model.replace(**randomize.randomized_fields(self._base_fields, info["dr"], self._dynamics))

    def native_model_fields(self, info: dict, rows: np.ndarray) -> dict:
        if not self.config.randomization.enabled:
            return {}
        dr = jax.tree_util.tree_map(lambda x: np.asarray(x)[rows], info["dr"])
        nominal = {k: np.array(v) for k, v in self._base_fields.items()}
        return randomize.randomized_fields(nominal, dr, self._dynamics, xp=np)

    def start_state(self, rng: jax.Array):
        """qpos, qvel of a new game (rules.start_state); `spawn(key)` uses the second of split(key)."""
        return rules.start_state(rng, self.config, self._qpos0, self._kickoff, self.layout,
                                 self.robot.standing_height, self.mj_model.nv)

    def first_state(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        obs = self._observe(view, info, rng)
        metrics = self.zero_metrics(view, info, info["last_action"])
        return State(view, obs, jnp.zeros(self.n_agents), jnp.float32(0.0), metrics, info)

    def prepare(self, state: State, action: jax.Array) -> tuple[jax.Array, jax.Array]:
        """PD targets of every actuator for actions [n_agents, action_size] (a schedule with action latency)."""
        return self.servo_controls(state, self.joint_targets(action)), action

    def servo_controls(self, state: State, ctrl: jax.Array) -> jax.Array:
        """What the servos get for the joint targets `ctrl`: with `motor_curve` the targets whose torque stays within
        the motors' torque-speed lines (legged.envs.motor), and with action latency drawn a schedule (n_substeps, nu)
        whose first physics steps keep each robot's previous targets, as many as its latency (the previous actions'
        targets, within the motor lines at the joints' state now: legged.envs.randomize.late_controls)."""
        ctrl = self._within_motor_curve(state, ctrl)
        latency = state.info["dr"].get("latency")
        if latency is None:
            return ctrl
        previous = self._within_motor_curve(state, self.joint_targets(state.info["last_action"]))
        steps = randomize.per_actuator(latency[:, None] * jnp.ones(self.action_size), self._dynamics)
        return late_controls(previous, ctrl, steps, self.n_substeps)

    def _within_motor_curve(self, state: State, ctrl: jax.Array) -> jax.Array:
        """`ctrl` with every robot's joint targets kept within its motors' torque-speed lines (EnvConfig.motor_curve;
        the episode's gains, the joints' state now)."""
        if not self.config.motor_curve:
            return ctrl
        dr, data, ids = state.info["dr"], state.pipeline_state, self.layout.actuator_ids
        scale = lambda key: dr[key][:, None] if key in dr else 1.0     # each robot's, on its joints
        kp, kd = servo_gains(self._base_fields["actuator_gainprm"][ids], self._base_fields["actuator_biasprm"][ids],
                             scale("kp"), scale("kd"), dr["strength"][ids])
        q, qd = data.qpos[self.layout.joint_qpos_adr], data.qvel[self.layout.joint_dof_adr]
        return ctrl.at[ids].set(within_motor_curve(ctrl[ids], q, qd, kp, kd, self._force_limit, self._motor_speeds))

    @property
    def uses_cameras(self) -> bool:
        return self.camera is not None

    @property
    def native_ray_camera(self):
        return self.camera if self.camera is not None and self.config.camera.native_caster else None

    def mjx_settle(self, model, data):
        """Body, geom and camera poses only: the observations and the camera need no more, and the next
        mjx.step computes the rest."""
        return mjx.camlight(model, mjx.kinematics(model, data))

    # ----------------------------------------------------------------- physics
    def joint_targets(self, action: jax.Array) -> jax.Array:
        """Full ctrl vector (PD targets of every actuator) for actions [n_agents, action_size]."""
        a = jnp.clip(action, -self.config.action_clip, self.config.action_clip)
        target = self._default_pose + self.robot.action_scale * a
        target = jnp.clip(target, self._ctrl_range[..., 0], self._ctrl_range[..., 1])
        return self._ctrl0.at[self.layout.actuator_ids].set(target)

    # ----------------------------------------------------------------- the game
    def transition(self, state: State, data: PhysicsView, action: jax.Array) -> State:
        """Next State from the view of stepped physics (MJX or native): rules, rewards, restarts, observations.

        After a restart the camera image is rendered from the poses before it (one control step late, in
        both engines): the kinematics of the moved bodies are the engine's to compute."""
        c = self.config
        bad = data.diverged
        action = jnp.where(bad, 0.0, jnp.clip(action, -c.action_clip, c.action_clip))  # the actions applied
        info = dict(state.info)
        info["rng"], k_noise = jax.random.split(info["rng"])
        info["step"] = info["step"] + 1
        if c.estimate_noise.enabled:
            info["estimate_error"] = next_error(c.estimate_noise, info["estimate_error"],
                                                jax.random.fold_in(k_noise, 11), self.dt)
        data, pushed = self._push(data, info, jax.random.fold_in(k_noise, 13))

        b = observe.read_bodies(self.layout, data.qpos, data.qvel)
        call = rules.call_ball(c.scene, b.ball_pos)
        fallen = (b.pos[:, 2] < c.fall_height) | (b.up_z < c.flip_up_z)
        torque = data.actuator_force[self.layout.actuator_ids]
        terms = reward_terms(c.rewards, b, call, self._team, self._goals, fallen & ~info["fallen"], torque,
                             action, info["last_action"], info["last_qvel"], self._q_range, self.dt)
        reward = jnp.where(bad, 0.0, sum(terms.values()))
        info["score"] = info["score"] + jnp.stack([call.home_scores, call.away_scores]).astype(jnp.int32)
        info["out_of_play"] = info["out_of_play"] + call.out.astype(jnp.int32)
        events = {**fall_events(fallen & ~info["fallen"], fallen, self.dt),
                  **getup_events(info["getting_up"], getting_up(info["walker_state"]))}
        info["fallen"] = fallen
        info["last_action"], info["last_qvel"] = action, b.qd

        time_out = info["step"] >= c.episode_steps
        ends_it = {"agent0": fallen[0], "any": jnp.any(fallen), "never": jnp.bool_(False)}[c.end_on_fall]
        ended = bad | ends_it | (c.end_on_goal & call.goal)
        done = ended | time_out
        info["truncation"] = (time_out & ~ended).astype(jnp.float32)
        data, restarted, kickoff = self._restart(data, call, done)
        info["teleported"] = restarted | pushed  # the engine loads the moved bodies and changed velocities
        info["players"] = jnp.where(kickoff, initial_memory(self.n_agents), info["players"])  # scripts start over
        # robots stand still at their kick-off poses: actions, walkers' clocks, filters and get-ups start over
        info["last_action"] = jnp.where(kickoff, 0.0, info["last_action"])
        info["last_qvel"] = jnp.where(kickoff, 0.0, info["last_qvel"])
        info["walker_state"] = jnp.where(kickoff, 0.0, info["walker_state"])
        info["getting_up"] = getting_up(info["walker_state"])  # after a kick-off: standing, not getting up
        now = observe.read_bodies(self.layout, data.qpos, data.qvel)  # after the restarts
        if c.estimate_noise.enabled and c.estimate_noise.sight:  # where each player last saw the ball
            info["ball_sighting"] = next_sighting(c.estimate_noise, info["ball_sighting"], now.pos[:, :2], now.yaw,
                                                  now.ball_pos[:2], self.dt, info["teleported"])

        metrics = {f"reward/{k}": v for k, v in terms.items()}
        score = info["score"].astype(jnp.float32)
        metrics.update(goals_home=score[0], goals_away=score[1],
                       out_of_play=info["out_of_play"].astype(jnp.float32), fell=fallen.astype(jnp.float32),
                       dist_to_ball=jnp.linalg.norm(b.ball_pos[:2] - b.pos[:, :2], axis=-1),
                       ball_speed=jnp.linalg.norm(b.ball_vel[:2]), diverged=bad.astype(jnp.float32), **events)
        if c.velocity_in_state:  # for walkers that read it (op3-walk's state ends with it)
            info["velocity_estimate"] = observe.velocity_estimate(now, c.noise.lin_vel if c.noise.enabled else 0.0,
                                                                  jax.random.fold_in(k_noise, 17))
        obs = self._observe(data, info, k_noise)
        return state.replace(pipeline_state=data, obs=obs, reward=reward.astype(jnp.float32),
                             done=done.astype(jnp.float32), metrics=metrics, info=info)

    def _push(self, data: PhysicsView, info: dict, rng: jax.Array) -> tuple[PhysicsView, jax.Array]:
        """(view, pushed): every `push_interval_s` each robot gets its own random horizontal velocity kick."""
        c = self.config.randomization
        if not (c.enabled and c.push_interval_s > 0 and c.push_velocity > 0):
            return data, jnp.bool_(False)
        pushed = (info["step"] % max(1, int(round(c.push_interval_s / self.dt))) == 0) & ~data.diverged
        kick = jax.random.uniform(rng, (self.n_agents, 2), minval=-c.push_velocity, maxval=c.push_velocity)
        adr = self.layout.root_dof_adr[:, None] + np.arange(2)
        return data.replace(qvel=data.qvel.at[adr].add(jnp.where(pushed, kick, 0.0))), pushed

    def _restart(self, data: PhysicsView, call: rules.BallCall, done) -> tuple[PhysicsView, jax.Array, jax.Array]:
        """Kick-off after a goal, ball back in play after it left the pitch (not when the episode ends); the
        view with the bodies moved, whether any moved, and whether the robots did (a kick-off)."""
        c, lay = self.config, self.layout
        goal = call.goal & ~done
        out = call.out & ~done
        qpos = jnp.where(goal, self._qpos0, data.qpos)  # _qpos0: every robot at its kick-off pose
        qvel = jnp.where(goal, 0.0, data.qvel)
        ball_now = data.qpos[lay.ball_qpos_adr:lay.ball_qpos_adr + 2]
        ball_xy = jnp.where(goal, 0.0, rules.back_in_play(c.scene, ball_now, c.restart_inset))
        placed_q, placed_v = rules.place_ball(qpos, qvel, lay.ball_qpos_adr, lay.ball_dof_adr, ball_xy,
                                              self._ball_radius)
        moved = goal | out
        data = data.replace(qpos=jnp.where(moved, placed_q, qpos), qvel=jnp.where(moved, placed_v, qvel),
                            ctrl=jnp.where(goal, self._ctrl0, data.ctrl))
        return data, moved, goal

    # ----------------------------------------------------------------- observations
    def _sensor_bias(self, dr: dict, size: int) -> jax.Array | float:
        """[A, size]: each robot's constant sensor biases laid out like its proprioception (IMU's on the projected
        gravity and the gyro, encoder offsets on the joint angles; 0. where none is drawn)."""
        parts = (("gravity_bias", 3), ("gyro_bias", 3), ("encoder_offset", self.action_size))
        if not any(k in dr for k, _ in parts):
            return 0.0
        bias = [dr[k] if k in dr else jnp.zeros((self.n_agents, n)) for k, n in parts]
        return jnp.concatenate(bias + [jnp.zeros((self.n_agents, size - 6 - self.action_size))], -1)

    def _observe(self, data, info: dict, rng) -> dict:
        """Every player's observations; with `vision_sightings` or `vision_tracker` the camera's sightings
        (`sightings`) are also put in `info['sightings']`."""
        c = self.config
        b = observe.read_bodies(self.layout, data.qpos, data.qvel)
        proprio = observe.proprioception(b, self._default_pose, info["last_action"])
        game = observe.game_features(b, self._team, self._goals, self._others)
        clean = jnp.concatenate([proprio, game], -1)
        state = proprio if c.vision else clean
        if c.estimate_noise.enabled:  # the deployable state only: critics and frozen opponents read the truth
            held = None
            if c.estimate_noise.sight:
                held = (held_ball(info["ball_sighting"], b.pos[:, :2], b.yaw), info["ball_sighting"][:, 2])
            state = jnp.concatenate([proprio, blurred(c.estimate_noise, info["estimate_error"], game, held)], -1)
        if c.vision_heading:
            state = jnp.concatenate([proprio, observe.attack_direction(b, self._team, self._goals)], -1)
        if c.noise.enabled:
            n = c.noise
            scale = jnp.concatenate([jnp.full(3, n.gravity), jnp.zeros(3), jnp.full(self.action_size, n.joint_pos),
                                     jnp.full(self.action_size, n.joint_vel),
                                     jnp.zeros(state.shape[-1] - 6 - 2 * self.action_size)])
            state = state + scale * jax.random.uniform(rng, state.shape, minval=-1.0, maxval=1.0)
        state = state + self._sensor_bias(info["dr"], state.shape[-1])
        fraction = info["step"].astype(jnp.float32) / c.episode_steps
        privileged = jnp.concatenate([clean, observe.privileged_features(b, self._team, info["score"], fraction)]
                                     + self._model_dynamics(info["dr"]), -1)
        obs = {"state": state, "privileged_state": privileged}
        if c.vision:  # what the state players read, for their students' teachers (legged distill)
            obs["features"] = clean
        if self.camera is not None:
            images = render_anywhere(self.camera, data) if data.camera_rgb is None else \
                {"rgb": data.camera_rgb, "depth": data.camera_depth}
            obs["camera"] = observe.camera_observation(images, c.camera.max_depth)
            if c.vision_sightings or c.vision_tracker:  # kept in info too, for the learner's tracker and viewers
                info["sightings"] = self.sightings(data, b, images)
            if c.vision_sightings:
                obs["state"] = jnp.concatenate([obs["state"], info["sightings"]], -1)
        return obs

    def sightings(self, data, b: observe.Bodies, images: dict) -> jax.Array:
        """[A, 3 SIGHTING_SIZE]: where each camera's image shows the ball, its robot's own goal and the opponent
        goal (SIGHTED; zeros for robots without a camera)."""
        c, cams = self.config, self.camera.camera_ids
        agents = camera_agents(cams, self.layout.head_camera)
        team = self.layout.team[agents]
        nets = np.array([c.scene.team_net_rgba(t)[:3] for t in (0, 1)], np.float32)
        points, in_range = pixel_points(images["depth"], self.camera.dirs, c.camera.max_depth)
        see = lambda *object_: sighting(images["rgb"], points, in_range, data.cam_xpos[cams],
                                        data.cam_xmat[cams].reshape(-1, 3, 3), b.pos[agents], b.yaw[agents], *object_)
        sight = jnp.concatenate([see(c.scene.ball_rgba[:3], BALL_MIN_SHADE, 2.0 / 3.0 * c.scene.ball_radius),
                                 see(nets[team], NET_MIN_SHADE, 0.0), see(nets[1 - team], NET_MIN_SHADE, 0.0)], -1)
        return jnp.zeros((self.n_agents, len(SIGHTED) * SIGHTING_SIZE), jnp.float32).at[agents].set(sight)

    def observation_layout(self) -> dict:
        """Named slices of each player's `state` and `privileged_state` (`privileged_state` begins with the
        clean features, named `state/...`; in vision games `state` is the proprioception alone)."""
        features = observe.feature_layout(self.layout.players_per_team)
        state = features[:1] if self.config.vision else features
        if self.config.vision_heading:
            state = state + [("attack_direction", observe.HEADING_SIZE)]
        if self.config.vision_sightings:
            state = state + [(f"{name}_sighting", SIGHTING_SIZE) for name in SIGHTED]
        drawn = jax.eval_shape(lambda k: self.spawn(k).info["dr"], jax.random.PRNGKey(0))
        dynamics = sum(int(np.prod(drawn[k].shape[1:])) for k in self._dynamics_keys(drawn))
        return {"state": state, "privileged_state": [(f"state/{n}", k) for n, k in features]
                + [("truth", observe.PRIVILEGED_SIZE)] + ([("model_dynamics", dynamics)] if dynamics else [])}

    @staticmethod
    def _dynamics_keys(dr: dict) -> list[str]:
        """The drawn model values the privileged observation holds, in order (none for runs saved before them)."""
        return [k for k in MODEL_DR + ("payload", "com", "kp", "kd") if k in dr]

    def _model_dynamics(self, dr: dict) -> list:
        """[[A, k], ...]: each robot's drawn model values, for critics and teachers (after everything older): its
        joints' damping, armature and friction loss, the feet's contact (one per game), its latency in seconds, its
        torso's payload and centre-of-mass shift, its Kp and Kd scales."""
        parts = []
        for key in self._dynamics_keys(dr):
            value = jnp.asarray(dr[key], jnp.float32) * (self.config.sim_dt if key == "latency" else 1.0)
            per_robot = jnp.broadcast_to(value, (self.n_agents,)).reshape(self.n_agents, 1) if value.ndim < 2 else value
            parts.append(per_robot)
        return parts

    @property
    def policy_state_size(self) -> int:
        """Length of the full egocentric feature vector (the state tasks' `state`): the first entries of
        `privileged_state`, which frozen opponent policies read in every task."""
        return observe.PROPRIO_SIZE + 10 + 4 * (self.n_agents - 1)

    def _initial_info(self, rng) -> dict:
        """Episode bookkeeping at the start of a game."""
        zeros = jnp.zeros((self.n_agents, self.action_size))
        return dict(rng=rng, step=jnp.int32(0), last_action=zeros, last_qvel=zeros, score=jnp.zeros(2, jnp.int32),
                    fallen=jnp.zeros(self.n_agents, bool), getting_up=jnp.zeros(self.n_agents, bool),
                    out_of_play=jnp.int32(0), truncation=jnp.float32(0.0),
                    teleported=jnp.bool_(False), players=initial_memory(self.n_agents),
                    walker_state=jnp.zeros((self.n_agents, WALKER_STATE_SIZE), jnp.float32),
                    **({"velocity_estimate": jnp.zeros((self.n_agents, 3))} if self.config.velocity_in_state else {}))
