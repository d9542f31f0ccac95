"""`legged slim`: a finished run's checkpoints keep the weights (the policy acts as before), lose what only resuming
reads, and a slimmed run refuses `--resume` in one line naming `--init-from`."""

import shutil

import numpy as np
import pytest
import torch

from legged.cli import main
from policies import training
from policies.average import average_checkpoints
from policies.checkpoints import encode_brax_checkpoint, load_brax_checkpoint, load_rsl_checkpoint
from policies.policy_io import load_policy
from policies.run_dir import RunDir, RunDirError
from policies.slim import slim_payload, slim_run

RSL_RUN = "tests/fixtures/runs/rough-dagger-cpu2"
"""A small committed distillation run (student, teacher, optimiser, normaliser)."""
BRAX_RUN = "tests/fixtures/runs/go1-flat-brax-cpu2"


def _actions(run, seed: int = 0) -> np.ndarray:
    policy, _ = load_policy(run)
    rng = np.random.default_rng(seed)
    obs = {k: rng.normal(size=(8, *np.atleast_1d(policy.obs_sizes[k]))).astype(np.float32) for k in policy.inputs}
    return np.asarray(policy.act(obs["state"] if tuple(policy.inputs) == ("state",) else obs))


@pytest.mark.parametrize("source", [RSL_RUN, BRAX_RUN])
def test_a_slimmed_run_acts_as_before_and_is_smaller(source, tmp_path, capsys):
    run = shutil.copytree(source, tmp_path / "run")
    before = _actions(run)
    assert main(["slim", str(run)]) == 0
    assert "1 of 1 checkpoint(s) slimmed" in capsys.readouterr().out
    path, original = RunDir(run).latest_checkpoint(), RunDir(source).latest_checkpoint().stat().st_size
    np.testing.assert_array_equal(_actions(run), before)
    if path.suffix == ".pt":
        payload = load_rsl_checkpoint(path)
        assert payload["slimmed"] and "optimizer_state_dict" not in payload["alg"] and "torch_rng" not in payload
        assert {"student_state_dict", "teacher_state_dict"} <= set(payload["alg"])
        assert path.stat().st_size < 0.6 * original  # Adam's two moments per student weight are gone
    else:  # this Brax run was saved without its optimiser state: only the mark is new
        payload = load_brax_checkpoint(path)
        assert payload["slimmed"] and payload["optimizer_leaves"] is None and path.stat().st_size < original + 1000
    assert slim_run(run)["slimmed"] == []  # a second pass leaves the file alone
    assert not list(path.parent.glob(".*.tmp"))


def test_a_slimmed_run_refuses_to_resume_and_names_init_from(tmp_path):
    run = shutil.copytree(RSL_RUN, tmp_path / "run")
    slim_run(run)
    task = RunDir(run).load_config().task
    with pytest.raises(RunDirError, match=f"cannot be resumed; fine-tune from it instead: legged train {task} "
                                          "--init-from"):
        training.resume_run(str(run), progress=False)


def test_slimming_drops_what_only_resuming_reads_and_keeps_what_a_fine_tune_goes_on_from():
    payload = {"backend": "rsl", "step": 7, "iteration": 1, "obs_sizes": {"state": 3}, "num_actions": 2,
               "torch_rng": torch.zeros(4), "curriculum_levels": torch.tensor([3, 1]),
               "opponent_pool": {"snapshots": [{"mean": torch.ones(3)}]},
               "alg": {"actor_state_dict": {"w": torch.ones(2)}, "critic_state_dict": {"w": torch.ones(1)},
                       "optimizer_state_dict": {"state": {}, "param_groups": [{"lr": 7e-5, "params": [0, 1]}]}}}
    slim = slim_payload(payload)
    assert set(slim) == {"backend", "step", "iteration", "obs_sizes", "num_actions", "alg", "slimmed",
                         "curriculum_levels", "learning_rate"}
    assert set(slim["alg"]) == {"actor_state_dict", "critic_state_dict"}
    assert slim["learning_rate"] == 7e-5 and slim["curriculum_levels"].tolist() == [3, 1]
    assert "optimizer_state_dict" in payload["alg"]  # the source is left as it was
    again = slim_payload(slim)  # a slimmed payload (e.g. in a mean of checkpoints) keeps them
    assert again["learning_rate"] == 7e-5 and again["curriculum_levels"].tolist() == [3, 1]


def test_the_mean_of_a_slimmed_and_a_full_checkpoint_is_slimmed(tmp_path):
    full = shutil.copytree(RSL_RUN, tmp_path / "full")
    slim = shutil.copytree(RSL_RUN, tmp_path / "slim")
    slim_run(slim)
    report = average_checkpoints([str(full), str(slim)], str(tmp_path / "soup"), None)
    soup = load_rsl_checkpoint(report["checkpoint"])
    assert soup["slimmed"] and "optimizer_state_dict" not in soup["alg"]
    np.testing.assert_allclose(_actions(tmp_path / "soup"), _actions(full), rtol=1e-5, atol=1e-6)


def test_a_brax_checkpoint_loses_its_optimiser_leaves(tmp_path):
    run = shutil.copytree(BRAX_RUN, tmp_path / "run")
    path = RunDir(run).latest_checkpoint()
    payload = load_brax_checkpoint(path)
    meta = {k: payload[k] for k in ("step", "obs_sizes", "num_actions")}
    leaves = payload["params_leaves"]
    path.write_bytes(encode_brax_checkpoint(meta, leaves, optimizer_state=[2 * a for a in leaves]))
    full = path.stat().st_size
    assert slim_run(run)["slimmed"] == [str(path)]
    slim = load_brax_checkpoint(path)
    assert slim["optimizer_leaves"] is None and path.stat().st_size < 0.6 * full
    assert all(np.array_equal(a, b) for a, b in zip(slim["params_leaves"], leaves))
