"""Trained policies from checkpoints, for either backend, as one deterministic `act(state) -> action`."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Callable

import jax
import numpy as np
import torch
from brax.training.acme import running_statistics
from brax.training.agents.ppo import networks as ppo_networks
from rsl_rl.utils import resolve_class

from legged.robots.op3 import OP3
from legged.soccer.getup_motion import getup_motion
from legged.soccer.opponents import OpponentNet
from legged.soccer.placo.gait_table import load_gait_table
from legged.soccer.placo.player import load_tables
from legged.soccer.walker import Walker
from legged.tasks import task_entry
from policies.algorithms import actor_inputs, actor_model, dummy_observations
from policies.brax_networks import network_factory, params_template
from policies.checkpoints import fill, load_brax_checkpoint, load_rsl_checkpoint
from policies.config import TrainConfig
from policies.latent_models import deployed_actor, deployed_features
from policies.run_dir import RunDir, RunDirError
from policies.soccer.selfplay import snapshot_rsl_actor

GETUP_SCRIPT = "script"
"""`soccer.getup=script`: soccer players get up by ROBOTIS' scripted get-up alone (legged.soccer.getup_motion)."""


@dataclasses.dataclass
class Policy:
    """A deterministic policy: actor observations -> actions (n, actions), numpy in and out. `act` takes the
    `state` array (n, obs) of a state-only actor, or a dict holding at least the groups in `inputs`."""

    act: Callable[[np.ndarray], np.ndarray]
    """The policy function."""
    backend: str
    """'rsl' or 'brax'."""
    step: int
    """Environment steps the checkpoint was trained for."""
    obs_sizes: dict
    """Observation sizes it was trained with ({'state': n, 'privileged_state': m})."""
    num_actions: int
    """Size of the action."""
    checkpoint: Path
    """File it was loaded from."""
    torch_module: torch.nn.Module | None = None
    """rsl: the deterministic actor (obs -> action) as a torch module, for export."""
    brax_params: tuple | None = None
    """brax: (normaliser, policy) parameters, for export."""
    inputs: tuple[str, ...] = ("state",)
    """Observation groups the actor reads, in its input order (e.g. state and history for students)."""
    features: Callable[[dict], np.ndarray | None] | None = None
    """rsl: what a linear probe reads from the actor (mean latent, or an MLP's last hidden layer)."""
    reset: Callable[..., None] = lambda done=None: None
    """Starts new episodes for a policy with memory: `reset()` all of them (a new batch), `reset(done)` those
    where the boolean array `done` is set; nothing for memoryless policies. Call it whenever episodes begin."""
    recurrent: bool = False
    """Whether `act` remembers earlier steps (policies.memory_models): then one batch of episodes at a time."""
    action_bound: float | None = None
    """Actions lie in +-this (the deployed actor clips them, as its environment does); None: unbounded."""

    @property
    def obs_size(self) -> int:
        """Size of the actor's observation (`state`)."""
        return self.obs_sizes["state"]


def _tensor(x, dtype=np.float32) -> torch.Tensor:
    """A torch tensor of a writable copy of `x` (JAX buffers and env outputs may be read-only)."""
    return torch.from_numpy(np.array(x, dtype))


def build_actor(config: TrainConfig, obs_sizes: dict, num_actions: int):
    """The rsl-rl actor model of a run's algorithm (for distillations: its student), untrained."""
    obs = dummy_observations(obs_sizes)
    camera = "camera" in obs_sizes
    cls, kwargs = resolve_class(actor_model(config, config.ppo.init_noise_std, camera))
    return cls(obs, {"actor": actor_inputs(config.algo, camera)}, "actor", num_actions, **kwargs)


class BoundedActions(torch.nn.Module):
    """A deployed actor whose actions are clipped to +-`bound`, the range its environment applies: part of the network,
    so the ONNX model clips too."""

    def __init__(self, module: torch.nn.Module, bound: float):
        super().__init__()
        self.module, self.bound = module, float(bound)

    @property
    def bounded(self) -> torch.nn.Module:
        """The actor whose output is clipped."""
        return self.module

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        return torch.clamp(self.module(*inputs), -self.bound, self.bound)


COMMAND_BOUND = 1.0
"""A commanding soccer player's actions are the walker's command in [-1, 1] (legged.soccer.walker clips it)."""


def action_bound(config: TrainConfig) -> float | None:
    """The range of a run's actions, or None where they are unbounded: joint actions, the environment's clip; a
    soccer player commanding a walker, the command's [-1, 1], or for corrections added to the placo player's command
    1 + the largest the placo command can be (the walker clips the sum to [-1, 1], so a larger correction changes
    nothing: `prior_reach`); None for a vision student whose actions also hold its estimate of the game (positions)."""
    entry = task_entry(config.task)
    if not entry.bounded_actions:
        return None
    if entry.kind == "soccer" and config.soccer.walker:
        if config.soccer.command_prior and config.env.vision:
            return None
        return COMMAND_BOUND + (prior_reach(config.soccer.walker) if config.soccer.command_prior else 0.0)
    return float(config.env.action_clip)


def prior_reach(walker: str) -> float:
    """The largest |commanding action| of the placo player's command for the walker of run `walker`: placo's request
    lies in its gait table's command grid, mapped onto the walker's command range."""
    table, env = load_gait_table(xp=np), RunDir(walker).load_config().env
    low, high = np.asarray(env.command_low, float), np.asarray(env.command_high, float)
    ends = [2.0 * (np.asarray(v, float) - low) / (high - low) - 1.0 for v in (table.command_low, table.command_high)]
    return float(np.max(np.abs(ends)))


def _rsl_policy(config: TrainConfig, path: Path) -> Policy:
    payload = load_rsl_checkpoint(path)
    actor = build_actor(config, payload["obs_sizes"], payload["num_actions"])
    key = "student_state_dict" if config.algo in ("dagger", "rma") else "actor_state_dict"
    actor.load_state_dict(payload["alg"][key], strict=True)
    module = deployed_actor(actor)
    inputs = tuple(actor_inputs(config.algo, "camera" in payload["obs_sizes"]))

    if getattr(module, "is_recurrent", False):
        return _recurrent_policy(module, payload, path, inputs)
    inner, bound = module, action_bound(config)
    if bound is not None:
        module = BoundedActions(inner, bound).eval()

    def act(obs) -> np.ndarray:
        with torch.inference_mode():
            if isinstance(obs, dict):  # the observation groups the actor reads, in its order
                return module(*(_tensor(obs[k]) for k in inputs)).numpy()
            return module(_tensor(obs)).numpy()

    def features(obs: dict) -> np.ndarray | None:
        with torch.inference_mode():
            out = deployed_features(inner, *(_tensor(obs[k]) for k in inputs))
        return None if out is None else out.numpy()

    return Policy(act=act, backend="rsl", step=payload["step"], obs_sizes=payload["obs_sizes"],
                  num_actions=payload["num_actions"], checkpoint=path, torch_module=module, inputs=inputs,
                  features=features, action_bound=bound)


def _recurrent_policy(module, payload: dict, path: Path, inputs: tuple[str, ...]) -> Policy:
    """A Policy over a deployed actor with memory ((inputs..., memory) -> (actions, memory)): `act` carries the
    memory of the batch from step to step, `reset` clears it."""
    memory: list = [None]

    def act(obs: dict) -> np.ndarray:
        groups = [_tensor(obs[k]) for k in inputs]
        with torch.inference_mode():
            if memory[0] is None or memory[0].shape[1] != len(groups[0]):  # a new batch
                memory[0] = module.initial_memory(len(groups[0]))
            actions, memory[0] = module(*groups, memory[0])
        return actions.numpy()

    def reset(done=None) -> None:
        if done is None or memory[0] is None:
            memory[0] = None
            return
        with torch.inference_mode():
            memory[0][:, _tensor(done, bool)] = 0.0

    return Policy(act=act, backend="rsl", step=payload["step"], obs_sizes=payload["obs_sizes"],
                  num_actions=payload["num_actions"], checkpoint=path, torch_module=module, inputs=inputs,
                  features=lambda obs: None, reset=reset, recurrent=True)


def _brax_policy(config: TrainConfig, path: Path) -> Policy:
    payload = load_brax_checkpoint(path)
    sizes = payload["obs_sizes"]
    networks = network_factory(config)(sizes, payload["num_actions"],
                                       preprocess_observations_fn=running_statistics.normalize)
    params = fill(params_template(config, sizes, payload["num_actions"]), payload["params_leaves"], "parameters", path)
    inference = jax.jit(ppo_networks.make_inference_fn(networks)((params[0], params[1]), deterministic=True))
    key = jax.random.PRNGKey(0)

    def act(obs) -> np.ndarray:
        obs = np.asarray(obs["state"] if isinstance(obs, dict) else obs, np.float32)
        full = {"state": obs, "privileged_state": np.zeros((len(obs), sizes["privileged_state"]), np.float32)}
        return np.asarray(inference(full, key)[0])

    return Policy(act=act, backend="brax", step=payload["step"], obs_sizes=sizes,
                  num_actions=payload["num_actions"], checkpoint=path, brax_params=(params[0], params[1]),
                  action_bound=1.0)  # Brax's deterministic policy is the tanh of its mean


def actor_observation(obs: dict, inputs: tuple[str, ...] = ("state",)):
    """What `Policy.act` takes from a batch of observations: the `state` array when the actor reads only
    that, else a dict of the groups it reads (`Policy.inputs`; camera tasks: `state` and `camera`)."""
    if "camera" in obs and "camera" not in inputs:
        inputs = tuple(inputs) + ("camera",)
    if tuple(inputs) == ("state",):
        return np.asarray(obs["state"])
    return {k: np.asarray(obs[k]) for k in inputs}


def load_policy(run_dir: str | Path, checkpoint: str | Path | None = None) -> tuple[Policy, TrainConfig]:
    """The policy of a run (its newest checkpoint unless one is named) and the run's config."""
    run = RunDir(run_dir)
    config = run.load_config()
    path = Path(checkpoint) if checkpoint else run.latest_checkpoint()
    if not path.is_file():
        raise RunDirError(f"checkpoint not found: {path}")
    loader = _rsl_policy if config.backend == "rsl" else _brax_policy
    return loader(config, path), config


def load_walker(run_dir: str | Path, getup: str | Path = "", prior: str = ""):
    """The frozen walking skill of an op3-walk run (`legged.soccer.walker.Walker`), for soccer players that
    command velocities, with a get-up skill when `getup` names one: `script` (ROBOTIS' scripted get-up alone)
    or an op3-getup run, and with `prior` `placo` the players' actions corrections to the placo player's
    command; ValueError naming what is wrong when a run is not what it should be."""
    config = RunDir(run_dir).load_config()  # RunDirError naming the path if it is not a run
    if config.task != "op3-walk" or config.backend != "rsl" or config.algo != "ppo":
        raise ValueError(f"walker {run_dir}: a walker is an op3-walk run trained with rsl/ppo; this run trained "
                         f"{config.task} with {config.backend}/{config.algo}")
    learned = bool(getup) and str(getup) != GETUP_SCRIPT
    if learned:  # both runs checked before either is loaded
        getup_config = RunDir(getup).load_config()
        if getup_config.task != "op3-getup" or getup_config.backend != "rsl" or getup_config.algo != "ppo":
            raise ValueError(f"getup {getup}: a get-up skill is `{GETUP_SCRIPT}` or an op3-getup run trained with "
                             f"rsl/ppo; this run trained {getup_config.task} with {getup_config.backend}/"
                             f"{getup_config.algo}")
    policy, _ = load_policy(run_dir)
    skill = {}
    if prior:
        skill["prior"] = load_tables()
    if getup:
        skill["getup_motion"] = getup_motion()
    if learned:
        skill.update(getup=snapshot_rsl_actor(load_policy(getup)[0].torch_module),
                     getup_net=OpponentNet(getup_config.ppo.activation), getup_residual=bool(getup_config.env.residual))
    return Walker(policy=snapshot_rsl_actor(policy.torch_module), net=OpponentNet(config.ppo.activation), **skill,
                  command_low=tuple(config.env.command_low), command_high=tuple(config.env.command_high),
                  gait=load_gait_table(), dt=float(config.env.ctrl_dt), residual=bool(config.env.residual),
                  velocity_input=bool(config.env.velocity_in_state),
                  default_pose=tuple(float(q) for q in OP3.default_pose), action_scale=float(OP3.action_scale))
