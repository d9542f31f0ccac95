"""Atomic writes (legged.files): the target gets the content or stays as it was, the temporary file is unique per
call and never left behind, and RunDir's cleaner tells a live write from a killed one's leftover."""

import os
import subprocess
import sys
import threading

import numpy as np
import pytest

from legged.files import TEMP_GLOB, atomic_path, write_atomic, writer_pid
from policies.run_dir import RunDir


def test_the_target_gets_the_content_and_no_temporary_file_stays(tmp_path):
    target = tmp_path / "a.bin"
    assert write_atomic(target, b"\x00\x01") == target and target.read_bytes() == b"\x00\x01"
    write_atomic(target, "tête\n")  # text as UTF-8, replacing the old content
    assert target.read_bytes() == "tête\n".encode() and os.listdir(tmp_path) == ["a.bin"]


def test_a_writer_that_takes_a_path_gets_its_suffix(tmp_path):
    target = tmp_path / "plan.npz"
    with atomic_path(target, suffix=".npz") as tmp:
        assert tmp.parent == tmp_path and tmp.name.endswith(".tmp.npz") and tmp.name.startswith(".plan.npz.")
        np.savez(tmp, x=np.arange(3))  # np.savez appends .npz to any other name
    with np.load(target) as data:
        assert data["x"].tolist() == [0, 1, 2]
    assert os.listdir(tmp_path) == ["plan.npz"]


@pytest.mark.parametrize("existed", [True, False])
def test_a_failed_write_leaves_the_target_and_no_temporary_file(tmp_path, existed):
    target = tmp_path / "model.onnx"
    if existed:
        target.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="check failed"):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("check failed")
    with pytest.raises(TypeError):
        write_atomic(target, 123)  # not bytes nor text: fails in the write
    assert os.listdir(tmp_path) == (["model.onnx"] if existed else [])
    assert not existed or target.read_bytes() == b"old"


def test_temporary_names_differ_per_call_and_name_their_process(tmp_path):
    target = tmp_path / "step_000000000040.pt"
    stale = tmp_path / f".{target.name}.tmp"  # a fixed name, as older writers used: not touched, not reused
    stale.write_bytes(b"stale")
    with atomic_path(target) as a, atomic_path(target) as b:
        assert a != b and a.exists() and b.exists() and stale not in (a, b)
        assert {p.name for p in tmp_path.glob(TEMP_GLOB)} == {a.name, b.name, stale.name}
        assert writer_pid(a.name) == writer_pid(b.name) == os.getpid()
        a.write_bytes(b"a")
        b.write_bytes(b"b")
    assert target.read_bytes() == b"a" and stale.read_bytes() == b"stale"  # b was replaced first, then a
    assert sorted(os.listdir(tmp_path)) == sorted([target.name, stale.name])


def test_two_threads_writing_one_target_do_not_collide(tmp_path):
    target, both_open, errors = tmp_path / "world.npz", threading.Barrier(2, timeout=10), []

    def write(value: int) -> None:
        try:
            with atomic_path(target, suffix=".npz") as tmp:
                both_open.wait()  # both temporary files exist at once
                np.savez(tmp, value=np.full(1000, value))
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=write, args=(v,)) for v in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    with np.load(target) as data:
        assert len(set(data["value"].tolist())) == 1 and data["value"][0] in (1, 2)  # one whole write, not a mix
    assert os.listdir(tmp_path) == ["world.npz"]


def test_writer_pid_reads_the_names_it_writes():
    assert writer_pid(".step_000000000040.pt.0a1b2c3d4e5f.123.tmp") == 123
    assert writer_pid(".plan.npz.0a1b2c3d4e5f.77.tmp.npz") == 77
    assert writer_pid(".config.yaml.42.tmp") == 42  # RunDir's earlier names
    assert writer_pid(".traj.npz.tmp") is None and writer_pid("step_000000000040.pt") is None


def test_run_dir_cleaner_removes_a_killed_writers_file_and_keeps_a_live_one(tmp_path):
    run = RunDir(tmp_path / "run")
    run.checkpoint_dir.mkdir(parents=True)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    leftover = run.checkpoint_dir / f".step_000000000040.pt.0a1b2c3d4e5f.{int(dead.stdout)}.tmp"
    leftover.write_bytes(b"half")
    orphan = run.path / ".config.yaml.tmp"  # no process named: removed
    orphan.write_bytes(b"half")
    with atomic_path(run.checkpoint_path(80, "pt")) as live:
        assert sorted(run.clean_stale()) == sorted([leftover, orphan])
        assert live.exists()  # this process still writes it
        live.write_bytes(b"done")
    assert [p.name for p in run.checkpoints()] == ["step_000000000080.pt"]
    assert not list(run.checkpoint_dir.glob(".*tmp"))
    assert run.write_checkpoint(120, "pt", b"x").read_bytes() == b"x" and not list(run.checkpoint_dir.glob(".*tmp"))
