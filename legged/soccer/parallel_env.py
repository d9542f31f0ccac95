"""The soccer game as a PettingZoo parallel environment, on native MuJoCo (for that ecosystem's users).

    from legged.soccer.parallel_env import SoccerParallelEnv
    env = SoccerParallelEnv("soccer-2v2")
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: env.action_space(a).sample() for a in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

Agents are named after their robots ('home0', 'away0', ...); `players={'away0': 'placo'}` hands robots to a
built-in player (the placo player, legged.soccer.placo.player), which then acts inside `step` and is no
agent of the API. Each observation is the agent's `state`
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

from legged.envs.native import NativeEnvs
from legged.soccer.opponents import placo_actions
from legged.soccer.placo.player import load_tables
from legged.tasks import make


class SoccerParallelEnv(ParallelEnv):
    """PettingZoo ParallelEnv over a soccer task (`soccer-1v1`, `soccer-2v2`, `soccer-1v1-vision`)."""

    metadata = {"name": "legged_soccer_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(self, task: str = "soccer-1v1", config=None, players: dict[str, str] | None = None):
        env = make(task, config)
        self.env, self.runner = env, NativeEnvs(env, 1)
        self.game = None
        """The game's State (a batch of one)."""
        robots = [p.rstrip("/") for p in env.layout.prefixes]
        players = dict(players or {})
        unknown = {a: p for a, p in players.items() if a not in robots or p != "placo"}
        if unknown:
            raise ValueError(f"players: built-in players drive robots {robots} and are 'placo'; got {unknown}")
        self.builtin = np.array([robots.index(a) for a in players], np.int32)
        """Robots driven inside the step by a built-in player (not agents of the PettingZoo API)."""
        self.possible_agents = [a for a in robots if a not in players]
        self._robots = robots
        if len(self.builtin):
            tables, size, scale = load_tables(), env.policy_state_size, env.robot.action_scale
            self._placo = jax.jit(lambda obs, memory: placo_actions(tables, obs[:, :size], memory, scale))
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
        given = np.stack([np.asarray(actions[a], np.float32) for a in self.possible_agents])
        if given.shape != (len(self.possible_agents), self.env.action_size):
            raise ValueError(f"each action must have shape ({self.env.action_size},), got {given.shape[1:]}")
        acts = np.zeros((self.env.n_agents, self.env.action_size), np.float32)
        acts[[self._robots.index(a) for a in self.possible_agents]] = given
        if len(self.builtin):  # the built-in players act and remember
            state = self._one()
            memory = state.info["players"]
            played, moved = self._placo(state.obs["privileged_state"][self.builtin], memory[self.builtin])
            acts[self.builtin] = np.asarray(played)
            players = memory.at[self.builtin].set(moved)[None]
            self.game = self.game.replace(info={**self.game.info, "players": players})
        self.game = self.runner.step(self.game, jnp.asarray(acts)[None])
        state = self._one()
        obs, infos = self._observations(state), self._infos(state)
        reward = np.asarray(state.reward)
        rewards = {a: float(reward[self._robots.index(a)]) for a in self.possible_agents}
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
        index = {a: self._robots.index(a) for a in self.possible_agents}
        if "camera" in obs:
            return {a: {"state": obs["state"][i], "camera": obs["camera"][i]} for a, i in index.items()}
        return {a: obs["state"][i] for a, i in index.items()}

    def _infos(self, state) -> dict:
        privileged = np.asarray(state.obs["privileged_state"])
        score = np.asarray(state.info["score"])
        metrics = {k: np.asarray(v) for k, v in state.metrics.items()}
        infos = {}
        for a in self.possible_agents:
            i = self._robots.index(a)
            terms = {k[len("reward/"):]: float(v[i]) for k, v in metrics.items() if k.startswith("reward/")}
            infos[a] = {"privileged_state": privileged[i], "score": score.copy(), "reward_terms": terms}
        return infos
