"""What the soccer games add to the rsl training loop (policies.training_hooks): who the learner plays against
(a pool of its own snapshots with the script among the draws, or the script in every game), and, for a pilot, the
game it learns in (its frozen vision student's camera game, policies.soccer.steered)."""

from __future__ import annotations

from policies.soccer import selfplay  # the module: its functions are looked up when called (tests replace them)
from policies.training_hooks import TrainingHooks


class SoccerHooks(TrainingHooks):
    """Opponents of a soccer run (config.soccer.selfplay): with self-play (TrainConfig.self_play) a pool of the
    learner's snapshots, drawn before a rollout (once per game with `draw_per_game`), grown every `snapshot_every`
    updates and saved in the checkpoints; else the script drives every other robot, except in a drill (nobody
    defends)."""

    def __init__(self, config, env):
        self.config, self.env = config, env
        self.pool, self.opponent, self.game_over = None, None, False  # the pool, its last draw, a game ended since

    def start(self, venv, payload, iteration, rank):
        game, sp = self.env.game, self.config.soccer.selfplay
        if self.config.self_play:
            self.pool = selfplay.OpponentPool(sp, game.policy_state_size, self.env.player_action_size,
                                              self.config.ppo.actor_hidden, seed=self.config.seed + rank + 7919 * iteration)
            if payload is not None and "opponent_pool" in payload:
                self.pool.load_state_dict(payload["opponent_pool"])
        elif not self.config.soccer.drill:
            venv.env_args = selfplay.script_opponents(sp, game.policy_state_size, self.env.player_action_size,
                                                      game.layout.players_per_team)

    def before_rollout(self, venv):
        if self.pool is not None and (self.opponent is None or self.game_over
                                      or not self.config.soccer.selfplay.draw_per_game):
            self.opponent, data = self.pool.sample()
            venv.env_args = (data, self.pool.teammate()) if self.env.game.layout.players_per_team > 1 else (data,)
        self.game_over = False

    def after_step(self, dones):
        self.game_over = self.game_over or bool(dones.any())

    def after_update(self, alg, iteration):
        if self.pool is not None and iteration % self.config.soccer.selfplay.snapshot_every == 0:
            self.pool.add(selfplay.snapshot_rsl_actor(alg.get_policy()))

    def record(self, venv):
        if self.pool is not None:
            return {"opponent": self.opponent, "opponent_pool": len(self.pool.snapshots)}
        return {"opponent": -1} if venv.env_args else {}

    def saved_state(self):
        return {} if self.pool is None else {"opponent_pool": self.pool.state_dict()}


class SteeredHooks(SoccerHooks):
    """A pilot's run (soccer.steered_student): its opponents as any soccer run's, in the game of its vision student
    (env: a policies.soccer.steered.SteeredView), which the loop batches and the learner plays through."""

    def played_env(self, env):
        return env.view

    def wrap(self, venv):
        return self.env.vec_env(venv)
