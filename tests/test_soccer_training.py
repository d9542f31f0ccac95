"""Training the soccer tasks: self-play snapshots as opponents (data, no recompiling), the vision task's CNN
actor, soccer evaluation figures, and the configuration checks that run before anything is built."""

import numpy as np
import pytest
import torch

from policies import training
from policies.config import ConfigError, PPOConfig, TrainConfig, apply_overrides
from policies.evaluate import summarize
from policies.export import export_onnx
from policies.policy_io import load_policy
from policies.rsl_backend import build_ppo, dummy_observations, save_checkpoint
from policies.algorithms import actor_inputs
from policies.run_dir import RunDir
from policies.soccer.config import SelfPlayConfig

TINY = ["env.episode_seconds=0.25", "ppo.num_steps_per_env=5", "ppo.num_mini_batches=2", "checkpoint_every=1",
        "ppo.actor_hidden=[16]", "ppo.critic_hidden=[16]"]
"""2 envs x 5 steps = 10 env steps per iteration; 10-step episodes."""


def _env(task: str):
    return training.build_env(apply_overrides(TrainConfig(task=task, num_envs=2).resolved(), TINY))


def test_self_play_snapshots_become_opponents_without_recompiling(tmp_path, monkeypatch):
    env = _env("soccer-1v1")
    monkeypatch.setattr(training, "build_env", lambda config: env)
    traces, real_prepare = [], env.prepare  # native physics: the task's prepare is traced inside the step
    monkeypatch.setattr(env, "prepare", lambda *args: (traces.append(len(args)), real_prepare(*args))[1])
    run_dir = tmp_path / "selfplay"
    training.start_run("soccer-1v1", str(run_dir), num_envs=2, timesteps=30, progress=False, physics="native",
                       threads=1, overrides=TINY + ["soccer.selfplay.snapshot_every=1",
                                                    "soccer.selfplay.scripted_fraction=0.0",
                                                    "soccer.selfplay.draw_per_game=false"])
    records = RunDir(run_dir).metrics()
    assert [r["opponent"] for r in records][0] == -1  # the pool starts empty: the script plays
    assert all(r["opponent"] >= 0 for r in records[1:]) and [r["opponent_pool"] for r in records] == [1, 2, 3]
    payload = torch.load(RunDir(run_dir).latest_checkpoint(), weights_only=False)
    snapshots = payload["opponent_pool"]["snapshots"]
    assert len(snapshots) == 3 and snapshots[0]["weight"] == 1.0
    assert snapshots[0]["layers"][0][0].shape == (env.game.policy_state_size, 16)
    assert not np.allclose(snapshots[0]["layers"][0][0], snapshots[2]["layers"][0][0])  # the learner moved on
    assert traces == [3]  # script and snapshots, all passed as data: the step was traced (compiled) once
    ended = [r for r in records if r["episodes"]]
    assert ended and {"episode_goals_for", "episode_goals_against", "episode_reward_goal"} <= set(ended[0])

    per_game = tmp_path / "per-game"  # the default: a drawn opponent plays until a game ends
    training.start_run("soccer-1v1", str(per_game), num_envs=2, timesteps=80, progress=False, physics="native",
                       threads=1, overrides=TINY + ["soccer.selfplay.snapshot_every=1",
                                                    "soccer.selfplay.scripted_fraction=0.0"])
    records = RunDir(per_game).metrics()
    draws = [i for i in range(1, len(records)) if records[i - 1]["episodes"]]  # iterations after a game ended
    assert draws and all(records[i]["opponent"] >= 0 for i in draws)
    held = [i for i in range(1, len(records)) if i not in draws]
    assert held and all(records[i]["opponent"] == records[i - 1]["opponent"] for i in held)
    assert records[0]["opponent"] == -1 and records[draws[0] - 1]["opponent"] == -1  # the first game: the script


def test_a_run_without_self_play_plays_the_configured_script(tmp_path, monkeypatch):
    import policies.soccer.selfplay as selfplay

    env = _env("soccer-1v1")
    monkeypatch.setattr(training, "build_env", lambda config: env)
    made = []
    real = selfplay.script_opponents
    monkeypatch.setattr(selfplay, "script_opponents", lambda *args: made.append(real(*args)) or made[-1])
    run_dir = tmp_path / "scripted"
    training.start_run("soccer-1v1", str(run_dir), num_envs=2, timesteps=20, progress=False, physics="native",
                       threads=1, overrides=TINY + ["soccer.selfplay.opponent=scripted"])
    assert [r["opponent"] for r in RunDir(run_dir).metrics()] == [-1, -1]
    assert len(made) == 1 and len(made[0]) == 1 and float(made[0][0].placo) == 1.0  # the placo player, not standing
    standing = selfplay.script_opponents(SelfPlayConfig(script="standing"), 8, 3, 2)
    assert len(standing) == 2 and float(standing[0].placo) == 0.0  # 2v2: the teammate plays the script too


def test_random_episode_starts_end_the_first_episodes_early(tmp_path, monkeypatch):
    env = training.build_env(apply_overrides(TrainConfig(task="soccer-1v1", num_envs=4).resolved(), TINY))
    monkeypatch.setattr(training, "build_env", lambda config: env)
    ended = {}
    for random_start in (False, True):
        run_dir = tmp_path / str(random_start)
        training.start_run("soccer-1v1", str(run_dir), num_envs=4, timesteps=20, progress=False, physics="native",
                           threads=1, overrides=TINY + [f"random_episode_start={str(random_start).lower()}"])
        ended[random_start] = RunDir(run_dir).metrics()[0]["episodes"]
    assert ended == {False: 0, True: ended[True]} and ended[True] > 0  # 10-step episodes, 5 steps per iteration
    with pytest.raises(ConfigError, match="random_episode_start is for --backend rsl"):
        apply_overrides(TrainConfig(task="soccer-1v1", backend="brax").resolved(), ["random_episode_start=true"])


def test_camera_tasks_get_a_cnn_actor_that_saves_loads_and_acts(tmp_path):
    """The vision task's actor (without compiling the MJX env: that path is the self-play test's)."""
    sizes = {"state": 66, "privileged_state": 97, "camera": (4, 30, 40)}
    ppo = PPOConfig(actor_hidden=(16,), critic_hidden=(16,))
    alg = build_ppo(dummy_observations(sizes, 2), 2, 20, ppo, "cpu")
    assert type(alg.get_policy()).__name__ == "CNNModel" and type(alg.critic).__name__ == "MLPModel"
    assert actor_inputs("ppo", camera=True) == ["state", "camera"]
    run = RunDir(tmp_path / "vision")
    run.create(apply_overrides(TrainConfig(task="soccer-1v1-vision").resolved(),
                               ["ppo.actor_hidden=[16]", "ppo.critic_hidden=[16]"]))
    save_checkpoint(run, alg, 1, 10, sizes, 20)
    policy, config = load_policy(run.path)
    assert policy.obs_sizes["camera"] == (4, 30, 40) and config.self_play is False
    rng = np.random.default_rng(0)
    state = np.zeros((3, 66), np.float32)
    actions = policy.act({"state": state, "camera": rng.random((3, 4, 30, 40), dtype=np.float32)})
    assert actions.shape == (3, 20) and not np.allclose(actions[0], actions[1])  # the images matter
    assert export_onnx(policy, tmp_path / "vision.onnx", samples=4)["max_abs_diff"] <= 1e-4


def test_soccer_configs_fail_before_any_work():
    with pytest.raises(ConfigError, match="trains with --backend rsl"):
        TrainConfig(task="soccer-1v1-vision", backend="brax").resolved()
    with pytest.raises(ConfigError, match="soccer.selfplay.opponent=scripted"):
        apply_overrides(TrainConfig(task="soccer-1v1", backend="brax").resolved(),
                        ["soccer.selfplay.opponent=self-play"])
    assert TrainConfig(task="soccer-1v1", backend="brax").resolved().self_play is False
    assert TrainConfig(task="soccer-2v2").resolved().self_play is True
    with pytest.raises(ConfigError, match="soccer.selfplay"):
        apply_overrides(TrainConfig(task="soccer-1v1").resolved(), ["soccer.selfplay.pool_size=0"])


def test_soccer_evaluation_figures():
    events = lambda falls: {"events/falls": falls, "events/seconds_down": 0.5 * falls, "fell": 0.0}
    finals = [{"return": 1.0, "length": 10, "goals_for": 2.0, "goals_against": 1.0, "reward/goal": 1.0, **events(0.0)},
              {"return": -1.0, "length": 4, "goals_for": 0.0, "goals_against": 0.0, "reward/goal": 0.0, **events(3.0)}]
    report = summarize(finals, confined=False)  # the second fell 3 times, got up and stood at the end
    assert report["win_rate"] == 0.5 and report["episodes_with_a_fall"] == 0.5 and report["falls"] == 3
    assert report["falls_per_episode"] == 1.5 and report["seconds_down_per_episode"] == 0.75
    assert report["goals_for_per_episode"] == 1.0 and report["goals_against_per_episode"] == 0.5


def test_soccer_benchmark_arguments_are_checked(capsys):
    from legged.cli import main

    assert main(["bench", "soccer", "--team-sizes", "3", "--json"]) == 2
    assert "--team-sizes takes 1 and/or 2" in capsys.readouterr().err


def test_a_self_play_snapshot_is_frozen_while_the_learner_trains_on():
    """Adam and the observation normaliser change the actor in place: a snapshot must not see it."""
    from rsl_rl.models import MLPModel

    from legged.soccer.opponents import OpponentNet, network_actions
    from policies.soccer.selfplay import snapshot_rsl_actor

    obs = dummy_observations({"state": 6}, 4)
    actor = MLPModel(obs, {"actor": ["state"]}, "actor", 3, hidden_dims=(8,), obs_normalization=True)
    x = torch.randn(4, 6)
    actor.obs_normalizer.update(x)
    snapshot = snapshot_rsl_actor(actor)
    before = np.asarray(network_actions(OpponentNet("elu"), snapshot, x.numpy()))
    with torch.no_grad():
        for p in actor.parameters():
            p.add_(1.0)
        actor.obs_normalizer.update(x + 10.0)
    after = np.asarray(network_actions(OpponentNet("elu"), snapshot, x.numpy()))
    assert np.array_equal(before, after)
