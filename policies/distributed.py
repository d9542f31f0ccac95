"""Training on more than one device or process.

- Brax backend: `ppo.train` splits the environments over every local JAX device with `pmap` (nothing to
  configure). Across hosts, start one process per host with JAX_COORDINATOR_ADDRESS (host:port of
  process 0), JAX_NUM_PROCESSES and JAX_PROCESS_ID set; `init_jax_processes` joins them before training.
- rsl backend: one process per GPU started by `torchrun --nproc_per_node=G -m legged.cli train ...`.
  Each process steps num_envs / G environments on its own GPU (JAX and torch on the same device),
  rsl-rl averages gradients and the KL-adapted learning rate over the processes (NCCL; gloo on the
  CPU), and only rank 0 writes the run directory. A checkpoint holds every process's curriculum levels (gathered
  in rank order), and a resumed run gives each process its own share back. After every update the processes
  compare fingerprints of their whole training state (networks, normalisers, optimiser; `Launch.spread`): data
  parallelism keeps them identical, and a run whose processes drift apart stops with the update it happened at.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from policies.config import ConfigError


@dataclasses.dataclass(frozen=True)
class Launch:
    """Where this process sits in a multi-process rsl run (torchrun's environment variables)."""

    world_size: int = 1
    """Number of training processes (WORLD_SIZE)."""
    rank: int = 0
    """This process's global rank (RANK)."""
    local_rank: int = 0
    """This process's rank on its host, which picks its GPU (LOCAL_RANK)."""

    @property
    def distributed(self) -> bool:
        """More than one process."""
        return self.world_size > 1

    @property
    def is_main(self) -> bool:
        """The process that writes the run directory and shows progress."""
        return self.rank == 0

    @classmethod
    def from_env(cls, environ=os.environ) -> "Launch":
        """The launch described by torchrun's variables (a single process when they are absent)."""
        try:
            launch = cls(int(environ.get("WORLD_SIZE", 1)), int(environ.get("RANK", 0)),
                         int(environ.get("LOCAL_RANK", 0)))
        except ValueError as exc:
            raise ConfigError(f"bad torchrun environment (WORLD_SIZE/RANK/LOCAL_RANK): {exc}") from None
        if not (0 <= launch.rank < launch.world_size and 0 <= launch.local_rank < launch.world_size):
            raise ConfigError(f"bad torchrun environment: rank {launch.rank}, local rank {launch.local_rank}, "
                              f"world size {launch.world_size}")
        return launch

    def envs_per_process(self, num_envs: int) -> int:
        """This process's share of the environments; ConfigError if they do not divide evenly."""
        if num_envs % self.world_size:
            raise ConfigError(f"num_envs {num_envs} is not divisible by the {self.world_size} training processes")
        return num_envs // self.world_size

    def gather_rows(self, rows: np.ndarray, device: str = "cpu") -> np.ndarray:
        """Every process's `rows` (one per environment, the same shape in each process) concatenated in rank order:
        what a checkpoint saves for all the run's environments. A collective: every process must call it."""
        if not self.distributed:
            return rows
        import torch
        import torch.distributed as dist

        mine = torch.from_numpy(np.ascontiguousarray(rows)).to(device)
        every = [torch.empty_like(mine) for _ in range(self.world_size)]
        dist.all_gather(every, mine)
        return torch.cat(every).cpu().numpy()

    def own_rows(self, rows: np.ndarray) -> np.ndarray:
        """This process's share of `rows` saved for all the run's environments in rank order (gather_rows)."""
        share = len(rows) // self.world_size
        return rows[self.rank * share:(self.rank + 1) * share]

    def spread(self, state, device: str = "cpu") -> float:
        """The largest difference between any process's `fingerprint(state)` and rank 0's: 0.0 when every process
        holds the same training state. A collective: every process must call it."""
        if not self.distributed:
            return 0.0
        import torch
        import torch.distributed as dist

        mine = fingerprint(state).to(device)
        every = [torch.empty_like(mine) for _ in range(self.world_size)]
        dist.all_gather(every, mine)
        return max(float((other - every[0]).abs().max()) for other in every)

    def multi_gpu_config(self) -> dict | None:
        """rsl-rl's `multi_gpu` config entry."""
        if not self.distributed:
            return None
        return {"global_rank": self.rank, "local_rank": self.local_rank, "world_size": self.world_size}


def fingerprint(state):
    """A float64 summary of every tensor in a nested state (dicts, lists: networks, normalisers, an optimiser's
    moments), in a fixed order: per tensor its sum and a sum weighted by position. Equal states give equal
    fingerprints; a changed parameter changes them."""
    import torch

    parts = []

    def walk(node):
        if isinstance(node, torch.Tensor):
            values = node.detach().to("cpu", torch.float64).flatten()
            weights = torch.arange(values.numel(), dtype=torch.float64) % 13 + 1
            parts.extend([values.sum(), (values * weights).sum()])
        elif isinstance(node, dict):
            for key in sorted(node, key=str):
                walk(node[key])
        elif isinstance(node, (list, tuple)):
            for item in node:
                walk(item)

    walk(state)
    return torch.stack(parts) if parts else torch.zeros(1, dtype=torch.float64)


def init_torch_processes(launch: Launch, device: str) -> str:
    """Join the process group and pin JAX and torch to this process's device; returns the torch device."""
    if not launch.distributed:
        return device
    import jax
    import torch
    import torch.distributed as dist

    cuda = device.startswith("cuda")
    if cuda:
        device = f"cuda:{launch.local_rank}"
        torch.cuda.set_device(launch.local_rank)
        gpus = [d for d in jax.local_devices() if d.platform == "gpu"]
        if len(gpus) <= launch.local_rank:
            raise ConfigError(f"local rank {launch.local_rank} has no GPU of its own (JAX sees {len(gpus)})")
        jax.config.update("jax_default_device", gpus[launch.local_rank])
    if not dist.is_initialized():
        dist.init_process_group(backend="nccl" if cuda else "gloo", rank=launch.rank, world_size=launch.world_size)
    return device


def init_jax_processes(environ=os.environ) -> None:
    """Join a multi-host JAX run when JAX_COORDINATOR_ADDRESS is set (Brax backend)."""
    address = environ.get("JAX_COORDINATOR_ADDRESS")
    if not address:
        return
    import jax

    try:
        jax.distributed.initialize(coordinator_address=address, num_processes=int(environ["JAX_NUM_PROCESSES"]),
                                   process_id=int(environ["JAX_PROCESS_ID"]))
    except KeyError as exc:
        raise ConfigError(f"JAX_COORDINATOR_ADDRESS is set but {exc.args[0]} is not") from None
