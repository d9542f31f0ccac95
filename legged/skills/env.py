"""OP3 skills learned one at a time, each a task of its own:

- `op3-walk` (WalkSkillEnv): the walk drill made a training task. The policy reads its proprioception, the
  velocity command and a gait clock, and is rewarded for tracking the command and for imitating the
  reference: the placo gait table's servo targets at the clock's phase and at the command low-pass
  filtered as the scripted player filters it (legged.soccer.placo.gait_table). With `residual` (the default) its
  actions are corrections added to the reference's.
- `op3-getup` (GetUpSkillEnv): the getup drill made a training task. The robot starts lying and is
  rewarded for raising its torso, turning upright, and standing in the default pose. Its reference is
  ROBOTIS' scripted get-up from the front or the back (legged.soccer.getup_motion); with `residual` (the
  default) its actions are corrections added to the script's.

Both are drills (legged.soccer.drills: one OP3 on the soccer pitch, the other parked off it), so physics,
randomisation and falls are the soccer game's own and a trained skill plays its drill unchanged (`legged
drill walk|getup --player RUN`). Their configs are legged.skills.config.
"""

from __future__ import annotations

import abc
import dataclasses

import jax.numpy as jnp
import numpy as np
from brax.envs.base import State

from legged.envs.math import quat_to_mat
from legged.envs.physics import PhysicsView, Spawn
from legged.skills.config import LEG_JOINTS, GetUpConfig, WalkSkillConfig
from legged.soccer.drills import DrillConfig, DrillEnv
from legged.soccer.getup_motion import getup_motion, lies_on_back, motion_features, motion_targets
from legged.soccer.learner import LEARNER
from legged.soccer.observe import PROPRIO_SIZE, Bodies, local_velocity, read_bodies
from legged.soccer.placo.gait_table import advance_phase, filter_command, gait_targets
from legged.soccer.placo.player import actions_of


class SkillEnv(DrillEnv, abc.ABC):
    """A drill trained as a task: the skill's own observations (proprioception first) and rewards."""

    def spawn(self, rng, carry: dict | None = None) -> Spawn:
        spawn = super().spawn(rng, carry)
        info = dict(spawn.info, previous_action=jnp.zeros(self.action_size, jnp.float32), **self._skill_info())
        return dataclasses.replace(spawn, info=info)

    def transition(self, state: State, view: PhysicsView, actions) -> State:
        info = dict(state.info, previous_action=state.info["last_action"][LEARNER])
        return super().transition(state.replace(info=self._advance(info)), view, actions)

    def _view(self, game: State) -> State:
        mine = super()._view(game)
        info, data = mine.info, game.pipeline_state
        b = read_bodies(self.game.layout, data.qpos, data.qvel)
        action = info["last_action"][LEARNER]
        force = data.actuator_force[self.game.layout.actuator_ids[LEARNER]]
        penalties = self.config.skill_penalties
        terms = dict(self._rewards(info, b, mine.metrics),
                     action_rate=penalties.action_rate * jnp.sum(jnp.square(action - info["previous_action"])),
                     torques=penalties.torques * jnp.sum(jnp.square(force)))
        own, privileged = self._features(info, b)
        game_obs = info["game_obs"]
        local_vel = local_velocity(b)[LEARNER]
        obs = {"state": jnp.concatenate([game_obs["state"][LEARNER, :PROPRIO_SIZE], own]),
               "privileged_state": jnp.concatenate([game_obs["privileged_state"][LEARNER, :PROPRIO_SIZE], own,
                                                    local_vel, b.pos[LEARNER, 2:], b.up_z[LEARNER, None],
                                                    privileged])}
        metrics = dict(mine.metrics, **{f"reward/{k}": v for k, v in terms.items()}, **self._metrics(info, b),
                       diverged=game.metrics["diverged"])
        reward = jnp.where(game.metrics["diverged"] > 0, 0.0, sum(terms.values())).astype(jnp.float32)
        return mine.replace(obs=obs, reward=reward, metrics=metrics)

    def observation_layout(self) -> dict:
        """Named slices of `state` and `privileged_state` (warm starts map a skill's inputs by them)."""
        own = self._feature_layout()
        privileged = [("base_lin_vel", 3), ("height", 1), ("up_z", 1), ("reference", self.action_size)]
        return {"state": [("proprio", PROPRIO_SIZE)] + own,
                "privileged_state": [("proprio", PROPRIO_SIZE)] + own + privileged}

    # ----------------------------------------------------------------- what a skill defines
    @abc.abstractmethod
    def _feature_layout(self) -> list[tuple[str, int]]:
        """Named slices of what the policy reads after its proprioception (`_features`' first part)."""

    def _skill_info(self) -> dict:
        """The skill's own entries of `info` at an episode's start."""
        return {}

    def _advance(self, info: dict) -> dict:
        """`info` one control step on (before the game's transition)."""
        return info

    @abc.abstractmethod
    def _rewards(self, info: dict, b: Bodies, metrics: dict) -> dict:
        """Reward terms of the skill (the shared penalties are added)."""

    def _features(self, info: dict, b: Bodies) -> tuple[jnp.ndarray, jnp.ndarray]:
        """(what the policy reads after its proprioception, what only the critic reads at the end)."""
        return jnp.zeros(0), jnp.zeros(0)

    def _metrics(self, info: dict, b: Bodies) -> dict:
        """The skill's own metrics."""
        return {}


class WalkSkillEnv(SkillEnv):
    """op3-walk: one OP3 tracking random velocity commands with the placo gait as its reference.

    Observations: `state` = proprioception (66), command (3), the command low-pass filtered as the reference
    reads it (3), gait clock (sin, cos of 2 pi phase), with `velocity_in_state` the torso's velocity in its own
    frame as a state estimator gives it (3, noisy: the game's `info['velocity_estimate']`);
    `privileged_state` = the same clean, torso velocity in the torso frame (3), height, uprightness and the
    reference's 20 servo targets."""

    def __init__(self, config: WalkSkillConfig = WalkSkillConfig()):
        drill = DrillConfig(name="walk", command_seconds=config.command_seconds, command_low=config.command_low,
                            command_high=config.command_high)
        super().__init__(drill, config)
        self._legs = np.array([i for i, name in enumerate(self.robot.joint_names)
                               if name.split("_", 1)[1] in LEG_JOINTS])

    def reference(self, info: dict) -> jnp.ndarray:
        """The placo gait's servo targets (20,) at the episode's gait clock and filtered command."""
        return gait_targets(self.tables.gait, info["gait_phase"], info["gait_command"])

    def learner_actions(self, state: State, action: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
        """The robot's joint actions: the policy's, plus the reference's when the skill is `residual`."""
        joints, walker_state = super().learner_actions(state, action)
        if self.config.residual:
            joints = joints + actions_of(self.reference(state.info), self.tables.default_pose, self.robot.action_scale)
        return joints, walker_state

    def _skill_info(self) -> dict:
        return dict(gait_phase=jnp.float32(0.0), gait_command=jnp.zeros(3, jnp.float32))

    def _advance(self, info: dict) -> dict:
        gait = self.tables.gait
        return dict(info, gait_phase=advance_phase(info["gait_phase"], self.dt, gait),
                    gait_command=filter_command(info["gait_command"], self.command(info), self.dt, gait))

    def _pose_error(self, info: dict, b: Bodies) -> jnp.ndarray:
        return jnp.mean(jnp.square(b.q[LEARNER, self._legs] - self.reference(info)[self._legs]))

    def _rewards(self, info: dict, b: Bodies, metrics: dict) -> dict:
        w, command = self.config.walk_rewards, self.command(info)
        measured = info["velocity_filtered"]  # (vx, vy, yaw rate) low-pass filtered over half a stride
        return {
            "tracking_lin_vel": w.tracking_lin_vel * jnp.exp(-jnp.sum(jnp.square(command[:2] - measured[:2]))
                                                             / w.lin_vel_sigma ** 2),
            "tracking_yaw_rate": w.tracking_yaw_rate * jnp.exp(-jnp.square(command[2] - measured[2])
                                                               / w.yaw_rate_sigma ** 2),
            "imitation": w.imitation * jnp.exp(-self._pose_error(info, b) / w.imitation_sigma ** 2),
            "upright": w.upright * b.up_z[LEARNER],
            "fall": w.fall * (metrics["fell"] > 0),
        }

    def _feature_layout(self) -> list[tuple[str, int]]:
        return [("command", 3), ("gait_command", 3), ("clock", 2)] + \
            ([("lin_vel", 3)] if self.config.velocity_in_state else [])

    def _features(self, info: dict, b: Bodies) -> tuple[jnp.ndarray, jnp.ndarray]:
        clock = 2 * jnp.pi * info["gait_phase"]
        own = [self.command(info), info["gait_command"], jnp.stack([jnp.sin(clock), jnp.cos(clock)])]
        if self.config.velocity_in_state:
            own.append(info["velocity_estimate"][LEARNER])
        return jnp.concatenate(own), self.reference(info)

    def _metrics(self, info: dict, b: Bodies) -> dict:
        return {"imitation_rms_rad": jnp.sqrt(self._pose_error(info, b))}


class GetUpSkillEnv(SkillEnv):
    """op3-getup: one OP3 starting on its front, back or side, learning to stand up and stay up.

    Observations: `state` = proprioception (66), which scripted get-up plays and how far it is (2,
    legged.soccer.getup_motion); `privileged_state` = the same clean, torso velocity in the torso frame (3),
    height, uprightness and the reference's 20 servo targets."""

    def __init__(self, config: GetUpConfig = GetUpConfig()):
        if config.velocity_in_state:
            raise ValueError("env.velocity_in_state: op3-getup does not read a velocity estimate (an op3-walk option)")
        super().__init__(DrillConfig(name="getup", getup_seconds=config.episode_seconds), config)
        self._default = jnp.asarray(self.robot.default_pose, jnp.float32)
        self.motion = getup_motion()

    def spawn(self, rng, carry: dict | None = None) -> Spawn:
        spawn = super().spawn(rng, carry)
        adr = int(self.game.layout.root_qpos_adr[LEARNER])
        gravity = -quat_to_mat(spawn.qpos[adr + 3:adr + 7])[2, :]  # as the proprioception reads it
        return dataclasses.replace(spawn, info=dict(spawn.info, getup_back=lies_on_back(gravity)))

    def reference(self, info: dict) -> jnp.ndarray:
        """The scripted get-up's servo targets (20,) at the episode's time."""
        return motion_targets(self.motion, info["getup_back"], info["getup_time"])

    def learner_actions(self, state: State, action: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
        """The robot's joint actions: the policy's, plus the reference's when the skill is `residual`."""
        joints, walker_state = super().learner_actions(state, action)
        if self.config.residual:
            joints = joints + actions_of(self.reference(state.info), self._default, self.robot.action_scale)
        return joints, walker_state

    def _skill_info(self) -> dict:
        return dict(getup_time=jnp.float32(0.0), getup_back=jnp.float32(1.0))

    def _advance(self, info: dict) -> dict:
        return dict(info, getup_time=info["getup_time"] + self.dt)

    def _feature_layout(self) -> list[tuple[str, int]]:
        return [("getup", 2)]

    def _features(self, info: dict, b: Bodies) -> tuple[jnp.ndarray, jnp.ndarray]:
        return motion_features(self.motion, info["getup_back"], info["getup_time"]), self.reference(info)

    def _metrics(self, info: dict, b: Bodies) -> dict:
        return {"reference_rms_rad": jnp.sqrt(jnp.mean(jnp.square(b.q[LEARNER] - self.reference(info)))),
                "back_getup": info["getup_back"]}

    def _rewards(self, info: dict, b: Bodies, metrics: dict) -> dict:
        w, d = self.config.getup_rewards, self.drill
        height = jnp.clip((b.pos[LEARNER, 2] - w.lying_height) / (d.stand_height - w.lying_height), 0.0, 1.0)
        upright = jnp.maximum(b.up_z[LEARNER], 0.0)
        posture = jnp.exp(-jnp.mean(jnp.square(b.q[LEARNER] - self._default)) / w.posture_sigma ** 2)
        return {"height": w.height * height, "upright": w.upright * upright,
                "standing": w.standing * self.standing(b), "posture": w.posture * upright * posture,
                "still": w.still * jnp.sum(jnp.square(b.vel[LEARNER, :2])) * self.standing(b)}
