"""The soccer game as a PettingZoo parallel environment, on native MuJoCo (for that ecosystem's users).

    from legged.soccer.parallel_env import SoccerParallelEnv
    env = SoccerParallelEnv("soccer-2v2")
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: env.action_space(a).sample() for a in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

Agents are named after their robots ('home0', 'away0', ...). Each observation is the agent's `state`
vector (state tasks) or a dict with `state` and `camera` (vision task); the ground truth is in
`infos[agent]['privileged_state']` and the whole game in `state()`. Physics is native MuJoCo (the batched
engine of legged.envs.native, one game); rules, rewards and observations are the task's own.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from legged.tasks import make
from legged.envs.native import NativeEnvs


class SoccerParallelEnv(ParallelEnv):
    """PettingZoo ParallelEnv over a soccer task (`soccer-1v1`, `soccer-2v2`, `soccer-1v1-vision`)."""

    metadata = {"name": "legged_soccer_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(self, task: str = "soccer-1v1", config=None):
        env = make(task, config)
        self.env, self.runner = env, NativeEnvs(env, 1)
        self.game = None
        """The game's State (a batch of one)."""
        self.possible_agents = [p.rstrip("/") for p in env.layout.prefixes]
        self.agents: list[str] = []
        self._seed = 0
        clip = float(env.config.action_clip)
        shapes = {k: tuple(s[1:]) for k, s in env.observation_size.items()}
        state = spaces.Box(-np.inf, np.inf, shapes["state"], np.float32)
        obs = spaces.Dict({"state": state, "camera": spaces.Box(0.0, 1.0, shapes["camera"], np.float32)}) \
            if "camera" in shapes else state
        self.observation_spaces = {a: obs for a in self.possible_agents}
        self.action_spaces = {a: spaces.Box(-clip, clip, (env.action_size,), np.float32) for a in self.possible_agents}

    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[agent]

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self._seed = int(seed)
        self.game = self.runner.reset(jax.random.PRNGKey(self._seed)[None])
        state = self._one()
        self._seed += 1  # the next reset without a seed starts another game
        self.agents = list(self.possible_agents)
        return self._observations(state), self._infos(state)

    def step(self, actions: dict):
        if not self.agents:
            raise RuntimeError("the game is over: call reset()")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise KeyError(f"no action for agent(s) {missing}")
        acts = np.stack([np.asarray(actions[a], np.float32) for a in self.possible_agents])
        if acts.shape != (self.env.n_agents, self.env.action_size):
            raise ValueError(f"each action must have shape ({self.env.action_size},), got {acts.shape[1:]}")
        self.game = self.runner.step(self.game, jnp.asarray(acts)[None])
        state = self._one()
        obs, infos = self._observations(state), self._infos(state)
        reward = np.asarray(state.reward)
        rewards = {a: float(reward[i]) for i, a in enumerate(self.possible_agents)}
        truncated = bool(state.info["truncation"] > 0)
        terminated = bool(state.done > 0) and not truncated
        terminations = {a: terminated for a in self.possible_agents}
        truncations = {a: truncated for a in self.possible_agents}
        if terminated or truncated:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    def state(self) -> np.ndarray:
        """The whole game: every agent's privileged observation, concatenated."""
        return np.asarray(self._one().obs["privileged_state"]).reshape(-1)

    def _one(self):
        """The game's State without its batch axis."""
        return jax.tree_util.tree_map(lambda x: x[0], self.game)

    def _observations(self, state) -> dict:
        obs = {k: np.asarray(v) for k, v in state.obs.items()}
        if "camera" in obs:
            return {a: {"state": obs["state"][i], "camera": obs["camera"][i]}
                    for i, a in enumerate(self.possible_agents)}
        return {a: obs["state"][i] for i, a in enumerate(self.possible_agents)}

    def _infos(self, state) -> dict:
        privileged = np.asarray(state.obs["privileged_state"])
        score = np.asarray(state.info["score"])
        metrics = {k: np.asarray(v) for k, v in state.metrics.items()}
        infos = {}
        for i, a in enumerate(self.possible_agents):
            terms = {k[len("reward/"):]: float(v[i]) for k, v in metrics.items() if k.startswith("reward/")}
            infos[a] = {"privileged_state": privileged[i], "score": score.copy(), "reward_terms": terms}
        return infos
