"""Teacher, students and HIB: the losses, the latent actors, every algorithm's update on synthetic rollouts,
the errors of `legged distill`, and one small distillation on go1-rough in native physics."""

import dataclasses

import numpy as np
import pytest
import torch
from tensordict import TensorDict

from legged.cli import main
from policies.algorithms import attach_information_bottleneck, build_algorithm, privileged_slices
from policies.config import ConfigError, TrainConfig, apply_overrides
from policies.hib import gaussian_kl, info_nce
from policies.latent_models import NOISE_GROUP, deployed_actor
from policies.probe import probe_r2
from policies.rsl_backend import save_checkpoint
from policies.run_dir import RunDir

H = 3
"""History steps of these tests' students."""
SIZES = {"state": 45, "privileged_state": 157, "history": 45 * H}
LAYOUT = {"privileged_state": [("state", 45), ("base_lin_vel", 3), ("base_ang_vel", 3), ("contact_forces", 7),
                               ("dynamics", 4), ("com", 3), ("motor_strength", 12), ("task", 37),
                               ("model_dynamics", 41), ("friction_cone", 2)]}
TINY = ["ppo.actor_hidden=[32, 32]", "ppo.critic_hidden=[32, 32]", "latent.encoder_hidden=[32]", "latent.latent_dim=4",
        f"latent.history_steps={H}", "ppo.num_steps_per_env=4", "ppo.num_mini_batches=2", "latent.infonce_samples=16"]


def config(algo: str, **changes) -> TrainConfig:
    return apply_overrides(dataclasses.replace(TrainConfig(task="go1-rough", algo=algo, **changes).resolved()), TINY)


def observations(n: int, rng: np.random.Generator, dynamics: np.ndarray | None = None) -> TensorDict:
    groups = {k: torch.as_tensor(rng.normal(size=(n, size)), dtype=torch.float32) for k, size in SIZES.items()}
    if dynamics is not None:  # the randomised parameters of each environment's episode
        at = 0
        for part in privileged_slices(LAYOUT):  # each entry of the randomised parameters, in order
            width = part.stop - part.start
            groups["privileged_state"][:, part] = torch.as_tensor(dynamics[:, at:at + width], dtype=torch.float32)
            at += width
    groups[NOISE_GROUP] = torch.as_tensor(rng.normal(size=(n, 4)), dtype=torch.float32)
    return TensorDict(groups, batch_size=[n])


def test_gaussian_kl_and_infonce():
    mean, log_std = torch.tensor([[1.0, 0.0]]), torch.tensor([[0.0, np.log(2.0)]])
    assert float(gaussian_kl(mean, log_std)) == pytest.approx(0.5 * (1.0 + (4.0 - 1.0 - 2 * np.log(2.0))))
    z = torch.eye(4)
    assert float(info_nce(z, z, 0.01)) < 1e-6  # each sample matches only its own pair
    same = torch.ones(4, 4, dtype=torch.bool)   # one randomisation for all: no negative is left
    assert float(info_nce(torch.ones(4, 2), torch.ones(4, 2), 1.0, same)) == pytest.approx(0.0)
    assert float(info_nce(torch.ones(4, 2), torch.ones(4, 2), 1.0)) == pytest.approx(np.log(4.0))


def test_same_dynamics_is_exact_on_full_mini_batches():
    from policies.hib import same_dynamics

    rng = np.random.default_rng(1)
    episodes = rng.integers(0, 50, size=512)  # 512 anchors: where cdist switches to its matrix-product path
    dynamics = torch.as_tensor(rng.normal(1.0, 2.0, size=(50, 19)), dtype=torch.float32)[episodes]
    assert torch.equal(same_dynamics(dynamics), torch.as_tensor(episodes[:, None] == episodes[None]))


def test_privileged_encoders_skip_the_state_copy():
    rng = np.random.default_rng(3)
    obs = observations(8, rng)
    for algo in ("teacher", "hib"):
        alg = build_algorithm(config(algo), obs, 8, 12, "cpu")
        actor = alg.get_policy() if hasattr(alg, "get_policy") else alg.actor
        moved, kept = obs.clone(), obs.clone()
        kept["privileged_state"][:, :SIZES["state"]] += 5.0    # the clean copy of the state
        moved["privileged_state"][:, SIZES["state"]:] += 5.0   # what only the simulator knows
        if algo == "teacher":
            z = lambda o: actor.encode(o)[0]
        else:
            z = lambda o: actor.embed_privileged(o["privileged_state"])
        assert torch.allclose(z(obs), z(kept)) and not torch.allclose(z(obs), z(moved))


def test_zero_action_init_starts_an_actor_at_a_zero_mean_that_still_learns():
    obs = observations(8, np.random.default_rng(4))
    for algo in ("ppo", "hib"):
        plain = build_algorithm(config(algo), obs, 8, 12, "cpu")
        alg = build_algorithm(apply_overrides(config(algo), ["ppo.zero_action_init=true"]), obs, 8, 12, "cpu")
        assert torch.count_nonzero(plain.actor(obs)) > 0 and torch.count_nonzero(alg.actor(obs)) == 0
        alg.actor(obs).sum().backward()
        last = [m for m in alg.actor.mlp.modules() if isinstance(m, torch.nn.Linear)][-1]
        assert torch.count_nonzero(last.weight.grad) > 0
    with pytest.raises(ConfigError, match="zero_action_init needs the rsl backend"):
        apply_overrides(TrainConfig(task="go1-flat", backend="brax").resolved(), ["ppo.zero_action_init=true"])


def test_probe_sees_linear_information_only():
    rng = np.random.default_rng(0)
    features = rng.normal(size=(400, 6))
    assert probe_r2(features, features[:, :3] @ rng.normal(size=(3, 2))) > 0.99
    assert probe_r2(features, rng.normal(size=(400, 2))) < 0.1
    assert probe_r2(features, np.ones((400, 2))) is None  # nothing varies: nothing to probe
    episodes = np.repeat(np.arange(40), 10)  # features that only name the episode hold no dynamics
    names, dynamics = np.eye(40)[episodes], rng.normal(size=(40, 2))[episodes]
    assert probe_r2(names, dynamics) > 0.99  # split by sample, each episode sits on both sides: a leak
    assert probe_r2(names, dynamics, episodes) < 0.1  # split by episode: held-out episodes are unknown


@pytest.mark.parametrize("algo", ["teacher", "hib", "hib-no-ib", "history"])
def test_ppo_algorithms_update_on_synthetic_rollouts(algo):
    cfg = config(algo)
    rng = np.random.default_rng(1)
    n = 8
    dynamics = rng.normal(size=(n, 19 + 41 + 2))
    alg = build_algorithm(cfg, observations(n, rng, dynamics), n, 12, "cpu")
    if algo.startswith("hib"):
        attach_information_bottleneck(alg, cfg, LAYOUT, seed=0)
        encoder = [p.clone() for p in alg.actor.encoder.parameters()]
        heads = [p.clone() for p in list(alg.actor.embedding.parameters()) + list(alg.actor.projection.parameters())]
    alg.train_mode()
    obs = observations(n, rng, dynamics)
    for _ in range(cfg.ppo.num_steps_per_env):
        actions = alg.act(obs)
        if algo.startswith("hib"):  # the stored noise gives back the stored z: PPO's ratio starts at 1
            alg.actor(obs, stochastic_output=True)
            assert torch.allclose(alg.actor.get_output_log_prob(actions), alg.transition.actions_log_prob, atol=1e-5)
        obs = observations(n, rng, dynamics)
        alg.process_env_step(obs, torch.ones(n), torch.zeros(n, dtype=torch.long), {})
    alg.compute_returns(obs)
    losses = alg.update()
    assert all(np.isfinite(v) for v in losses.values())
    if algo.startswith("hib"):
        diagnostics = alg.symmetry.means()
        assert set(diagnostics) == {"hib_kl", "hib_infonce", "hib_mi_lower_bound"}
        assert all(np.isfinite(v) for v in diagnostics.values())
        assert any(not torch.equal(a, b) for a, b in zip(encoder, alg.actor.encoder.parameters()))
        after = list(alg.actor.embedding.parameters()) + list(alg.actor.projection.parameters())
        assert all(not torch.equal(a, b) for a, b in zip(heads, after))  # InfoNCE trains its heads in both
    deployed = deployed_actor(alg.get_policy())
    inputs = [obs[g] for g in deployed.input_names] if hasattr(deployed, "input_names") else [obs["state"]]
    alg.get_policy().eval()
    assert torch.allclose(deployed(*inputs), alg.get_policy()(obs), atol=1e-5)  # the mean z at deployment


def test_mixed_precision_runs_the_update_in_bfloat16():
    """ppo.mixed_precision reaches rsl-rl: the update's forward passes run in bfloat16 and still learn."""
    cfg = apply_overrides(config("ppo"), ["ppo.mixed_precision=true"])
    rng, n = np.random.default_rng(5), 8
    alg = build_algorithm(cfg, observations(n, rng), n, 12, "cpu")
    assert alg.use_mixed_precision
    dtypes = []
    alg.actor.mlp.register_forward_hook(lambda module, args, out: dtypes.append(out.dtype))
    alg.train_mode()
    for _ in range(cfg.ppo.num_steps_per_env):
        alg.act(observations(n, rng))
        alg.process_env_step(observations(n, rng), torch.ones(n), torch.zeros(n, dtype=torch.long), {})
    alg.compute_returns(observations(n, rng))
    before = [p.clone() for p in alg.actor.parameters()]
    dtypes.clear()
    losses = alg.update()
    assert dtypes and set(dtypes) == {torch.bfloat16}  # every forward pass of the update
    assert all(np.isfinite(v) for v in losses.values())
    assert any(not torch.equal(a, b) for a, b in zip(before, alg.actor.parameters()))
    assert all(p.dtype == torch.float32 for p in alg.actor.parameters())  # the weights stay float32
    with pytest.raises(ConfigError, match="mixed_precision is for --backend rsl"):
        apply_overrides(TrainConfig(task="go1-flat", backend="brax").resolved(), ["ppo.mixed_precision=true"])


@pytest.fixture(scope="module")
def teacher_run(tmp_path_factory):
    """An (untrained) teacher run directory: config and one checkpoint."""
    cfg = config("teacher", physics="native", threads=1, num_envs=4, timesteps=32, checkpoint_every=1)
    cfg = dataclasses.replace(cfg, env=dataclasses.replace(
        cfg.env, episode_seconds=0.5, terrain=dataclasses.replace(cfg.env.terrain, levels=1, tile_size=2.0,
                                                                    border=1.0)))
    run = RunDir(tmp_path_factory.mktemp("teacher") / "run")
    run.create(cfg)
    sizes = {"state": SIZES["state"], "privileged_state": SIZES["privileged_state"]}
    alg = build_algorithm(cfg, observations(4, np.random.default_rng(2)).exclude("history", NOISE_GROUP), 4, 12, "cpu")
    save_checkpoint(run, alg, 1, 16, sizes, 12)
    return run.path


def test_distill_errors_are_one_line(teacher_run, tmp_path, capsys):
    cases = [
        ([str(teacher_run), "--method", "bc"], "unknown distillation method 'bc'"),
        ([str(tmp_path / "nothing"), "--method", "dagger"], "not a run directory"),
        ([str(teacher_run), "--method", "dagger", "--set", "latent.history_steps=0"], "history_steps must be >= 1"),
    ]
    ppo = RunDir(tmp_path / "ppo")
    ppo.create(TrainConfig(task="go1-rough").resolved())
    cases.append(([str(ppo.path), "--method", "rma"], "trained with --algo ppo"))
    brax = RunDir(tmp_path / "brax")
    brax.create(TrainConfig(task="go1-flat", backend="brax").resolved())
    cases.append(([str(brax.path), "--method", "dagger"], "trained with the brax backend"))
    for argv, message in cases:
        assert main(["distill", *argv, "--run-dir", str(tmp_path / "student")]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    with pytest.raises(ConfigError, match="legged distill"):
        TrainConfig(task="go1-rough", algo="dagger").resolved()
    with pytest.raises(ConfigError, match="single-robot state task"):
        TrainConfig(task="soccer-1v1", algo="hib").resolved()


def test_rma_student_starts_as_the_teacher_and_resumes(teacher_run, tmp_path, monkeypatch):
    from policies.distill import start_distill
    from policies.export import export_onnx
    from policies.policy_io import load_policy
    from policies.training import resume_run

    out = tmp_path / "rma"
    real_log = RunDir.log

    def killed_after_second_report(self, record, writer=None):
        real_log(self, record, writer)
        if record["step"] == 32:
            raise KeyboardInterrupt  # killed before the second checkpoint was written

    monkeypatch.setattr(RunDir, "log", killed_after_second_report)
    with pytest.raises(KeyboardInterrupt):
        start_distill(str(teacher_run), "rma", str(out), timesteps=48, progress=False)
    monkeypatch.setattr(RunDir, "log", real_log)
    assert [p.name for p in RunDir(out).checkpoints()] == ["step_000000000016.pt"]
    record = resume_run(str(out), progress=False)
    assert record["step"] == 48 and np.isfinite(record["loss_latent"])
    student, cfg = load_policy(out)
    assert cfg.algo == "rma" and student.inputs == ("state", "history")
    assert cfg.env.history_steps == H and (out / "teacher.yaml").is_file()
    check = export_onnx(student, out / "policy.onnx")
    assert check["inputs"] == ["obs", "history"] and check["max_abs_diff"] < 1e-4
    payload = torch.load(RunDir(out).latest_checkpoint(), weights_only=True)["alg"]
    teacher_head = {k: v for k, v in payload["teacher_state_dict"].items() if k.startswith("mlp.")}
    assert teacher_head and all(torch.equal(v, payload["student_state_dict"][k]) for k, v in teacher_head.items())


def test_history_conv_encoder_shapes():
    from policies.bench_encoder import conv1d_reference
    from policies.latent_models import HistoryConv

    encoder = HistoryConv(steps=50, features=42, output_dim=16)
    assert len(encoder.convs) == 3  # lengths 50 -> 11 -> 7 -> 3
    history = torch.randn(5, 7, 50 * 42)
    assert encoder(history).shape == (5, 7, 16)
    newest_changed = history.clone()
    newest_changed[..., -42:] += 1.0  # the last (newest) step moves the code
    assert not torch.allclose(encoder(history), encoder(newest_changed))
    oldest_changed = history.clone()
    oldest_changed[..., :2 * 42] += 1.0  # the strides leave the two oldest steps over
    assert torch.allclose(encoder(history), encoder(oldest_changed))
    assert torch.allclose(conv1d_reference(encoder, history), encoder(history), atol=1e-5)  # the same convolutions
    short = HistoryConv(steps=3, features=42, output_dim=4)  # too short for any convolution: embed and flatten
    assert len(short.convs) == 0 and short(torch.randn(2, 3 * 42)).shape == (2, 4)
