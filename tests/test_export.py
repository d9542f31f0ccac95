"""Every deployable policy exports to ONNX and matches the framework: a tiny run of each method of the Go1 tasks,
its history long enough for the convolutional history encoder (the students deployed with a memory of past
steps). The memory (GRU) and camera students are exported in test_vision_distill.py and test_soccer_training.py."""

import dataclasses

import numpy as np
import pytest
from tensordict import TensorDict
import torch

from legged.cli import main
from policies.algorithms import build_algorithm
from policies.config import TrainConfig, apply_overrides
from policies.export import export_onnx
from policies.latent_models import NOISE_GROUP
from policies.policy_io import load_policy
from policies.rsl_backend import save_checkpoint
from policies.run_dir import RunDir

H = 10
"""History steps: long enough for the encoder's first convolution (kernel 8)."""
SIZES = {"state": 45, "privileged_state": 114, "history": 45 * H}
TINY = ["ppo.actor_hidden=[16, 16]", "ppo.critic_hidden=[16]", "latent.encoder_hidden=[16]", "latent.latent_dim=4",
        f"latent.history_steps={H}"]


def _config(algo: str, teacher: str = "") -> TrainConfig:
    cfg = TrainConfig(task="go1-rough", algo=algo)
    return apply_overrides(dataclasses.replace(cfg, distill=dataclasses.replace(cfg.distill, teacher=teacher))
                           .resolved(), TINY)


def _observations(n: int, groups) -> TensorDict:
    rng = np.random.default_rng(0)
    obs = {g: torch.as_tensor(rng.normal(size=(n, SIZES[g])), dtype=torch.float32) for g in groups}
    obs[NOISE_GROUP] = torch.as_tensor(rng.normal(size=(n, 4)), dtype=torch.float32)
    return TensorDict(obs, batch_size=[n])


@pytest.mark.parametrize("algo", ["ppo", "teacher", "hib", "hib-no-ib", "history", "dagger", "rma"])
def test_every_method_exports_and_matches_the_framework(algo, tmp_path):
    teacher = _config("teacher") if algo in ("dagger", "rma") else None
    cfg = _config(algo, str(tmp_path / "teacher") if teacher else "")
    if teacher is not None:
        RunDir(tmp_path / "teacher").create(teacher)
    run = RunDir(tmp_path / "run")
    run.create(cfg)
    obs = _observations(4, SIZES)
    alg = build_algorithm(cfg, obs, 4, 12, "cpu", teacher=teacher)
    sizes = {g: SIZES[g] for g in ("state", "privileged_state") + (("history",) if cfg.env.history_steps else ())}
    save_checkpoint(run, alg, 1, 16, sizes, 12)
    policy, _ = load_policy(run.path)
    check = export_onnx(policy, tmp_path / "policy.onnx", samples=8)
    assert check["max_abs_diff"] <= 1e-4 and (tmp_path / "policy.onnx").stat().st_size > 1000
    assert check["action_bound"] == cfg.env.action_clip and check["max_abs_action"] <= cfg.env.action_clip
    if cfg.env.history_steps:
        assert "history" in check["inputs"]


def test_export_failure_is_one_line(tmp_path, capsys):
    run = RunDir(tmp_path / "empty")
    run.create(TrainConfig(task="go1-flat").resolved())
    assert main(["export", str(run.path), "--onnx"]) == 2
    err = capsys.readouterr().err
    assert "checkpoint" in err and err.count("\n") == 1, err


def test_the_deployed_actor_clips_its_actions_where_its_environment_does(tmp_path):
    """Random observations ten times larger than a normalised one drive an untrained actor far past the clip: the
    framework's policy and its ONNX both stay inside +-action_clip, and reach it."""
    cfg = apply_overrides(_config("ppo"), ["env.action_clip=0.5"])
    run = RunDir(tmp_path / "run")
    run.create(cfg)
    alg = build_algorithm(cfg, _observations(4, ("state", "privileged_state")), 4, 12, "cpu")
    with torch.no_grad():
        for p in alg.actor.parameters():
            p.mul_(20.0)
    save_checkpoint(run, alg, 1, 16, {"state": 45, "privileged_state": 114}, 12)
    policy, _ = load_policy(run.path)
    actions = policy.act(np.random.default_rng(1).normal(size=(64, 45)).astype(np.float32) * 10)
    assert np.abs(actions).max() == pytest.approx(0.5)
    check = export_onnx(policy, tmp_path / "policy.onnx", samples=64)
    assert check["max_abs_action"] == pytest.approx(0.5) and check["action_bound"] == 0.5
