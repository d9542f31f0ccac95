"""The environments runs train and play in, built from a run's config: the task's game, its learner's view
(soccer), a drill, a confined task's planned worlds, and the players that share the pitch with the learner
(opponents, teammates, the pilot that steers a vision student).

Training (policies.training, policies.distill), evaluation (policies.evaluate, policies.eval_report), drills
and the dashboard build them here, so that a policy plays exactly the game it trained in.
"""

from __future__ import annotations

from legged.soccer.drills import DrillConfig, DrillEnv
from legged.soccer.opponents import placo_opponent, scripted_opponent
from legged.tasks import learner_env, make, task_entry
from planners import make_planned_env
from policies.config import TrainConfig
from policies.policy_io import load_policy, load_walker
from policies.run_dir import RunDir
from policies.soccer.selfplay import snapshot_rsl_actor


def build_env(config: TrainConfig, progress: bool = True):
    """The run's environment as its registry entry says: confined tasks on traversable worlds with planned
    waypoints; soccer tasks as the learner's view of the game (agent 0; the others driven by opponents
    given to each step) or of `config.soccer.drill`, commanding `config.soccer.walker` when it names one."""
    entry, soccer = task_entry(config.task), config.soccer
    walker = None
    if soccer.walker:
        walker = load_walker(soccer.walker, soccer.getup, soccer.command_prior)
    if soccer.drill:  # one player on the pitch doing the drill, the other parked (no opponent to hand it)
        env = DrillEnv(DrillConfig(name=soccer.drill), config.env, walker=walker,
                       teacher_prior=config.game_gives_placo_command)
    else:
        if entry.kind == "confined":
            game = make_planned_env(config.task, config=config.env, progress=progress)
        else:
            game = make(config.task, config.env)
        env = learner_env(entry, game, config.ppo.activation, config.ppo.actor_hidden, walker,
                          config.game_gives_placo_command)
    if soccer.pilot:  # a game or a drill
        steer_with_pilot(env, soccer.pilot)
    return env


def steer_with_pilot(env, pilot: str) -> None:
    """Let the state soccer run `pilot` steer the vision student's view `env` from its estimate of the game
    (TrainConfig.soccer.pilot); ValueError naming the run if it cannot."""
    env.steer_with(soccer_opponent(pilot, env, role="pilot"), pilot)


def soccer_opponent(spec: str, env, policy=None, role: str = "--opponent"):
    """The `Opponent` that `--opponent` (or `--teammate`, or a vision student's pilot: `role`, for errors) names
    for a soccer learner's view `env`: `placo` (walks and kicks), `scripted` (stands, head on the ball), `self`
    (the evaluated `policy`) or a soccer run directory (its deterministic actor)."""
    size = env.game.policy_state_size
    if spec in ("placo", "scripted"):
        return (placo_opponent if spec == "placo" else scripted_opponent)(size, env.player_action_size)
    if spec == "self":
        if policy is None or policy.backend != "rsl" or policy.inputs != ("state",):
            raise ValueError("--teammate self needs an rsl-rl policy on the state features (a vision or Brax "
                             "player cannot drive its teammate): name placo, scripted or a state run instead")
        return snapshot_rsl_actor(policy.torch_module)
    config = RunDir(spec).load_config()  # RunDirError naming the path if it is not a run
    if task_entry(config.task).kind != "soccer" or config.backend != "rsl" or config.algo != "ppo":
        raise ValueError(f"{role} {spec}: a soccer opponent is placo, scripted or an rsl-rl soccer run; this "
                         f"run trained {config.task} with {config.backend}/{config.algo}")
    theirs = config.soccer
    if bool(theirs.walker) != (env.walker is not None):
        mine = "commands a walker" if env.walker is not None else "drives its joints"
        raise ValueError(f"{role} {spec}: the learner {mine}, the opponent run "
                         f"{'commands a walker' if theirs.walker else 'drives its joints'}: both must do the same")
    if bool(theirs.command_prior) != (env.walker is not None and env.walker.prior is not None):
        raise ValueError(f"{role} {spec}: its commands are{'' if theirs.command_prior else ' not'} corrections "
                         "to the placo player's (soccer.command_prior), the learner's are"
                         f"{' not' if theirs.command_prior else ''}: both must do the same")
    policy, _ = load_policy(spec)
    if policy.inputs != ("state",) or policy.obs_sizes["state"] != size:
        raise ValueError(f"{role} {spec}: its actor reads {policy.obs_sizes['state']} state features; the "
                         f"opponents of this game read {size} (same team size, a state task)")
    return snapshot_rsl_actor(policy.torch_module)
