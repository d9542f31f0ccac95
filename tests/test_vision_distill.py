"""Vision students of a state soccer player (`legged distill TEACHER --task soccer-1v1-vision --method
dagger|kl`): the KL loss, the errors, and a tiny distillation by each method in native physics."""

import dataclasses

import numpy as np
import pytest
import torch
from rsl_rl.models import MLPModel
from tensordict import TensorDict

from legged.cli import main
from policies.algorithms import build_algorithm
from policies.config import TrainConfig, apply_overrides
from policies.rsl_backend import dummy_observations, save_checkpoint
from policies.run_dir import RunDir
from policies.teacher_kl import TeacherKL

TINY = ["ppo.actor_hidden=[16]", "ppo.critic_hidden=[16]", "ppo.num_steps_per_env=4", "ppo.num_mini_batches=2",
        "env.episode_seconds=0.5"]


def _gaussian_mlp(n_in: int, seed: int) -> MLPModel:
    torch.manual_seed(seed)
    obs = TensorDict({"x": torch.zeros(1, n_in)}, batch_size=[1])
    return MLPModel(obs, {"actor": ["x"]}, "actor", 2, hidden_dims=[8], obs_normalization=False,
                    distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})


def test_teacher_kl_is_zero_for_the_teacher_itself_and_trains_the_student_only():
    teacher, student = _gaussian_mlp(3, 0), _gaussian_mlp(3, 0)
    batch = type("Batch", (), {"observations": TensorDict({"x": torch.randn(64, 3)}, batch_size=[64])})()
    kl = TeacherKL(teacher, weight=2.0, decay=0.5, iteration=1)
    assert kl.mirror_loss_coeff == pytest.approx(1.0)  # 2 x 0.5^1: a resumed run goes on with its weight
    student(batch.observations, stochastic_output=True)
    assert float(kl.compute_loss(student, batch, 64).detach()) == pytest.approx(0.0, abs=1e-6)
    other = _gaussian_mlp(3, 1)
    other(batch.observations, stochastic_output=True)
    loss = kl.compute_loss(other, batch, 64)
    loss.backward()
    assert float(loss.detach()) > 0.01 and all(p.grad is None for p in teacher.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in other.parameters())
    kl.end_iteration()
    assert kl.mirror_loss_coeff == pytest.approx(0.5) and kl.means()["teacher_kl"] > 0


@pytest.fixture(scope="module")
def soccer_teacher(tmp_path_factory):
    """An (untrained) state soccer player: config and one checkpoint."""
    from legged.soccer.learner import LearnerView
    from legged.tasks import make

    cfg = apply_overrides(TrainConfig(task="soccer-1v1", physics="native", threads=1, num_envs=2, timesteps=8,
                                      checkpoint_every=1).resolved(), TINY)
    run = RunDir(tmp_path_factory.mktemp("soccer") / "teacher")
    run.create(cfg)
    sizes = LearnerView(make("soccer-1v1")).observation_dims()
    alg = build_algorithm(cfg, dummy_observations(sizes, 2), 2, 20, "cpu")
    save_checkpoint(run, alg, 1, 8, sizes, 20)
    return run.path


def test_vision_distillation_errors_are_one_line(soccer_teacher, tmp_path, capsys):
    flat = RunDir(tmp_path / "flat")
    flat.create(TrainConfig(task="go1-flat").resolved())
    cases = [([str(soccer_teacher), "--method", "rma", "--task", "soccer-1v1-vision"], "learns by dagger or kl"),
             ([str(flat.path), "--method", "kl", "--task", "soccer-1v1-vision"], "cannot teach soccer-1v1-vision"),
             ([str(soccer_teacher), "--method", "dagger", "--task", "soccer-2v2-vision"], "cannot teach")]
    for argv, message in cases:
        assert main(["distill", *argv, "--run-dir", str(tmp_path / "student")]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


@pytest.mark.parametrize("method", ["kl", "dagger"])
def test_a_vision_student_learns_from_the_state_player(soccer_teacher, tmp_path, method):
    from policies.distill import start_distill
    from policies.policy_io import load_policy

    out = tmp_path / method
    record = start_distill(str(soccer_teacher), method, str(out), timesteps=16, progress=False,
                           task="soccer-1v1-vision")
    assert record["step"] == 16
    losses = [v for k, v in record.items() if k.startswith("loss_")]
    assert losses and all(np.isfinite(losses))
    if method == "kl":
        assert record["teacher_kl"] > 0 and record["teacher_kl_weight"] == pytest.approx(0.995)  # the second iteration's
    student, cfg = load_policy(out)
    assert cfg.task == "soccer-1v1-vision" and cfg.env.vision and cfg.algo == method
    assert student.inputs == ("state", "camera") and student.num_actions == 20
    assert dataclasses.replace(cfg.env, vision=False) == RunDir(soccer_teacher).load_config().env


def test_a_teacher_that_corrected_the_placo_command_teaches_the_whole_command(tmp_path):
    from rsl_rl.utils import resolve_class

    from legged.soccer.learner import LearnerView
    from legged.tasks import make
    from policies.algorithms import teacher_model
    from policies.distill import start_distill
    from policies.policy_io import load_policy, load_walker

    walker = "assets/policies/op3-walker"
    cfg = apply_overrides(TrainConfig(task="soccer-1v1", physics="native", threads=1, num_envs=2, timesteps=8,
                                      checkpoint_every=1, walker=walker, command_prior="placo").resolved(), TINY)
    sizes = LearnerView(make("soccer-1v1"), walker=load_walker(walker, prior="placo")).observation_dims()
    obs = dummy_observations(sizes, 2)
    obs["features"], obs["command_prior"] = torch.randn(2, sizes["state"]), torch.randn(2, 3)
    cls, kwargs = resolve_class(teacher_model(cfg))
    corrector = cls(obs, {"teacher": ["features"]}, "teacher", 3, **kwargs)
    plain = MLPModel(obs, {"teacher": ["features"]}, "teacher", 3, **kwargs)
    plain.load_state_dict(corrector.state_dict())
    torch.testing.assert_close(corrector(obs), (plain(obs) + obs["command_prior"]).clamp(-1.0, 1.0))
    assert (plain(obs) + obs["command_prior"]).abs().max() > 1.0  # the clip was exercised
    corrector(obs, stochastic_output=True)
    plain(obs, stochastic_output=True)
    torch.testing.assert_close(corrector.output_mean, (plain.output_mean + obs["command_prior"]).clamp(-1.0, 1.0))

    teacher = RunDir(tmp_path / "teacher").create(cfg)
    save_checkpoint(teacher, build_algorithm(cfg, dummy_observations(sizes, 2), 2, 3, "cpu"), 1, 8, sizes, 3)
    record = start_distill(str(teacher.path), "dagger", str(tmp_path / "student"), timesteps=16, progress=False,
                           task="soccer-1v1-vision")
    assert record["step"] == 16 and np.isfinite(record["loss_behavior"])
    student, scfg = load_policy(tmp_path / "student")
    assert scfg.command_prior == "" and scfg.distill.teacher_prior and scfg.walker == walker
    assert student.inputs == ("state", "camera") and student.num_actions == 3
    from policies.drill import run_drill  # the student does the empty-goal drill through its own camera

    report = run_drill("empty-goal", str(tmp_path / "student"), episodes=1, seed=0, threads=1, progress=False,
                       num_envs=1)
    assert report["episodes"] == 1 and report["goal_rate"] in (0.0, 1.0)
