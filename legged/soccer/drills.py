"""Drills for any OP3 soccer player: one robot on the soccer pitch, the other parked off it, one skill measured.

- `walk`: the robot starts at the centre spot facing a random way and is given random velocity commands
  (a new one every `command_seconds`) for `episode_seconds` (20 s); reported: `speed_mps` (mean planar speed),
  `tracking_error_mps` (mean |commanded - actual| planar velocity in the heading frame),
  `smoothed_tracking_error_mps` (the same with the velocity low-pass filtered over `velocity_filter_s`, which
  averages out the torso's sway within each step), `smoothed_yaw_rate_error_radps` (mean |commanded - actual|
  yaw rate, filtered the same way), and the falls (legged.envs.events; a fall ends the episode).
- `empty-goal`: the ball rests 1-2 m in front of the opponent goal, the robot starts 0.5-1.5 m from it at
  any bearing, turned anyhow; the episode ends at a goal (or a fall, or after `episode_seconds`); reported: `goal_rate`.
- `getup`: the robot starts lying at the centre spot (on its front, back or a side, any heading, joints
  jittered) and has `getup_seconds` to stand (torso origin above `stand_height`, up axis within 25 degrees
  of vertical, for `stand_hold_s`); reported: `success_rate`, `time_to_stand_s`. Falls do not end it; lying at
  the start is no fall, falling again after rising is.

`DrillEnv` is a single-agent environment (like the soccer learner's view): agent 0 is the player. With
`placo=True` the placo player (legged.soccer.placo.player) drives it from inside the step and the actions
given are ignored; otherwise they are the player's (a trained policy's) actions. Physics, rules and
randomisation are the soccer game's own.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from brax.envs.base import State

from legged.envs.math import quat_multiply, yaw_rotate
from legged.envs.physics import PhysicsView, Spawn
from legged.soccer import rules
from legged.soccer.config import SoccerConfig
from legged.soccer.env import SoccerEnv
from legged.soccer.learner import LearnerView
from legged.soccer.observe import read_bodies
from legged.soccer.placo.player import actions_of, command_request, motion_step, request_from_features
from legged.soccer.walker import Walker

DRILLS = ("walk", "empty-goal", "getup")
"""The drills."""
LYING_HEIGHT = 0.09
"""getup: height of the torso origin of a robot put down lying, m (the physics lets it settle)."""


@dataclasses.dataclass(frozen=True)
class DrillConfig:
    """How a drill is set up (the game's own settings come from its SoccerConfig)."""

    name: str = "walk"
    """walk or empty-goal."""
    command_seconds: float = 5.0
    """walk: seconds between new random commands."""
    command_low: tuple[float, float, float] = (-0.05, -0.04, -0.5)
    """walk: lower bounds of the random (vx, vy, yaw rate) commands (m/s, m/s, rad/s)."""
    command_high: tuple[float, float, float] = (0.2, 0.04, 0.5)
    """walk: upper bounds of the random commands."""
    ball_distance: tuple[float, float] = (1.0, 2.0)
    """empty-goal: range of the ball's distance in front of the goal line, metres."""
    robot_distance: tuple[float, float] = (0.5, 1.5)
    """empty-goal: range of the robot's distance from the ball (any bearing, any heading, on the pitch)."""
    episode_seconds: float = 20.0
    """walk and empty-goal: length of an episode, seconds."""
    getup_seconds: float = 5.0
    """getup: length of an episode, seconds."""
    stand_height: float = 0.21
    """getup: least torso-origin height that counts as standing, m (0.245 at the default pose)."""
    stand_up_z: float = 0.9
    """getup: least z component of the torso's up axis that counts as standing (25 degrees of tilt)."""
    stand_hold_s: float = 0.25
    """getup: how long the standing pose must be held before it counts, seconds."""
    lying_joint_noise: float = 0.3
    """getup: joints start up to this far (rad) from the default pose."""
    velocity_filter_s: float = 0.5
    """walk: time constant of the low-pass filter on the measured (vx, vy, yaw rate), seconds (half a stride:
    it averages out the sway of the torso within each step)."""

    def __post_init__(self):
        if self.name not in DRILLS:
            raise ValueError(f"unknown drill {self.name!r}; drills: {', '.join(DRILLS)}")
        if not (self.episode_seconds > 0 and self.getup_seconds > 0):
            raise ValueError(f"drill episodes need a positive length, got episode_seconds={self.episode_seconds}, "
                             f"getup_seconds={self.getup_seconds}")


class DrillEnv(LearnerView):
    """One OP3 on the pitch doing a drill (see the module docstring); the other robot stands off the pitch."""

    def __init__(self, drill: DrillConfig, config: SoccerConfig = SoccerConfig(), placo: bool = False,
                 walker: Walker | None = None, teacher_prior: bool = False):
        getup = drill.name == "getup"
        config = dataclasses.replace(config, end_on_fall="never" if getup else "agent0",
                                     end_on_goal=drill.name == "empty-goal",
                                     episode_seconds=drill.getup_seconds if getup else drill.episode_seconds)
        super().__init__(SoccerEnv(config), walker=walker, teacher_prior=teacher_prior)
        if self.game.n_agents != 2:
            raise ValueError(f"drills play on the 1v1 scene (2 robots), got {self.game.n_agents}")
        self.drill, self.placo = drill, placo
        self._segments = int(round(config.episode_seconds / drill.command_seconds)) + 1

    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        k_game, k_robot, k_ball, k_cmd = jax.random.split(rng, 4)
        spawn = self.game.spawn(k_game, carry)
        scene, lay = self.config.scene, self.game.layout
        half_l, half_w = scene.field_length / 2, scene.field_width / 2
        u = jax.random.uniform(k_robot, (3,), minval=-1.0, maxval=1.0)
        parked = jnp.array([0.0, half_w + 2.0, 0.0])                       # off the pitch, out of play
        if self.drill.name in ("walk", "getup"):
            player = jnp.array([0.0, 0.0, jnp.pi * u[2]])
            ball = jnp.array([half_l - 0.4, -half_w + 0.4])                 # a far corner
        else:
            v = jax.random.uniform(k_ball, (2,), minval=0.0, maxval=1.0)
            lo, hi = self.drill.ball_distance
            ball = jnp.array([half_l - lo - (hi - lo) * v[0], (v[1] - 0.5) * scene.goal_width])
            near, far = self.drill.robot_distance
            d = near + (far - near) * (0.5 + 0.5 * u[0])
            at = ball + d * jnp.array([jnp.cos(jnp.pi * u[1]), jnp.sin(jnp.pi * u[1])])
            at = jnp.clip(at, -jnp.array([half_l, half_w]) + 0.3, jnp.array([half_l, half_w]) - 0.3)
            player = jnp.array([at[0], at[1], jnp.pi * u[2]])
        qpos = rules.place_players(spawn.qpos, lay.root_qpos_adr, jnp.stack([player, parked]),
                                   self.robot.standing_height)
        qpos, qvel = rules.place_ball(qpos, spawn.qvel, lay.ball_qpos_adr, lay.ball_dof_adr, ball,
                                      scene.ball_radius)
        fallen = spawn.info["fallen"]
        if self.drill.name == "getup":  # put down lying: down from the start, not a fall in the drill
            qpos = self._lying(qpos, player[2], jax.random.fold_in(k_robot, 1))
            fallen = fallen.at[0].set(True)
        low, high = jnp.asarray(self.drill.command_low), jnp.asarray(self.drill.command_high)
        commands = low + (high - low) * jax.random.uniform(k_cmd, (self._segments, 3))
        info = dict(spawn.info, fallen=fallen, commands=commands, speed_sum=jnp.float32(0.0),
                    error_sum=jnp.float32(0.0), smoothed_error_sum=jnp.float32(0.0), yaw_error_sum=jnp.float32(0.0),
                    velocity_filtered=jnp.zeros(3, jnp.float32), standing_steps=jnp.int32(0), stood_step=jnp.int32(-1))
        return Spawn(qpos=qpos, qvel=qvel, ctrl=spawn.ctrl, info=info)

    def _lying(self, qpos, yaw, rng):
        """qpos with robot 0 lying on its front, back, left or right side (heading `yaw`), joints jittered."""
        k_side, k_joints = jax.random.split(rng)
        side = jax.random.randint(k_side, (), 0, 4)
        half = jnp.pi / 4  # half of a quarter turn: front (+pitch), back (-pitch), left, right (roll)
        tilt = jnp.array([[0.0, jnp.sin(half), 0.0], [0.0, -jnp.sin(half), 0.0],
                          [jnp.sin(half), 0.0, 0.0], [-jnp.sin(half), 0.0, 0.0]])[side]
        lie = jnp.concatenate([jnp.cos(half)[None], tilt])                  # about a body axis, in the heading frame
        turn = jnp.array([jnp.cos(yaw / 2), 0.0, 0.0, jnp.sin(yaw / 2)])
        quat = quat_multiply(turn, lie)
        adr = int(self.game.layout.root_qpos_adr[0])
        root = jnp.concatenate([qpos[adr:adr + 2], jnp.array([LYING_HEIGHT]), quat])
        joints = self.game.layout.joint_qpos_adr[0]
        noise = self.drill.lying_joint_noise * jax.random.uniform(k_joints, (len(joints),), minval=-1.0, maxval=1.0)
        return qpos.at[adr:adr + 7].set(root).at[joints].set(jnp.asarray(self.robot.default_pose) + noise)

    def standing(self, b) -> jax.Array:
        """Whether robot 0 stands (getup's criterion, without the hold), from `read_bodies`."""
        return (b.pos[0, 2] > self.drill.stand_height) & (b.up_z[0] > self.drill.stand_up_z)

    def command(self, info: dict) -> jax.Array:
        """The walk drill's current command (vx, vy, yaw rate)."""
        segment = jnp.minimum(info["step"] * self.dt // self.drill.command_seconds, self._segments - 1)
        return info["commands"][segment.astype(jnp.int32)]

    def prepare(self, state: State, action: jax.Array):
        """Controls: agent 0 from the given action (or the placo player), the parked robot at rest."""
        memory, walker_state = state.info["players"], state.info["walker_state"]
        estimate_sq = None if self.placo else self._estimate_sq(state, action)
        if self.placo:
            features = state.info["game_obs"]["privileged_state"][0, :self.game.policy_state_size]
            request = request_from_features(self.tables, features) if self.drill.name == "empty-goal" else \
                command_request(self.command(state.info) * (self.drill.name == "walk"))
            targets, row = motion_step(self.tables, memory[0], *request)
            action = actions_of(targets, self.tables.default_pose, self.robot.action_scale)
            memory = memory.at[0].set(row)
        else:
            action, walker_state = self.learner_actions(state, action)
        actions = jnp.stack([action, jnp.zeros_like(action)])
        return (self.game.servo_controls(state, self.game.joint_targets(actions)),
                (actions, memory, walker_state, estimate_sq))

    def transition(self, state: State, view: PhysicsView, actions) -> State:
        b = read_bodies(self.game.layout, view.qpos, view.qvel)
        velocity = yaw_rotate(b.yaw[0], b.vel[0, :2])
        info = dict(state.info)
        command = self.command(info)
        info["speed_sum"] = info["speed_sum"] + jnp.linalg.norm(velocity)
        info["error_sum"] = info["error_sum"] + jnp.linalg.norm(command[:2] - velocity)
        measured = jnp.concatenate([velocity, b.gyro[0, 2:]])
        info["velocity_filtered"] = info["velocity_filtered"] + \
            min(1.0, self.dt / self.drill.velocity_filter_s) * (measured - info["velocity_filtered"])
        info["smoothed_error_sum"] = info["smoothed_error_sum"] + \
            jnp.linalg.norm(command[:2] - info["velocity_filtered"][:2])
        info["yaw_error_sum"] = info["yaw_error_sum"] + jnp.abs(command[2] - info["velocity_filtered"][2])
        info["standing_steps"] = jnp.where(self.standing(b), info["standing_steps"] + 1, 0)
        held = info["standing_steps"] * self.dt >= self.drill.stand_hold_s - 1e-6
        info["stood_step"] = jnp.where((info["stood_step"] < 0) & held, info["step"] + 1, info["stood_step"])
        return super().transition(state.replace(info=info), view, actions)

    def _view(self, game: State) -> State:
        """Agent 0's share of the game State, with the drill's metrics."""
        mine = super()._view(game)
        steps = jnp.maximum(mine.info["step"], 1).astype(jnp.float32)
        metrics = {**mine.metrics,  # the game's (goals, falls, rewards, a vision player's estimate errors)
                   "speed_mps": mine.info["speed_sum"] / steps, "tracking_error_mps": mine.info["error_sum"] / steps,
                   "smoothed_tracking_error_mps": mine.info["smoothed_error_sum"] / steps,
                   "smoothed_yaw_rate_error_radps": mine.info["yaw_error_sum"] / steps,
                   "time_s": mine.info["step"] * self.dt, "stood": (mine.info["stood_step"] >= 0).astype(jnp.float32),
                   "time_to_stand_s": mine.info["stood_step"].astype(jnp.float32) * self.dt}
        return mine.replace(metrics=metrics)
