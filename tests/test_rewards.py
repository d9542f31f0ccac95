"""How a step's reward is made from its terms: the clip at 0 of `only_positive_rewards` and the failure penalty,
which is paid after the clip so that a fall always costs it. Pure functions: the file takes a second."""

import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.config import EnvConfig
from legged.envs.confined import ConfinedConfig
from legged.envs.rewards import step_reward


def _terms():
    """Two environments: one earning more than its penalties, one whose penalties outweigh what it earns."""
    return {"tracking": jnp.array([1.0, 0.2]), "torques": jnp.array([-0.3, -0.5])}


def test_the_sum_is_clipped_at_zero_only_when_asked():
    assert np.allclose(step_reward(_terms(), jnp.array([False, False]), False, 0.0), [0.7, -0.3])
    assert np.allclose(step_reward(_terms(), jnp.array([False, False]), True, 0.0), [0.7, 0.0])


def test_a_failure_costs_the_penalty_after_the_clip_and_is_logged():
    terms = _terms()
    reward = step_reward(terms, jnp.array([False, True]), True, -20.0)
    assert np.allclose(reward, [0.7, -20.0])  # the clipped 0 of the failing environment, then the penalty
    assert np.allclose(terms["failure"], [0.0, -20.0])
    quiet = _terms()
    step_reward(quiet, jnp.array([True, True]), True, 0.0)
    assert "failure" not in quiet  # no penalty, no term: logs of tasks without one are unchanged


def test_a_failure_penalty_must_be_a_cost():
    for config in (EnvConfig, ConfinedConfig):
        assert config().failure_penalty == 0.0
        for bad in (1.0, float("nan")):
            with pytest.raises(ValueError, match="failure_penalty"):
                config(failure_penalty=bad)
