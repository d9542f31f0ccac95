"""What the confined follower is trained and judged with: the difficulty curriculum (carried from episode
to episode), the warm start from the go1-flat walker, and the fixed held-out evaluation."""

import dataclasses
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import torch

from conftest import BATCH
from legged.envs.curriculum import pick_tile
from legged.envs.native import NativeEnvs
from legged.tasks import make
from policies.config import PPOConfig
from policies.evaluate import confined_eval_config, one_tile_each, wilson_interval
from policies.rsl_backend import build_ppo, dummy_observations
from policies.warm_start import ADAPT_SAMPLES, element_names, input_map, warm_start
from tests.warm_support import random_observations, saved_actor, warm_started

WALKER = Path(__file__).resolve().parents[1] / "assets" / "policies" / "go1-flat-walker-v1"


def _info(level, succeeded, waypoint, path_len=10):
    return {"level": jnp.int32(level), "succeeded": jnp.bool_(succeeded), "waypoint": jnp.int32(waypoint),
            "path_len": jnp.int32(path_len), "tile": jnp.int32(0)}


def test_curriculum_promotes_on_success_and_demotes_short_episodes(confined):
    env = confined.env
    assert int(env.carry(_info(0, True, 9))["level"]) == 1
    assert int(env.carry(_info(1, False, 2))["level"]) == 0   # ended short of half its path
    assert int(env.carry(_info(1, False, 6))["level"]) == 1   # got past half: stays
    assert int(env.carry(_info(0, False, 1))["level"]) == 0   # never below the easiest
    assert int(env.carry(_info(0, True, 9))["tile"]) == -1     # the next tile is drawn, not kept


def test_new_episodes_play_a_tile_of_their_level(confined):
    env = confined.env  # two worlds: difficulty 0 (tile 0) and 2 (tile 1): levels [0, 2]
    assert list(env.levels) == [0, 2]
    pick = jax.jit(lambda key, carry: pick_tile(key, carry, env._tile_level, len(env.levels), True))
    for k in range(6):
        key = jax.random.PRNGKey(k)
        assert [int(x) for x in pick(key, {"level": jnp.int32(1), "tile": jnp.int32(-1)})] == [1, 1]
        assert [int(x) for x in pick(key, {"level": jnp.int32(0), "tile": jnp.int32(-1)})] == [0, 0]
        assert int(pick(key, {"level": jnp.int32(0), "tile": jnp.int32(1)})[0]) == 1  # an evaluator's choice
        assert int(pick(key, {"level": jnp.int32(2), "tile": jnp.int32(-1)})[1]) in (0, 1)  # past the hardest
    assert [int(x) for x in pick(jax.random.PRNGKey(0), None)] == [0, 0]  # first episodes: the easiest


def test_evaluation_plays_one_world_per_episode_in_native_physics(confined):
    env = confined.env
    carry = one_tile_each(3, BATCH, env.terrain.num_tiles)
    assert carry["tile"].tolist() == [(3 + i) % 2 for i in range(BATCH)]
    native = NativeEnvs(env, BATCH)
    state = native.reset(jax.random.split(jax.random.PRNGKey(0), BATCH), carry=carry)
    assert np.asarray(state.info["tile"]).tolist() == carry["tile"].tolist()
    start = np.asarray(env.terrain.starts)[carry["tile"], :2]
    assert np.allclose(np.asarray(state.pipeline_state.qpos)[:, :2], start, atol=1e-5)
    # the engine's own state agrees (the first reset also compiles partial resets, which must leave no trace)
    assert np.allclose(native.physics.batch.bind("qpos")[:, :2], start, atol=1e-5)


def test_eval_config_and_interval():
    config = confined_eval_config(make("confined-waypoints").config, 2, 50, None)
    assert (config.num_worlds, config.difficulties, config.curriculum) == (50, (2,), False)
    assert config.world_seed == 1_000_003  # training seed 0 + the held-out offset
    assert wilson_interval(0, 50) == [0.0, 0.0714]  # 3.84 / 53.84
    low, high = wilson_interval(45, 50)
    assert low < 0.9 < high and high < 1.0


def test_warm_started_follower_acts_as_the_walker_on_shared_inputs():
    """Zero weights on the new inputs (height scans, target height and tilt) and the walker's weights on the
    shared ones: the follower's first policy is the walker, a waypoint ahead read as a velocity command."""
    walker_env, follower_env = make("go1-flat"), make("confined-waypoints")
    src = element_names(walker_env.observation_layout()["state"])
    dst = element_names(follower_env.observation_layout()["state"])
    mapping = input_map(src, dst)
    assert [src[i] for i in mapping[dst.index("command/dx"):dst.index("command/dx") + 2]] == ["command/vx", "command/vy"]
    assert src[mapping[dst.index("command/dyaw")]] == "command/yaw_rate"
    assert (mapping[[n.startswith("exteroception") for n in dst]] == -1).all()

    ppo = PPOConfig(actor_hidden=(128, 128, 128), critic_hidden=(128, 128, 128))
    sizes = follower_env.observation_dims()
    rng = np.random.default_rng(0)
    obs = dummy_observations(sizes, 64)
    for key in obs.keys():
        obs[key] = torch.as_tensor(rng.normal(size=obs[key].shape), dtype=torch.float32)
    follower = build_ppo(obs, 64, 12, ppo, "cpu")
    warm_start(follower, WALKER, follower_env, obs)
    walker = build_ppo(dummy_observations(walker_env.observation_dims(), 64), 64, 12, ppo, "cpu")
    payload = torch.load(sorted((WALKER / "checkpoints").glob("*.pt"))[-1], weights_only=True)
    walker.actor.load_state_dict(payload["alg"]["actor_state_dict"])
    walker_obs = dummy_observations(walker_env.observation_dims(), 64)
    state = obs["state"].clone()
    walker_obs["state"] = state[:, torch.as_tensor(np.flatnonzero(mapping >= 0))][:, np.argsort(mapping[mapping >= 0])]
    with torch.no_grad():
        a = follower.actor(obs, stochastic_output=False)
        b = walker.actor(walker_obs, stochastic_output=False)
    assert torch.allclose(a, b, atol=1e-5)


def test_warm_start_from_the_same_task_copies_every_weight():
    """A new go1-flat run started from a go1-flat run: actor, critic, normalisers and noise as they were; a
    network of other sizes is refused, naming the settings to use."""
    from policies.run_dir import RunDirError

    from legged.envs.config import NoiseConfig, RandomizationConfig

    sizes = make("go1-flat", randomization=RandomizationConfig(), noise=NoiseConfig()).observation_dims()  # the walker's
    obs = dummy_observations(sizes, 8)
    ppo = PPOConfig(actor_hidden=(128, 128, 128), critic_hidden=(128, 128, 128))
    new = build_ppo(obs, 8, 12, ppo, "cpu")
    note = warm_start(new, WALKER, None, obs, "go1-flat")
    assert "same task" in note
    payload = torch.load(sorted((WALKER / "checkpoints").glob("*.pt"))[-1], weights_only=True)["alg"]
    for net, key in ((new.actor, "actor_state_dict"), (new.critic, "critic_state_dict")):
        for name, value in net.state_dict().items():
            assert torch.equal(value, payload[key][name]), name
    with pytest.raises(RunDirError, match="ppo.actor_hidden"):
        warm_start(build_ppo(obs, 8, 12, PPOConfig(actor_hidden=(64, 64)), "cpu"), WALKER, None, obs, "go1-flat")


def test_warm_start_of_the_same_task_with_randomisation_draws_keeps_the_policy():
    """go1-flat as it now trains (the randomisation's draws appended to the privileged state) from the walker trained
    without: the actor is copied whole, its normaliser's sample count too (a fine-tune's first observations must not
    pull settled statistics away); the critic's old inputs keep their weights, the new ones start at zero weight with
    the first batch's statistics, and its normaliser keeps the source's count too."""
    env = make("go1-flat")
    sizes = env.observation_dims()
    obs = dummy_observations(sizes, 8)
    ppo = PPOConfig(actor_hidden=(128, 128, 128), critic_hidden=(128, 128, 128))
    new = build_ppo(obs, 8, 12, ppo, "cpu")
    note = warm_start(new, WALKER, env, obs, "go1-flat")
    assert "42 of 42" in note and f"74 of {sizes['privileged_state']}" in note, note
    payload = torch.load(sorted((WALKER / "checkpoints").glob("*.pt"))[-1], weights_only=True)["alg"]
    for name, value in new.actor.state_dict().items():
        assert torch.equal(value, payload["actor_state_dict"][name]), name
    critic = new.critic.state_dict()
    assert int(critic["obs_normalizer.count"]) == int(payload["critic_state_dict"]["obs_normalizer.count"])
    assert int(critic["obs_normalizer.count"]) != ADAPT_SAMPLES
    batch = obs["privileged_state"][:, 74:].float()
    torch.testing.assert_close(critic["obs_normalizer._mean"][0, 74:], batch.mean(0))
    torch.testing.assert_close(critic["obs_normalizer._std"][0, 74:], batch.std(0).clamp_min(1e-2))
    settled = payload["critic_state_dict"]["obs_normalizer._mean"]
    torch.testing.assert_close(critic["obs_normalizer._mean"][:, :74], settled)
    first = new.critic.state_dict()["mlp.0.weight"]
    assert torch.equal(first[:, :74], payload["critic_state_dict"]["mlp.0.weight"])
    assert torch.count_nonzero(first[:, 74:]) == 0


def test_a_same_task_warm_start_measures_its_new_inputs_over_a_rollout():
    """With `observe` (a rollout of the warm-started policy), the new inputs take the rollout's statistics, not the
    first batch's (the kept sample count never revises them); the old ones and every weight stay as saved."""
    env = make("go1-flat")
    obs = dummy_observations(env.observation_dims(), 8)
    new = build_ppo(obs, 8, 12, PPOConfig(actor_hidden=(128, 128, 128), critic_hidden=(128, 128, 128)), "cpu")
    n = env.observation_dims()["privileged_state"]
    rolled = {"state": (torch.zeros(42), torch.ones(42)),
              "privileged_state": (torch.linspace(-1.0, 1.0, n), torch.linspace(0.001, 2.0, n))}
    calls = []
    note = warm_start(new, WALKER, env, obs, "go1-flat", observe=lambda alg: calls.append(alg) or rolled)
    assert calls == [new] and "measured over a rollout" in note, note
    payload = torch.load(sorted((WALKER / "checkpoints").glob("*.pt"))[-1], weights_only=True)["alg"]
    payload, critic = payload["critic_state_dict"], new.critic.state_dict()
    mean, std = rolled["privileged_state"]
    torch.testing.assert_close(critic["obs_normalizer._mean"][0, 74:], mean[74:])
    torch.testing.assert_close(critic["obs_normalizer._std"][0, 74:], std[74:].clamp_min(1e-2))
    torch.testing.assert_close(critic["obs_normalizer._mean"][:, :74], payload["obs_normalizer._mean"])
    assert torch.equal(critic["mlp.0.weight"][:, :74], payload["mlp.0.weight"])
    assert torch.count_nonzero(critic["mlp.0.weight"][:, 74:]) == 0


def test_rollout_statistics_are_those_of_every_observation_the_rollout_saw():
    """The mean and std over the first observations and those of each step; actions sampled as in training; the hooks
    called as in a rollout; the warm-up's finished episodes not left for the first iteration's record."""
    from policies.rsl_vecenv import EpisodeStats
    from policies.warm_start import rollout_statistics

    gen = torch.Generator().manual_seed(0)
    batches = [torch.randn(4, 3, generator=gen) * (k + 1) for k in range(6)]

    class Venv:
        episode_stats = EpisodeStats()
        seen = 0

        def get_observations(self):
            return {"state": batches[0]}

        def step(self, actions):
            assert actions.shape == (4, 2)
            self.seen += 1
            self.episode_stats.count += 1
            return {"state": batches[self.seen]}, None, torch.zeros(4, dtype=torch.bool), {}

    class Hooks:
        calls = []

        def before_rollout(self, venv):
            self.calls.append("before")

        def after_step(self, dones):
            self.calls.append("step")

    class Actor:
        modes, resets = [], 0

        def __call__(self, obs, stochastic_output):
            self.modes.append(stochastic_output)
            return torch.zeros(4, 2)

        def reset(self, dones):
            self.resets += 1

    venv, hooks, actor = Venv(), Hooks(), Actor()
    stats = rollout_statistics(venv, actor, hooks, steps=5)
    every = torch.cat(batches)
    torch.testing.assert_close(stats["state"][0], every.mean(0))
    torch.testing.assert_close(stats["state"][1], every.std(0))
    assert actor.modes == [True] * 5 and actor.resets == 5 and hooks.calls == ["before"] + ["step"] * 5
    assert venv.episode_stats.count == 0


def test_a_fine_tune_of_the_same_task_goes_on_at_its_sources_curriculum_levels(tmp_path):
    """source_levels: the source's last checkpoint's levels, repeated or cut to the new run's environments, when it
    trained the same task; None for another task or a checkpoint without levels."""
    import shutil

    from policies.warm_start import source_levels

    run = tmp_path / "run"
    shutil.copytree(WALKER, run)
    assert source_levels(run, "go1-flat", 4) is None  # the walker has no curriculum
    last = sorted((run / "checkpoints").glob("*.pt"))[-1]
    payload = torch.load(last, weights_only=True)
    payload["curriculum_levels"] = torch.tensor([3, 1, 4], dtype=torch.int32)
    torch.save(payload, last)
    assert source_levels(run, "go1-flat", 5).tolist() == [3, 1, 4, 3, 1]
    assert source_levels(run, "go1-flat", 2).tolist() == [3, 1]
    assert source_levels(run, "go1-rough", 5) is None


def test_a_same_task_warm_start_goes_on_with_its_sources_optimiser():
    """Adam's moments as the source left them (a first layer rebuilt by layout column by column, a new input's at
    zero) and, with the adaptive schedule, the learning rate it had reached; a fixed schedule keeps this run's rate;
    no optimiser in the source or one of other shapes leaves the new one, unless the source (a slimmed run) kept the
    rate it had reached: the new optimiser then starts there."""
    from policies.warm_start import continue_optimiser

    ppo = PPOConfig(actor_hidden=(16, 16), critic_hidden=(16, 16))
    src_obs = random_observations({"state": 5, "privileged_state": 6}, 8, 0)
    source = build_ppo(src_obs, 8, 3, ppo, "cpu")
    (source.actor(src_obs).square().sum() + source.critic(src_obs).square().sum()).backward()
    source.optimizer.step()  # every moment a weight's own
    for group in source.optimizer.param_groups:
        group["lr"] = 5e-5
    saved = {"optimizer_state_dict": source.optimizer.state_dict()}
    first = lambda alg: dict(alg.actor.named_parameters())["mlp.0.weight"]
    mapping = np.array([0, 1, -1, 2, 3, -1, 4])  # two inputs added to the actor's five
    new_obs = random_observations({"state": 7, "privileged_state": 6}, 8, 1)

    target = build_ppo(new_obs, 8, 3, ppo, "cpu")
    assert continue_optimiser(target, saved, {id(first(target)): mapping}) == "moments" and target.learning_rate == 5e-5
    moment, source_moment = (a.optimizer.state[first(a)]["exp_avg"] for a in (target, source))
    assert torch.equal(moment[:, [0, 1, 3, 4, 6]], source_moment) and torch.count_nonzero(moment[:, [2, 5]]) == 0
    last = [list(alg.critic.parameters())[-1] for alg in (target, source)]
    assert torch.equal(target.optimizer.state[last[0]]["exp_avg_sq"], source.optimizer.state[last[1]]["exp_avg_sq"])

    fixed = build_ppo(new_obs, 8, 3, dataclasses.replace(ppo, schedule="fixed", learning_rate=3e-4), "cpu")
    assert continue_optimiser(fixed, saved, {id(first(fixed)): mapping}) == "moments"
    assert fixed.optimizer.param_groups[0]["lr"] == 3e-4
    assert continue_optimiser(build_ppo(new_obs, 8, 3, ppo, "cpu"), {}, {}) == "new"
    assert continue_optimiser(build_ppo(src_obs, 8, 3, dataclasses.replace(ppo, actor_hidden=(8, 8)), "cpu"),
                              saved) == "new"
    # a slimmed source keeps only the rate it had reached: a new optimiser starts there (adaptive schedule only)
    slimmed = build_ppo(new_obs, 8, 3, ppo, "cpu")
    assert continue_optimiser(slimmed, {}, rate=5e-5) == "rate" and slimmed.learning_rate == 5e-5
    assert slimmed.optimizer.param_groups[0]["lr"] == 5e-5 and not slimmed.optimizer.state
    fixed = build_ppo(new_obs, 8, 3, dataclasses.replace(ppo, schedule="fixed", learning_rate=3e-4), "cpu")
    assert continue_optimiser(fixed, {}, rate=5e-5) == "new" and fixed.optimizer.param_groups[0]["lr"] == 3e-4


def test_warm_start_into_a_state_with_past_steps_acts_as_the_walker():
    """go1-flat with `env.past_steps` (the last steps' joint angles, velocities and actions in `state`) from the
    walker trained without: the past inputs start at zero weight, so the first policy is the walker's."""
    env = make("go1-flat", past_steps=3)
    names = element_names(env.observation_layout()["state"])
    assert sum(n.startswith("past_") for n in names) == 3 * 3 * 12
    ppo = PPOConfig(actor_hidden=(128, 128, 128), critic_hidden=(128, 128, 128))
    new, obs, note = warm_started(WALKER, env, "go1-flat", 12, ppo, seed=1)
    assert f"state: 42 of {env.observation_dims()['state']}" in note, note
    walker = saved_actor(WALKER, make("go1-flat").observation_dims(), 12, ppo)
    walker_obs = obs.clone()
    walker_obs["state"] = obs["state"][:, [i for i, n in enumerate(names) if not n.startswith("past_")]]
    with torch.no_grad():
        assert torch.allclose(new.actor(obs, stochastic_output=False),
                              walker.actor(walker_obs, stochastic_output=False), atol=1e-5)


def test_navigation_geometry():
    """How far the robot is from its plan, and its pose from a free joint (the replanning trigger)."""
    import mujoco

    from policies.navigate import _distance_to_path, _pose_of

    path = np.array([[0.0, 0.0, 0.27], [1.0, 0.0, 0.27], [1.0, 1.0, 0.27]])
    assert _distance_to_path(np.array([0.5, 0.3]), path) == pytest.approx(0.3)
    assert _distance_to_path(np.array([1.4, 0.5]), path) == pytest.approx(0.4)
    assert _distance_to_path(np.array([-1.0, 0.0]), path) == pytest.approx(1.0)
    quat = np.zeros(4)
    mujoco.mju_euler2Quat(quat, np.array([0.1, -0.2, 0.7]), "XYZ")  # extrinsic: Rz(yaw) Ry(pitch) Rx(roll)
    pose = _pose_of(np.concatenate([[1.0, 2.0, 0.3], quat]))
    np.testing.assert_allclose(pose, [1.0, 2.0, 0.3, 0.1, -0.2, 0.7], atol=1e-9)


@pytest.mark.parametrize("bootstraps", [False, True])
def test_reaching_the_goal_ends_as_a_truncation_where_asked(confined, bootstraps):
    """Velocity and skills tasks end at the goal as a truncation (their value is bootstrapped, so stopping
    just short of the goal to keep collecting tracking reward no longer pays); the follower's do not."""
    from legged.envs.confined import ConfinedConfig, ConfinedEnv

    env = ConfinedEnv(ConfinedConfig(mode="velocity", success_bootstraps=bootstraps), terrain=confined.env.terrain)
    native = NativeEnvs(env, 2, 1)
    state = native.reset(jax.random.split(jax.random.PRNGKey(0), 2))
    here = state.pipeline_state.qpos[:, :2]
    goal = state.info["goal"].at[:, :2].set(here)  # the goal where the robots stand
    state = state.replace(info=dict(state.info, goal=goal))
    state = native.step(state, jnp.zeros((2, 12)))
    assert np.all(np.asarray(state.metrics["success"]) == 1.0) and np.all(np.asarray(state.done) == 1.0)
    assert np.all(np.asarray(state.info["truncation"]) == float(bootstraps))
    from legged.tasks import default_config

    assert default_config("confined-velocity").success_bootstraps and default_config("confined-skills").success_bootstraps
    assert not default_config("confined-waypoints").success_bootstraps
