"""Multi-process training's collectives on the CPU (gloo), in two real processes: a checkpoint gathers every
process's curriculum levels in rank order, and each process takes its own share back on resume."""

import os
import socket

import numpy as np
import torch.multiprocessing as mp

from policies.distributed import Launch


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
