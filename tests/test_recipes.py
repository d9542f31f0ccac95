"""A task's training recipe: the settings a new run starts from (policies.recipes)."""

import pytest

from policies.config import ConfigError, TrainConfig, apply_overrides
from policies.recipes import RECIPES, task_config


def test_a_new_go1_flat_run_starts_from_its_recipe_and_the_command_line_wins():
    """The recipe's values land in the config (and so in config.yaml); explicit fields and --set overrides come
    after it; the Brax backend and other tasks keep TrainConfig's defaults."""
    config = task_config("go1-flat")
    assert config.num_envs == 512 and config.ppo.actor_hidden == (256, 128, 64)
    assert config.randomization_curriculum == 0.25 and config.random_episode_start
    assert config.env.rewards.feet_air_threshold == 0.2
    assert task_config("go1-flat", num_envs=8, seed=3).num_envs == 8
    assert task_config("go1-flat", num_envs=None).num_envs == 512
    assert apply_overrides(config, ["ppo.actor_hidden=[32]"]).ppo.actor_hidden == (32,)
    defaults = TrainConfig(task="go1-flat", backend="brax", physics="mjx").resolved()
    assert task_config("go1-flat", backend="brax", physics="mjx") == defaults
    assert task_config("confined-waypoints") == TrainConfig(task="confined-waypoints").resolved()
    assert all(backend in ("rsl", "brax") for _, backend in RECIPES)


def test_a_ramp_on_top_of_the_recipe_says_how_to_choose():
    with pytest.raises(ConfigError, match="randomization_curriculum=0"):
        apply_overrides(task_config("go1-flat"), ["randomization_ramp=100"])
    assert apply_overrides(task_config("go1-flat"), ["randomization_ramp=100", "randomization_curriculum=0"]
                           ).randomization_ramp == 100
