"""Trained policies from checkpoints, for either backend, as one deterministic `act(state) -> action`."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Callable

import jax
import numpy as np
import torch

from policies.config import TrainConfig
from policies.run_dir import RunDir, RunDirError


@dataclasses.dataclass
class Policy:
    """A deterministic policy: actor observations (n, obs) -> actions (n, actions), numpy in and out (camera
    tasks: a dict of `state` and `camera`, see `actor_observation`)."""

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

    @property
    def obs_size(self) -> int:
        """Size of the actor's observation (`state`)."""
        return self.obs_sizes["state"]


def _rsl_policy(config: TrainConfig, path: Path) -> Policy:
    from policies.rsl_backend import build_ppo, dummy_observations, load_checkpoint

    payload = load_checkpoint(path)
    alg = build_ppo(dummy_observations(payload["obs_sizes"]), 1, payload["num_actions"], config.ppo, "cpu")
    alg.load(payload["alg"], {"actor": True}, strict=True)
    module = alg.get_policy().as_onnx(verbose=False).eval()

    def act(obs) -> np.ndarray:
        tensor = lambda x: torch.from_numpy(np.array(x, np.float32))  # a writable copy of the JAX buffer
        with torch.inference_mode():
            if isinstance(obs, dict):  # a camera task: the state vector, then the images (CNN actor)
                return module(tensor(obs["state"]), tensor(obs["camera"])).numpy()
            return module(tensor(obs)).numpy()

    return Policy(act=act, backend="rsl", step=payload["step"], obs_sizes=payload["obs_sizes"],
                  num_actions=payload["num_actions"], checkpoint=path, torch_module=module)


def _brax_policy(config: TrainConfig, path: Path) -> Policy:
    from brax.training.acme import running_statistics
    from brax.training.agents.ppo import networks as ppo_networks

    from policies.brax_backend import fill, load_checkpoint, network_factory, params_template

    payload = load_checkpoint(path)
    sizes = payload["obs_sizes"]
    networks = network_factory(config)(sizes, payload["num_actions"],
                                       preprocess_observations_fn=running_statistics.normalize)
    params = fill(params_template(config, sizes, payload["num_actions"]), payload["params_leaves"], "parameters", path)
    inference = jax.jit(ppo_networks.make_inference_fn(networks)((params[0], params[1]), deterministic=True))
    key = jax.random.PRNGKey(0)

    def act(obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs, np.float32)
        full = {"state": obs, "privileged_state": np.zeros((len(obs), sizes["privileged_state"]), np.float32)}
        return np.asarray(inference(full, key)[0])

    return Policy(act=act, backend="brax", step=payload["step"], obs_sizes=sizes,
                  num_actions=payload["num_actions"], checkpoint=path, brax_params=(params[0], params[1]))


def actor_observation(obs: dict):
    """What `Policy.act` takes from a batch of observations: the `state` array, or for camera tasks a dict of
    `state` and `camera` arrays."""
    if "camera" in obs:
        return {"state": np.asarray(obs["state"]), "camera": np.asarray(obs["camera"])}
    return np.asarray(obs["state"])


def load_policy(run_dir: str | Path, checkpoint: str | Path | None = None) -> tuple[Policy, TrainConfig]:
    """The policy of a run (its newest checkpoint unless one is named) and the run's config."""
    run = RunDir(run_dir)
    config = run.load_config()
    path = Path(checkpoint) if checkpoint else run.latest_checkpoint()
    if not path.is_file():
        raise RunDirError(f"checkpoint not found: {path}")
    loader = _rsl_policy if config.backend == "rsl" else _brax_policy
    return loader(config, path), config
