"""The PettingZoo adapter: native MuJoCo physics under the MJX environment's rules, vision observations."""

import numpy as np
import pytest

from legged.soccer.parallel_env import SoccerParallelEnv


@pytest.fixture(scope="module")
def vision_game():
    return SoccerParallelEnv("soccer-1v1-vision")


def test_passes_pettingzoos_parallel_api_test(vision_game):
    from pettingzoo.test import parallel_api_test

    parallel_api_test(vision_game, num_cycles=25)


def test_vision_observations_are_the_head_camera_images(vision_game):
    """The camera observation is each robot's head camera: its depth channel agrees with MuJoCo's own
    renderer looking through the same camera."""
    from legged.soccer.vision.cameras import native_images

    env = vision_game
    assert env.possible_agents == ["home0", "away0"]
    obs, infos = env.reset(seed=5)
    for _ in range(3):
        obs, rewards, terminations, truncations, infos = env.step({a: np.zeros(20, np.float32) for a in env.agents})
    game = env.env
    try:
        native = native_images(game.mj_model, env.runner.data(0), game.camera)
    except RuntimeError as exc:
        pytest.skip(f"no native rendering here: {exc}")
    for i, agent in enumerate(env.possible_agents):
        assert obs[agent]["state"].shape == (66,) and obs[agent]["camera"].shape == (4, 30, 40)
        assert 0.0 <= obs[agent]["camera"].min() and obs[agent]["camera"].max() <= 1.0
        depth = obs[agent]["camera"][3] * game.config.camera.max_depth
        hit = native["depth"][i] < game.config.camera.max_depth
        assert hit.mean() > 0.2 and np.median(np.abs(depth - native["depth"][i])[hit]) < 0.01
        assert infos[agent]["privileged_state"].shape == (97 + 68,)  # + its drawn model (OP3_RANDOMIZATION)
        assert set(infos[agent]["reward_terms"]) >= {"goal", "vel_to_ball", "fall"}
    assert all(isinstance(r, float) for r in rewards.values())


def test_actions_for_every_agent_are_required(vision_game):
    vision_game.reset(seed=0)
    with pytest.raises(KeyError, match="away0"):
        vision_game.step({"home0": np.zeros(20, np.float32)})


def test_2v2_game_has_four_agents_and_stays_finite_under_random_actions():
    env = SoccerParallelEnv("soccer-2v2")
    assert env.possible_agents == ["home0", "home1", "away0", "away1"]
    obs, infos = env.reset(seed=3)
    assert all(o.shape == (88,) for o in obs.values()) and infos["away1"]["privileged_state"].shape == (105 + 68,)
    rng = np.random.default_rng(0)
    steps = 0
    while env.agents and steps < 8:
        obs, rewards, terminations, truncations, infos = env.step(
            {a: rng.uniform(-1, 1, 20).astype(np.float32) for a in env.agents})
        steps += 1
        assert all(np.all(np.isfinite(o)) for o in obs.values()) and len(rewards) == 4
    assert env.state().shape == (4 * (105 + 68),)
