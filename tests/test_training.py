"""Training pipeline (rsl-rl backend): adapter, run directory, resume, deterministic eval, ONNX parity, errors.

One tiny go1-flat env (10-step episodes) is compiled once and shared by every test: each new environment
object or batch size would compile again (about a minute on 2 CPU cores).
"""


import pytest
import torch

import policies.training as training
from legged.envs import make
from legged.envs.vector import VectorEnv
from policies.config import ConfigError, TrainConfig, apply_overrides
from policies.evaluate import evaluate_mjx, summarize
from policies.export import export_onnx
from policies.policy_io import load_policy
from policies.rsl_vecenv import RslVecEnv
from policies.run_dir import RunDir, RunDirError, check_compatible
from tests.conftest import BATCH, TINY_EPISODE_S as EPISODE_S, TINY_RUN as TINY



@pytest.fixture(scope="module")
def tiny_env():
    return make("go1-flat", episode_seconds=EPISODE_S)


@pytest.fixture(scope="module")
def trained_run(tiny_env, tmp_path_factory):
    """A run killed after its second report (checkpoint 1 only), then resumed to 120 steps."""
    run_dir = tmp_path_factory.mktemp("runs") / "tiny"
    patch = pytest.MonkeyPatch()
    patch.setattr(training, "build_env", lambda config: tiny_env)
    real_log = RunDir.log

    def killed_after_second_report(self, record, writer=None):
        real_log(self, record, writer)
        if record["step"] == 80:
            raise KeyboardInterrupt  # as if the process were killed before checkpoint 2 was written

    patch.setattr(RunDir, "log", killed_after_second_report)
    with pytest.raises(KeyboardInterrupt):
        training.start_run("go1-flat", str(run_dir), num_envs=BATCH, timesteps=120, overrides=TINY, progress=False)
    patch.setattr(RunDir, "log", real_log)
    before = RunDir(run_dir).metrics()
    checkpoints_before = [p.name for p in RunDir(run_dir).checkpoints()]
    training.resume_run(str(run_dir), progress=False)
    patch.undo()
    return run_dir, before, checkpoints_before


def test_adapter_shapes_time_outs_and_zero_copy(tiny_env):
    venv = RslVecEnv(VectorEnv.of(tiny_env, BATCH), seed=0)
    obs = venv.get_observations()
    assert obs["state"].shape == (BATCH, 42) and obs["privileged_state"].shape == (BATCH, 74)
    assert obs["state"].dtype == torch.float32
    assert obs["state"].data_ptr() == venv._obs["state"].unsafe_buffer_pointer()  # DLPack: no copy
    for k in range(10):
        obs, rewards, dones, extras = venv.step(torch.zeros(BATCH, venv.num_actions))
        assert rewards.shape == (BATCH,) and dones.shape == (BATCH,)
        if k < 9:
            assert not dones.any() and not extras["time_outs"].any() and extras["log"] == {}
    assert dones.all() and extras["time_outs"].all()  # the 0.2 s limit: time-outs, to be bootstrapped
    assert extras["log"]["/episode/length"] == 10.0
    assert {"/episode/return", "/episode/reward/tracking_lin_vel"} <= set(extras["log"])
    assert (venv.episode_length_buf == 0).all()  # the environments were reset


def test_run_directory_is_complete_and_resume_continues(trained_run):
    run_dir, before, checkpoints_before = trained_run
    run = RunDir(run_dir)
    assert [r["step"] for r in before] == [40, 80]
    assert checkpoints_before == ["step_000000000040.pt"]
    records = run.metrics()
    assert [r["step"] for r in records] == [40, 80, 80, 120]  # resumed from the step-40 checkpoint
    assert all("episode_return" in r for r in records)
    assert records[1]["episodes"] == BATCH and records[1]["episode_length"] == 10.0  # the 0.2 s episodes ended
    assert records[-1]["iteration"] == 3
    config = run.load_config()
    assert config.task == "go1-flat" and config.env.episode_seconds == EPISODE_S and config.ppo.actor_hidden == (32, 32)
    assert [p.name for p in run.checkpoints()][-1] == "step_000000000120.pt"
    assert list((run_dir / "tb").glob("events.out.tfevents.*"))
    assert not list(run.checkpoint_dir.glob(".*tmp"))  # no half-written checkpoint left behind


def test_eval_is_deterministic_and_onnx_matches(trained_run, tiny_env, tmp_path):
    run_dir, _, _ = trained_run
    policy, config = load_policy(run_dir)
    assert policy.step == 120 and policy.obs_size == 42
    first = evaluate_mjx(tiny_env, policy, episodes=BATCH, seed=3, num_envs=BATCH, progress=False)
    again = evaluate_mjx(tiny_env, policy, episodes=BATCH, seed=3, num_envs=BATCH, progress=False)
    assert first == again
    report = summarize(first, confined=False)
    assert report["episodes"] == BATCH and report["episode_length_steps"] == 10.0
    export = export_onnx(policy, tmp_path / "policy.onnx")
    assert export["max_abs_diff"] <= 1e-4 and (tmp_path / "policy.onnx").stat().st_size > 1000


def test_confined_summary_metrics():
    finals = [{"return": 1.0, "length": 5, "success": 1.0, "time_to_goal_s": 4.0, "collisions": 2.0,
               "final_distance_m": 0.1, "reward/exploration": 0.5},
              {"return": 3.0, "length": 7, "success": 0.0, "time_to_goal_s": 0.0, "collisions": 0.0,
               "final_distance_m": 1.5, "reward/exploration": 1.5}]
    report = summarize(finals, confined=True)
    assert report["success_rate"] == 0.5 and report["time_to_goal_s"] == 4.0
    assert report["collisions_per_episode"] == 1.0 and report["final_distance_m"] == pytest.approx(0.8)
    assert report["episode_return"] == 2.0 and report["reward_terms"] == {"exploration": 1.0}


def test_bad_input_fails_before_training(tiny_env, tmp_path, capsys):
    from legged.cli import main

    assert main(["train", "no-such-task", "--run-dir", str(tmp_path / "a")]) == 2
    assert "unknown task 'no-such-task'" in capsys.readouterr().err
    assert main(["train", "go1-flat", "--run-dir", "/proc/legged-run"]) == 2
    assert "not writable" in capsys.readouterr().err
    assert main(["train", "go1-flat", "--run-dir", str(tmp_path / "b"), "--set", "ppo.nope=1"]) == 2
    assert "no field 'nope'" in capsys.readouterr().err
    assert main(["train", "go1-flat", "--backend", "brax", "--num-envs", "6", "--run-dir", str(tmp_path / "c")]) == 2
    assert "num_mini_batches" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()
    assert main(["train", "--resume", str(tmp_path)]) == 2
    assert "not a run directory" in capsys.readouterr().err
    with pytest.raises(RunDirError, match="expects observations"):
        check_compatible({"state": 261, "privileged_state": 295}, 12, tiny_env, tmp_path / "x.pt")
    assert main(["eval", str(tmp_path), "--episodes", "2"]) == 2


def test_overrides_round_trip_through_yaml(tmp_path):
    config = apply_overrides(TrainConfig(task="confined-waypoints").resolved(),
                             ["ppo.learning_rate=3e-4", "env.world.tunnel_width=1.4", "env.difficulties=[2]"])
    assert config.ppo.learning_rate == 3e-4 and config.env.world.tunnel_width == 1.4
    assert config.env.difficulties == (2,)
    run = RunDir(tmp_path / "r").create(config)
    assert run.load_config() == config
    with pytest.raises(ConfigError, match="expected float"):
        apply_overrides(config, ["ppo.learning_rate=fast"])


def test_torchrun_launch_splits_environments():
    from policies.distributed import Launch

    launch = Launch.from_env({"WORLD_SIZE": "4", "RANK": "2", "LOCAL_RANK": "2"})
    assert launch.distributed and not launch.is_main and launch.envs_per_process(4096) == 1024
    assert launch.multi_gpu_config() == {"global_rank": 2, "local_rank": 2, "world_size": 4}
    with pytest.raises(ConfigError, match="not divisible by the 4 training processes"):
        launch.envs_per_process(4098)
    with pytest.raises(ConfigError, match="bad torchrun environment"):
        Launch.from_env({"WORLD_SIZE": "2", "RANK": "2"})
    assert Launch.from_env({}).multi_gpu_config() is None
