"""Training pipeline (rsl-rl backend): adapter, run directory, resume, deterministic eval, ONNX parity, errors.

One tiny go1-flat env (10-step episodes) is compiled once and shared by every test: each new environment
object or batch size would compile again (about a minute on 2 CPU cores).
"""

import contextlib
import shutil
import types

import numpy as np
import pytest
import torch

import policies.training as training
from legged.tasks import make
from legged.envs.vector import VectorEnv
from policies.config import ConfigError, TrainConfig, apply_overrides
from policies.evaluate import evaluate, summarize
from policies.export import export_onnx
from policies.policy_io import load_policy
from policies.rsl_vecenv import RslVecEnv
from policies.run_dir import RunDir, RunDirError, check_compatible, check_policy
from tests.conftest import BATCH, TINY_EPISODE_S as EPISODE_S, TINY_RUN as TINY
from tests.test_training_brax import SlidingBlock



@pytest.fixture(scope="module")
def tiny_env():
    return make("go1-flat", episode_seconds=EPISODE_S)


@contextlib.contextmanager
def torch_threads_kept():
    """A native run pins torch's thread count (its `threads`); the tests after it keep theirs."""
    threads = torch.get_num_threads()
    try:
        yield
    finally:
        torch.set_num_threads(threads)


@pytest.fixture(scope="module")
def trained_run(tiny_env, tmp_path_factory):
    """A run killed after its second report (checkpoint 1 only), then resumed to 120 steps. In native physics:
    the run directory and its resume do not depend on the engine, and an MJX training program would be
    the suite's costliest compilation (12 minutes on a slow 2-core machine); VectorEnv's MJX engine is checked on a
    pure-JAX task below (test_mjx_evaluation_...) and by the Brax run (tests/test_training_brax.py), the two engines'
    agreement on go1-flat in tests/test_mjx_vs_native.py and tests/test_mjx_randomized.py."""
    run_dir = tmp_path_factory.mktemp("runs") / "tiny"
    patch = pytest.MonkeyPatch()
    patch.setattr(training, "build_env", lambda config: tiny_env)
    real_log = RunDir.log

    def killed_after_second_report(self, record, writer=None):
        real_log(self, record, writer)
        if record["step"] == 80:
            raise KeyboardInterrupt  # as if the process were killed before checkpoint 2 was written

    patch.setattr(RunDir, "log", killed_after_second_report)
    with torch_threads_kept():
        with pytest.raises(KeyboardInterrupt):
            training.start_run("go1-flat", str(run_dir), num_envs=BATCH, timesteps=120, overrides=TINY,
                               progress=False, physics="native", threads=1)
        patch.setattr(RunDir, "log", real_log)
        before = RunDir(run_dir).metrics()
        checkpoints_before = [p.name for p in RunDir(run_dir).checkpoints()]
        training.resume_run(str(run_dir), progress=False)
    patch.undo()
    return run_dir, before, checkpoints_before


def test_adapter_shapes_time_outs_and_zero_copy(tiny_env):
    venv = RslVecEnv(VectorEnv.of(tiny_env, BATCH, "native", 1), seed=0)
    obs = venv.get_observations()
    assert obs["state"].shape == (BATCH, 42) and obs["privileged_state"].shape == (BATCH, 74 + 41 + 2)  # + draws, cone
    assert obs["state"].dtype == torch.float32
    assert obs["state"].data_ptr() == venv._obs["state"].unsafe_buffer_pointer()  # DLPack: no copy
    native = venv.vector.native
    jitted = (native._spawn, native._first, native._carry, native._prepare, native._transition)
    for k in range(10):
        obs, rewards, dones, extras = venv.step(torch.zeros(BATCH, venv.num_actions))
        assert rewards.shape == (BATCH,) and dones.shape == (BATCH,)
        if k == 0:
            compiled = [f._cache_size() for f in jitted]
        if k < 9:
            assert not dones.any() and not extras["time_outs"].any() and extras["log"] == {}
    assert dones.all() and extras["time_outs"].all()  # the 0.2 s limit: time-outs, to be bootstrapped
    # the programs of the first step and of the reset's warm-up serve every later step and reset (actions that
    # came in committed to a device, as DLPack makes them, compiled the step and the reset again)
    assert [f._cache_size() for f in jitted] == compiled
    assert extras["log"]["/episode/length"] == 10.0
    assert {"/episode/return", "/episode/reward/tracking_lin_vel"} <= set(extras["log"])
    assert (venv.episode_length_buf == 0).all()  # the environments were reset


def test_run_directory_is_complete_and_resume_continues(trained_run):
    run_dir, before, checkpoints_before = trained_run
    run = RunDir(run_dir)
    assert [r["step"] for r in before] == [40, 80]
    assert checkpoints_before == ["step_000000000040.pt"]
    records = run.metrics()
    # resumed from the step-40 checkpoint: the step-80 record logged after it is written again, not twice
    assert [r["step"] for r in records] == [40, 80, 120]
    assert all("episode_return" in r for r in records)
    assert before[1]["episodes"] == BATCH and before[1]["episode_length"] == 10.0  # the 0.2 s episodes ended
    assert records[-1]["iteration"] == 3
    config = run.load_config()
    assert config.task == "go1-flat" and config.env.episode_seconds == EPISODE_S and config.ppo.actor_hidden == (32, 32)
    assert [p.name for p in run.checkpoints()][-1] == "step_000000000120.pt"
    assert list((run_dir / "tb").glob("events.out.tfevents.*"))
    assert not list(run.checkpoint_dir.glob(".*tmp"))  # no half-written checkpoint left behind


def test_a_finished_run_trains_further_to_a_new_total(trained_run, tiny_env, tmp_path, monkeypatch):
    run_dir = tmp_path / "tiny"
    shutil.copytree(trained_run[0], run_dir)
    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    with torch_threads_kept():
        with pytest.raises(ConfigError, match="not past"):  # the total, not the steps to add
            training.resume_run(str(run_dir), progress=False, timesteps=120)
        training.resume_run(str(run_dir), progress=False, timesteps=160)
    run = RunDir(run_dir)
    assert [r["step"] for r in run.metrics()] == [40, 80, 120, 160]
    assert run.load_config().timesteps == 160  # the new total is the run's own
    assert [p.name for p in run.checkpoints()][-2:] == ["step_000000000120.pt", "step_000000000160.pt"]


def test_every_record_splits_its_iteration_time(trained_run):
    records = RunDir(trained_run[0]).metrics()
    for r in records:
        parts = [r[f"time_{p}_s"] for p in ("physics", "env", "policy", "update")]
        assert all(p >= 0 for p in parts) and r["time_physics_s"] > 0 and r["time_saving_s"] >= 0
        assert sum(parts) <= BATCH * 5 / r["steps_per_s"] + 1e-6  # parts of the iteration (TINY: 5 steps each)
    # the first iteration of a run and of its resume have written nothing yet; then the record and checkpoint
    assert records[0]["time_saving_s"] == 0.0 and records[1]["time_saving_s"] == 0.0 and records[2]["time_saving_s"] > 0


def test_eval_is_deterministic_and_onnx_matches(trained_run, tiny_env, tmp_path):
    run_dir, _, _ = trained_run
    policy, config = load_policy(run_dir)
    assert policy.step == 120 and policy.obs_size == 42
    # the native engine the run trained in (its compiled functions reused); MJX's evaluation: the test below, and the
    # engines' agreement on this task: tests/test_mjx_vs_native.py, tests/test_mjx_randomized.py
    first = evaluate(tiny_env, policy, episodes=BATCH, seed=3, physics="native", num_envs=BATCH, threads=1,
                     progress=False)
    again = evaluate(tiny_env, policy, episodes=BATCH, seed=3, physics="native", num_envs=BATCH, threads=1,
                     progress=False)
    assert first == again
    report = summarize(first, confined=False)
    assert report["episodes"] == BATCH and report["episode_length_steps"] == 10.0
    assert 0.0 <= report["tracking_error_mps"] and report["falls"] == 0
    halves = evaluate(tiny_env, policy, episodes=BATCH, seed=3, physics="native", num_envs=BATCH // 2, progress=False)
    assert len(halves) == BATCH and all(f["length"] == 10.0 for f in halves)  # two rounds, every episode whole
    export = export_onnx(policy, tmp_path / "policy.onnx")
    assert export["max_abs_diff"] <= 1e-4 and (tmp_path / "policy.onnx").stat().st_size > 1000


class Pusher:
    """A policy for SlidingBlock: both actions push the block toward the origin."""

    inputs = ("state",)

    def reset(self, done=None):
        pass

    def act(self, obs):
        push = -np.clip(2.0 * np.asarray(obs)[:, :1], -1.0, 1.0)
        return np.repeat(push, 2, axis=1).astype(np.float32)


def test_mjx_evaluation_runs_every_episode_whole_and_deterministically():
    """`evaluate` on MJX (VectorEnv's jitted, auto-resetting step) on a pure-JAX task that compiles in seconds: six
    episodes on four environments (two rounds, the second with two), each to its end, its return the sum of its
    rewards, the same figures twice."""
    env = SlidingBlock()
    first = evaluate(env, Pusher(), episodes=6, seed=3, num_envs=4, progress=False)
    assert first == evaluate(env, Pusher(), episodes=6, seed=3, num_envs=4, progress=False)
    assert len(first) == 6 and all(f["length"] == 10.0 for f in first)
    assert all(f["return"] == pytest.approx(f["reward/position"]) and f["return"] < 0.0 for f in first)
    assert len({round(f["return"], 6) for f in first}) == 6  # six different starts
    assert first != evaluate(env, Pusher(), episodes=6, seed=4, num_envs=4, progress=False)


def test_native_training_is_reproducible(tiny_env, tmp_path, monkeypatch):
    """Two native-physics runs with the same seed and thread count log the same metrics."""
    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    runs = []
    for name in ("a", "b"):
        with torch_threads_kept():
            training.start_run("go1-flat", str(tmp_path / name), num_envs=BATCH, timesteps=80, overrides=TINY,
                               progress=False, physics="native", threads=1)
        runs.append([{k: v for k, v in r.items() if k not in ("steps_per_s", "wall_s", "startup_s")
                      and not k.startswith("time_")} for r in RunDir(tmp_path / name).metrics()])
    assert runs[0] == runs[1] and len(runs[0]) == 2
    assert RunDir(tmp_path / "a").load_config().physics == "native"


def test_a_randomisation_ramp_grows_with_the_steps_trained(tiny_env, tmp_path, monkeypatch):
    """With randomization_ramp, each rollout's new episodes (and the first ones) draw at the ramp's scale of the
    steps trained so far, logged with every record; a resumed run goes on along the ramp."""
    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    scales = []
    monkeypatch.setattr(RslVecEnv, "set_randomization_scale",
                        lambda self, s, original=RslVecEnv.set_randomization_scale: (scales.append(s),
                                                                                     original(self, s)))
    with torch_threads_kept():
        training.start_run("go1-flat", str(tmp_path / "run"), num_envs=BATCH, timesteps=80, progress=False,
                           overrides=TINY + ["randomization_ramp=160"], physics="native", threads=1)
        config = tmp_path / "run" / "config.yaml"
        config.write_text(config.read_text().replace("timesteps: 80\n", "timesteps: 160\n"))
        training.resume_run(str(tmp_path / "run"), progress=False)
    assert scales == [0.0, 0.25, 0.5, 0.75]
    assert [r["randomization_scale"] for r in RunDir(tmp_path / "run").metrics()] == [0.0, 0.25, 0.5, 0.75]


def test_a_randomisation_curriculum_is_saved_and_resumed(tiny_env, tmp_path, monkeypatch):
    """With randomization_curriculum, the mean scale is logged with every record, each environment's scale is saved
    with each checkpoint, and a resumed run starts its environments at the saved scales (the first run at 0)."""
    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    started = []
    monkeypatch.setattr(RslVecEnv, "__init__", lambda self, *a, original=RslVecEnv.__init__, **k: (
        started.append((k["dr_scale"], k["dr_step"])), original(self, *a, **k))[1])
    overrides = [o for o in TINY if not o.startswith("randomization_curriculum")] + ["randomization_curriculum=0.5"]
    with torch_threads_kept():
        training.start_run("go1-flat", str(tmp_path / "run"), num_envs=BATCH, timesteps=120, progress=False,
                           overrides=overrides, physics="native", threads=1)
        run = RunDir(tmp_path / "run")
        saved = torch.load(run.latest_checkpoint(), weights_only=False)["randomization_scales"].numpy()
        config = tmp_path / "run" / "config.yaml"
        config.write_text(config.read_text().replace("timesteps: 120\n", "timesteps: 160\n"))
        training.resume_run(str(tmp_path / "run"), progress=False)
    assert saved.shape == (BATCH,) and np.all((saved >= 0) & (saved <= 1)) and np.all(saved * 2 == np.round(saved * 2))
    assert started[0] == (0.0, 0.5) and np.array_equal(started[1][0], saved) and started[1][1] == 0.5
    logged = [r["randomization_scale"] for r in run.metrics()]
    assert len(logged) == 4 and logged[2] == pytest.approx(saved.mean())


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
    # a deployed policy is checked on what its actor reads: critics' inputs may differ (another robot model)
    sizes = tiny_env.observation_dims()
    policy = types.SimpleNamespace(inputs=("state",), obs_sizes=dict(sizes, privileged_state=1), num_actions=12,
                                   checkpoint=tmp_path / "x.pt")
    check_policy(policy, tiny_env)
    with pytest.raises(RunDirError, match="reads observations"):
        check_policy(types.SimpleNamespace(**dict(vars(policy), obs_sizes=dict(sizes, state=1))), tiny_env)
    assert main(["eval", str(tmp_path), "--episodes", "2"]) == 2


def test_a_run_that_fails_to_start_leaves_nothing_behind(tmp_path, capsys):
    from legged.cli import main

    source = RunDir(tmp_path / "src").create(TrainConfig(task="go1-flat", backend="brax").resolved())
    command = ["train", "go1-flat", "--physics", "native", "--num-envs", "4", "--timesteps", "96",
               "--run-dir", str(tmp_path / "new"), "--init-from", str(source.path)]
    for _ in range(2):  # the retry meets the same error, not "already holds a run"
        assert main(command) == 2
        assert "brax backend" in capsys.readouterr().err
        assert not (tmp_path / "new").exists()
    started = RunDir(tmp_path / "kept").create(TrainConfig(task="go1-flat").resolved())
    started.write_checkpoint(96, "pt", b"x")
    assert not started.discard_unstarted() and started.config_path.exists()


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


def test_a_diverging_run_stops_keeps_its_last_good_checkpoint_and_resumes(tiny_env, tmp_path, monkeypatch):
    """A parameter turned NaN by an update stops the run: nothing is saved after it, NaN-free resume."""
    from rsl_rl.algorithms import PPO

    from policies.rsl_backend import TrainingDiverged

    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    real_update, calls = PPO.update, []

    def poisoned_update(self):
        losses = real_update(self)
        calls.append(1)
        if len(calls) == 2:
            next(self.actor.parameters()).data.fill_(float("nan"))
        return losses

    monkeypatch.setattr(PPO, "update", poisoned_update)
    run_dir = tmp_path / "diverging"
    diverged = pytest.raises(TrainingDiverged, match="actor parameters not finite.*step_000000000040.pt")
    with torch_threads_kept(), diverged:
        training.start_run("go1-flat", str(run_dir), num_envs=BATCH, timesteps=120, overrides=TINY, progress=False,
                           physics="native", threads=1)  # native, like `trained_run`: no MJX training compiled
    run = RunDir(run_dir)
    assert [p.name for p in run.checkpoints()] == ["step_000000000040.pt"]
    assert [r["step"] for r in run.metrics()] == [40, 80]  # the bad iteration is logged, not saved
    monkeypatch.setattr(PPO, "update", real_update)
    with torch_threads_kept():
        record = training.resume_run(str(run_dir), progress=False)
    assert record["step"] == 120 and all(np.isfinite(v) for k, v in record.items() if k.startswith("loss_"))


def test_pickled_checkpoints_are_refused_until_converted_by_the_user(trained_run, tmp_path):
    """A checkpoint holding numpy objects (pickles) is not loaded; `convert-checkpoints --trust-pickles`
    rewrites it as tensors, after which the safe loader reads it."""
    import shutil

    from policies.convert import convert_run
    from policies.rsl_backend import load_checkpoint

    run_dir, _, _ = trained_run
    copy = tmp_path / "old-run"
    shutil.copytree(run_dir, copy)
    path = RunDir(copy).latest_checkpoint()
    payload = load_checkpoint(path)
    payload["opponent_pool"] = {"snapshots": [{"weight": 1.0, "mean": np.ones(3, np.float32)}], "rng": {"state": 7}}
    torch.save(payload, path)  # numpy arrays inside: a pickle
    with pytest.raises(RunDirError, match="not loaded"):
        load_checkpoint(path)
    with pytest.raises(RunDirError, match="--trust-pickles"):
        convert_run(copy, trust_pickles=False)
    report = convert_run(copy, trust_pickles=True)
    assert report["converted"] == [str(path)]
    pool = load_checkpoint(path)["opponent_pool"]
    assert isinstance(pool["snapshots"][0]["mean"], np.ndarray) and pool["snapshots"][0]["mean"].sum() == 3.0


def test_plot_overlays_runs_one_colour_each(trained_run, tmp_path, capsys):
    import json
    import shutil

    from PIL import Image

    from legged.cli import main
    from policies.plots import COLOURS

    run_dir = trained_run[0]
    other = shutil.copytree(run_dir, tmp_path / "other")
    records = RunDir(other).metrics()
    shifted = lambda v: None if v is None else v + 100.0  # a second run whose line lies elsewhere
    (other / "metrics.jsonl").write_text("".join(json.dumps(dict(r, episode_return=shifted(r["episode_return"])))
                                                 + "\n" for r in records))
    out = tmp_path / "both.png"
    assert main(["plot", str(run_dir), str(other), "--y", "episode_return", "--out", str(out)]) == 0
    pixels = {colour for _, colour in Image.open(out).convert("RGB").getcolors(maxcolors=1 << 20)}
    assert COLOURS[0] in pixels and COLOURS[1] in pixels and COLOURS[2] not in pixels  # a line (and label) per run
    assert main(["plot", str(run_dir), str(shutil.copytree(run_dir, tmp_path / "x" / run_dir.name))]) == 2
    assert "share a folder name" in capsys.readouterr().err


def test_a_learning_curve_plots_held_out_figures_against_time_from_process_start(trained_run, tmp_path, capsys):
    """`legged curve`: each checkpoint evaluated on the same held-out episodes, placed at the seconds from its
    training process's start (every process's first record holds its start-up: imports, build, compilation)."""
    import json

    from legged.cli import main
    from policies.learning_curve import saved_at

    run_dir = trained_run[0]
    records = RunDir(run_dir).metrics()  # step 40 by the first process, 80 (again) and 120 by the resumed one
    assert records[0]["startup_s"] > 0 and records[1]["startup_s"] > 0 and "startup_s" not in records[2]
    times = saved_at(RunDir(run_dir))
    assert times[40] == pytest.approx(records[0]["startup_s"] + records[0]["wall_s"])
    assert times[120] == pytest.approx(records[0]["startup_s"] + records[1]["startup_s"] + records[2]["wall_s"])
    out = tmp_path / "curve.png"
    assert main(["curve", str(run_dir), "--every", "2", "--episodes", "2", "--num-envs", "2", "--physics", "native",
                 "--threads", "1", "--out", str(out), "--json", "--quiet"]) == 0  # checkpoints 120 and 40
    report = json.loads(capsys.readouterr().out)
    points = report["curves"][0]["points"]
    assert [p["step"] for p in points] == [40, 120] and points[0]["wall_s"] < points[1]["wall_s"]
    assert all(p["tracking_error_mps"] >= 0 and p["episodes_with_a_fall"] == 0.0 for p in points)
    assert out.stat().st_size > 1000 and report["plot"] == str(out)
    empty = RunDir(tmp_path / "empty")
    empty.create(TrainConfig(task="go1-flat").resolved())
    assert main(["curve", str(empty.path), "--episodes", "2"]) == 2  # nothing to evaluate: one line
    assert "has no checkpoint to evaluate" in capsys.readouterr().err
    confined = RunDir(tmp_path / "confined")
    confined.create(TrainConfig(task="confined-waypoints").resolved())
    assert main(["curve", str(confined.path)]) == 2  # a confined run's figures are per level: one must be named
    assert "evaluated per difficulty level; give one, e.g. --difficulty 0" in capsys.readouterr().err
    assert main(["curve", str(confined.path), "--difficulty", "0"]) == 2
    assert "has no checkpoint to evaluate" in capsys.readouterr().err


def test_table_puts_saved_evaluations_side_by_side(tmp_path, capsys):
    import json

    from legged.cli import main

    for name, ret, ood in (("teacher", 1234.5, 900.0), ("hib", 1100.25, 950.0)):
        (tmp_path / name).mkdir()
        for file, value in (("eval_native.json", ret), ("eval_ood_native.json", ood)):
            (tmp_path / name / file).write_text(json.dumps({"episode_return": value, "episodes_with_a_fall": 0.02,
                                                            "trained_steps": 40_000_000}))
    runs = [str(tmp_path / "teacher"), str(tmp_path / "hib")]
    assert main(["table", *runs, "--files", "eval_native.json,eval_ood_native.json",
                 "--metrics", "episode_return,episodes_with_a_fall"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == ("| run | steps | episode_return (eval_native) | episodes_with_a_fall (eval_native) | "
                        "episode_return (eval_ood_native) | episodes_with_a_fall (eval_ood_native) |")
    assert lines[2] == "| teacher | 40,000,000 | 1,234 | 0.02 | 900 | 0.02 |"
    assert lines[3] == "| hib | 40,000,000 | 1,100 | 0.02 | 950 | 0.02 |"
    assert main(["table", *runs, "--metrics", "win_rate"]) == 2
    assert "no win_rate in eval_native.json" in capsys.readouterr().err
