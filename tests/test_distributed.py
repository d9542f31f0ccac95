"""Multi-process training on the CPU (gloo), in two real processes: a checkpoint gathers every process's curriculum
levels in rank order and each process takes its own share back on resume; `torchrun` trains and resumes a small
run end to end, its processes holding the same networks after every update and only rank 0 writing."""

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest
import torch
import torch.multiprocessing as mp

from policies.checkpoints import load_rsl_checkpoint
from policies.distributed import Launch, fingerprint
from policies.run_dir import RunDir

ROOT = Path(__file__).resolve().parents[1]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _gather_in_rank(rank: int, world: int, port: int, out: str) -> None:
    import torch.distributed as dist

    os.environ.update(MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port))
    dist.init_process_group("gloo", rank=rank, world_size=world)
    launch = Launch(world_size=world, rank=rank, local_rank=rank)
    mine = np.arange(3, dtype=np.int32) + 10 * rank  # this process's environments' levels
    every = launch.gather_rows(mine)
    np.save(f"{out}/rank{rank}.npy", np.stack([every, np.tile(launch.own_rows(every), world)]))
    dist.destroy_process_group()


def test_levels_gather_in_rank_order_and_each_process_gets_its_share_back(tmp_path):
    mp.spawn(_gather_in_rank, args=(2, _free_port(), str(tmp_path)), nprocs=2, join=True)
    for rank in (0, 1):
        every, own = np.load(tmp_path / f"rank{rank}.npy")
        assert every.tolist() == [0, 1, 2, 10, 11, 12]
        assert own[:3].tolist() == [10 * rank, 10 * rank + 1, 10 * rank + 2]


def test_one_process_keeps_its_rows():
    rows = np.arange(5)
    assert Launch().gather_rows(rows) is rows and Launch().own_rows(rows).tolist() == [0, 1, 2, 3, 4]


def test_fingerprints_tell_states_apart():
    step = {"state": {0: {"step": torch.tensor(4.0)}}}
    state = {"actor": {"w": torch.ones(3, 2), "b": torch.zeros(2)}, "optimizer": step}
    same = {"optimizer": step, "actor": {"b": torch.zeros(2), "w": torch.ones(3, 2)}}
    assert torch.equal(fingerprint(state), fingerprint(same))  # the order of the keys does not matter
    swapped = {**state, "actor": {"w": torch.tensor([[1.0, 1.0], [1.0, 2.0], [0.0, 1.0]]), "b": torch.zeros(2)}}
    assert not torch.equal(fingerprint(state), fingerprint(swapped))  # same sum, other places
    assert Launch().spread(state) == 0.0  # one process: nothing to compare


def _torchrun(args: list[str], port: int) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "torch.distributed.run", "--nproc_per_node=2", "--master_addr=127.0.0.1",
               f"--master_port={port}", "-m", "legged.cli", *args]
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    cache = jax.config.jax_compilation_cache_dir  # the suite's XLA cache: the resume loads what the first run compiled
    if cache:
        env.update(JAX_COMPILATION_CACHE_DIR=str(cache), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0.5")
    return subprocess.run(command, capture_output=True, text=True, env=env, cwd=ROOT, timeout=1200)


@pytest.mark.slow
def test_torchrun_trains_and_resumes_with_two_processes(tmp_path):
    """Two gloo processes train go1-rough for two updates and resume for a third: the processes' networks,
    normalisers and optimiser states are identical after every update (the loop compares fingerprints and stops
    otherwise; each record holds the difference), only rank 0 writes (one record per update), and the resumed run
    goes on at the levels its checkpoint holds (edited here, so that dropping them would show)."""
    run = tmp_path / "run"
    train = ["train", "go1-rough", "--physics", "native", "--threads", "1", "--num-envs", "8", "--run-dir", str(run),
             "--set", "ppo.num_steps_per_env=5", "--set", "ppo.num_mini_batches=2", "--set", "checkpoint_every=1",
             "--set", "ppo.actor_hidden=[32, 32]", "--set", "ppo.critic_hidden=[32, 32]",
             "--set", "env.terrain.levels=2", "--set", "env.terrain.tile_size=2.0", "--set", "env.terrain.border=1.0"]
    done = _torchrun([*train, "--timesteps", "80"], _free_port())
    assert done.returncode == 0, done.stderr[-3000:]
    records = RunDir(run).metrics()
    assert [r["iteration"] for r in records] == [1, 2]  # rank 1 wrote nothing beside rank 0's records
    assert all(r["process_spread"] == 0.0 for r in records)
    assert sorted(p.name for p in run.iterdir()) == ["checkpoints", "config.yaml", "metrics.jsonl", "tb"]
    last = RunDir(run).latest_checkpoint()
    payload = load_rsl_checkpoint(last)
    assert payload["curriculum_levels"].shape == (8,)
    payload["curriculum_levels"] = torch.tensor([0, 1, 1, 0, 1, 1, 0, 1], dtype=torch.int32)
    torch.save(payload, last)

    config = run / "config.yaml"
    config.write_text(config.read_text().replace("timesteps: 80", "timesteps: 120"))
    done = _torchrun(["train", "--resume", str(run)], _free_port())
    assert done.returncode == 0, done.stderr[-3000:]
    records = RunDir(run).metrics()
    assert [r["iteration"] for r in records] == [1, 2, 3] and records[-1]["process_spread"] == 0.0
    resumed = load_rsl_checkpoint(RunDir(run).latest_checkpoint())
    assert resumed["iteration"] == 3
    # 5 steps of 20 s episodes end none, so each environment is still at the level it resumed at
    assert resumed["curriculum_levels"].tolist() == [0, 1, 1, 0, 1, 1, 0, 1]
