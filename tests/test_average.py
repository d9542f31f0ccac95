"""`legged average`: the weighted mean of checkpoints of one network, as a run that loads and acts."""

import json
import shutil

import numpy as np
import pytest
import torch

from legged.cli import main
from policies.average import average_checkpoints
from policies.policy_io import load_policy
from policies.rsl_backend import load_checkpoint
from policies.run_dir import RunDir, RunDirError

SOURCE = "tests/fixtures/runs/rough-dagger-cpu2"
"""A small committed distillation run (student, teacher, optimiser, normaliser)."""


def _copy(tmp_path, name: str, change=None):
    """A copy of SOURCE whose checkpoint's payload `change(payload)` edited."""
    run = tmp_path / name
    shutil.copytree(SOURCE, run)
    path = RunDir(run).latest_checkpoint()
    if change is not None:
        payload = load_checkpoint(path)
        change(payload)
        torch.save(payload, path)
    return run


def _shift_student(payload, amount=1.0):
    student = payload["alg"]["student_state_dict"]
    for key, value in student.items():
        if value.is_floating_point():
            student[key] = value + amount
    for key in [k for k in student if k.endswith("._var")]:  # a normaliser stays one: std = sqrt(var)
        student[key[:-len("_var")] + "_std"] = torch.sqrt(student[key])
    payload["step"] += 1000


def _observations(policy, n: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {k: rng.normal(size=(n, *np.atleast_1d(policy.obs_sizes[k]))).astype(np.float32) for k in policy.inputs}


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("average")
    return tmp, _copy(tmp, "a"), _copy(tmp, "b", _shift_student)


def test_the_weighted_mean_of_two_students_loads_and_acts(pair):
    tmp, a, b = pair
    out = tmp / "soup"
    assert main(["average", str(a), str(RunDir(b).latest_checkpoint()), "--out", str(out), "--weights", "1,3",
                 "--json"]) == 0
    first, second = (load_checkpoint(RunDir(r).latest_checkpoint()) for r in (a, b))
    soup = load_checkpoint(RunDir(out).latest_checkpoint())
    assert soup["step"] == second["step"]  # named by the largest source step
    s0, s1, s = (p["alg"]["student_state_dict"] for p in (first, second, soup))
    for key, value in s.items():
        if key.endswith("._std"):  # the normaliser's std stays the square root of its (averaged) variance
            torch.testing.assert_close(value, torch.sqrt(s[key[:-len("_std")] + "_var"]))
        elif value.is_floating_point():
            torch.testing.assert_close(value, 0.25 * s0[key] + 0.75 * s1[key])
        else:
            assert torch.equal(value, torch.maximum(s0[key], s1[key])), key
    teacher = first["alg"]["teacher_state_dict"]
    assert all(torch.equal(soup["alg"]["teacher_state_dict"][k], teacher[k]) for k in teacher)
    record = json.loads((out / "averaged_from.json").read_text())
    assert [src["weight"] for src in record["sources"]] == [0.25, 0.75]
    assert (out / "teacher.yaml").is_file() and RunDir(out).load_config() == RunDir(a).load_config()

    policy, _ = load_policy(out)
    assert np.isfinite(policy.act(_observations(policy, 3, seed=0))).all()


def test_the_mean_of_a_checkpoint_and_itself_acts_as_it_does(pair):
    tmp, a, _ = pair
    out = tmp / "self"
    average_checkpoints([a, a], out)
    original, _ = load_policy(a)
    same, _ = load_policy(out)
    obs = _observations(original, 5, seed=1)  # equal up to the normaliser's std, recomputed as sqrt(var)
    np.testing.assert_allclose(same.act(obs), original.act(obs), rtol=1e-5, atol=1e-5)


def _other_teacher(payload):
    teacher = payload["alg"]["teacher_state_dict"]
    key = next(k for k, v in teacher.items() if v.is_floating_point())
    teacher[key] = teacher[key] + 1.0


def _other_shape(payload):
    student = payload["alg"]["student_state_dict"]
    key = next(k for k in student if k.endswith("weight"))
    student[key] = torch.zeros(3, 3)


def test_what_cannot_be_averaged_is_refused_before_writing(pair, tmp_path):
    _, a, _ = pair
    cases = [
        ([a], "at least two"),
        ([a, _copy(tmp_path, "teacher", _other_teacher)], "different teachers"),
        ([a, _copy(tmp_path, "shape", _other_shape)], "not the same network"),
        ([a, "tests/fixtures/runs/go1-flat-brax-cpu2"], "rsl-rl checkpoints"),
        ([a, "tests/fixtures/runs/rough-rma-cpu2"], "differ in algo"),
        ([a, tmp_path / "nothing"], "neither a run directory nor a checkpoint"),
    ]
    for sources, words in cases:
        out = tmp_path / "out"
        with pytest.raises((RunDirError, ValueError), match=words):
            average_checkpoints(sources, out)
        assert not (out / "config.yaml").exists(), words
    with pytest.raises(ValueError, match="one positive number per source"):
        average_checkpoints([a, a], tmp_path / "out", weights=[1.0, 0.0])
    with pytest.raises(RunDirError, match="already holds a run"):
        average_checkpoints([a, a], a)
