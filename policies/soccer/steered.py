"""A state soccer player trained to steer a frozen vision student (TrainConfig.soccer.steered_student).

A piloted vision player (TrainConfig.soccer.pilot, LearnerView.steer_with) is a vision student that estimates the game
from its head camera and a state player (the pilot) that reads proprioception and that estimate as if it were
the truth. A pilot trained at the truth, or on modelled estimate errors (env.estimate_noise), meets the student's
actual errors, which are correlated over time and with each other, only when it plays. Here it trains in them:
the game is the student's camera game, the frozen student estimates it at every step (its deterministic
network, its memory cleared when an episode starts, its estimate passed through the tracker and the parts
`LearnerView.used_estimate` replaces), and the learner reads [proprioception, that estimate] and outputs the
corrections to the placo command computed from the same estimate, exactly as it steers the student in eval.
The critic reads the game's privileged state. The run stays a state soccer player: eval, view and `--pilot`
load it as one.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import jax
import jax.numpy as jnp
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from legged.soccer.observe import PROPRIO_SIZE, feature_layout
from legged.soccer.walker import COMMAND_SIZE
from policies.config import ConfigError, TrainConfig
from policies.environments import build_env
from policies.policy_io import load_policy
from policies.rsl_vecenv import RslVecEnv, to_torch
from policies.run_dir import RunDir


def steered_env(config: TrainConfig) -> "SteeredView":
    """The training environment of a state soccer run with `soccer.steered_student`: the student's camera game as the
    learner's view, with the student loaded; ConfigError naming what does not fit, before anything compiles."""
    path = Path(config.soccer.steered_student)
    student = RunDir(path).load_config()  # RunDirError naming the path if it is not a run
    theirs, mine = student.soccer, config.soccer
    if not student.estimates_world or student.backend != "rsl":
        raise ConfigError(f"soccer.steered_student {path}: a vision student that estimates the game (a soccer vision "
                          f"task, soccer.command_prior=placo, rsl); this run trained {student.task} with command_prior "
                          f"{theirs.command_prior!r} and the {student.backend} backend")
    if student.task != f"{config.task}-vision":
        raise ConfigError(f"soccer.steered_student {path} plays {student.task}; a {config.task} player steers a "
                          f"{config.task}-vision student")
    if (theirs.walker, theirs.command_prior, theirs.getup) != (mine.walker, mine.command_prior, mine.getup):
        raise ConfigError(f"soccer.steered_student {path} commands walker={theirs.walker!r}, command_prior="
                          f"{theirs.command_prior!r}, getup={theirs.getup!r}; this run must command the same")
    # the student's game as eval plays it, without its pilot; the self-play opponents are this run's networks
    view = build_env(dataclasses.replace(student, soccer=dataclasses.replace(theirs, pilot="", drill=""),
                                         ppo=config.ppo), progress=False)
    return SteeredView(view, load_policy(path)[0])


class SteeredView:
    """The vision student's game as a state player's training environment: everything is the student's
    LearnerView (`view`, its attributes read through) except the learner's actions (the COMMAND_SIZE
    corrections) and observations (`state`: proprioception and the student's estimate; `privileged_state`)."""

    def __init__(self, view, student):
        self.view, self.student = view, student
        """The student's LearnerView (no pilot) and its deterministic network (a recurrent policy_io.Policy)."""
        self.action_size = COMMAND_SIZE
        """The learner's actions: corrections to the placo command."""

    def __getattr__(self, name: str):
        return getattr(self.view, name)

    def observation_dims(self) -> dict:
        return {"state": PROPRIO_SIZE + self.view.world_size,
                "privileged_state": self.view.observation_dims()["privileged_state"]}

    def observation_layout(self) -> dict:
        """A state player's layout: its `state` is the features it would read in the state game."""
        return {"state": feature_layout(self.view.game.layout.players_per_team),
                "privileged_state": self.view.game.observation_layout()["privileged_state"]}

    def learner_state(self, state, student_actions: jax.Array) -> jax.Array:
        """The learner's `state` in one game: its proprioception and the student's estimate as the game uses it."""
        return jnp.concatenate([state.obs["state"][:PROPRIO_SIZE], self.view.used_estimate(state, student_actions)])

    def vec_env(self, inner: RslVecEnv) -> "SteeredVecEnv":
        """The rsl-rl environment the learner trains in, over `inner` (the student's game, batched)."""
        return SteeredVecEnv(inner, self)


class SteeredVecEnv(VecEnv):
    """rsl-rl's VecEnv of a `SteeredView`: each step plays the learner's corrections with the student's estimate,
    then lets the student see the new frame; observations are [proprioception, the estimate used]."""

    def __init__(self, inner: RslVecEnv, view: SteeredView):
        self.inner, self.view, self.student = inner, view, view.student
        self.num_envs, self.device, self.cfg = inner.num_envs, inner.device, inner.cfg
        self.num_actions = view.action_size
        self.max_episode_length = inner.max_episode_length
        self._learner_state = jax.jit(jax.vmap(view.learner_state))
        self.student.reset()
        self._see()

    # what train_rsl reads and sets on its environment, the inner one's
    env_args = property(lambda self: self.inner.env_args, lambda self, value: setattr(self.inner, "env_args", value))
    episode_length_buf = property(lambda self: self.inner.episode_length_buf,
                                  lambda self, value: setattr(self.inner, "episode_length_buf", value))
    episode_stats = property(lambda self: self.inner.episode_stats)

    def curriculum_levels(self):
        return self.inner.curriculum_levels()

    def physics_seconds(self):
        return self.inner.physics_seconds()

    def _see(self) -> None:
        """The student's actions at the current observations (its estimate among them) and the learner's."""
        obs = self.inner.batch.state.obs
        groups = {k: jax.device_get(obs[k]) for k in self.student.inputs}
        self._student_actions = jnp.asarray(self.student.act(groups))
        state = self._learner_state(self.inner.batch.state, self._student_actions)
        self._obs = TensorDict({"state": to_torch(state, self.device),
                                "privileged_state": to_torch(obs["privileged_state"], self.device)},
                               batch_size=[self.num_envs], device=self.device)

    def get_observations(self) -> TensorDict:
        return self._obs

    def step(self, actions: torch.Tensor):
        estimate = self._student_actions[:, COMMAND_SIZE:]
        played = torch.cat([actions, to_torch(estimate, self.device)], -1)
        _, rewards, dones, extras = self.inner.step(played)
        self.student.reset(dones.bool().cpu().numpy())
        self._see()
        return self._obs, rewards, dones, extras

