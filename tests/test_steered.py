"""A state pilot trained in its vision student's camera game (policies.soccer.steered)."""

import dataclasses
from pathlib import Path

import jax
import numpy as np
import pytest
import torch

from legged.envs.vector import VectorEnv
from legged.soccer.observe import PROPRIO_SIZE
from policies.config import ConfigError, TrainConfig
from policies.policy_io import load_policy
from policies.rsl_vecenv import RslVecEnv
from policies.run_dir import RunDir
from policies.soccer.config import SoccerTrainConfig

ROOT = Path(__file__).resolve().parents[1]
STUDENT = "assets/policies/op3-soccer-1v1-vision-piloted"
"""A shipped vision student that estimates the game, with the state pilot that steers it (its config's
soccer.pilot)."""


def _pilot_config(soccer: dict | None = None, **changes) -> TrainConfig:
    """The shipped pilot's config, to train it again in its student's game (`soccer`: changes to its soccer
    section, `changes`: to the rest)."""
    pilot = RunDir(ROOT / STUDENT).load_config().soccer.pilot
    config = RunDir(ROOT / pilot).load_config()
    section = dataclasses.replace(config.soccer, **{"steered_student": str(ROOT / STUDENT), **(soccer or {})})
    return dataclasses.replace(config, soccer=section, **changes)


def test_a_pilot_in_its_students_game_sees_and_plays_as_it_steers_the_student():
    """Each step of the steered game: the learner reads [proprioception, the student's estimate as its game uses it]
    and its corrections move the robots exactly as when it steers the student (`--pilot`, LearnerView.steer_with)
    from the same start."""
    from policies.soccer.steered import steered_env
    from policies.training import build_env

    student_config = RunDir(ROOT / STUDENT).load_config()
    steered = steered_env(_pilot_config())
    assert steered.action_size == 3
    assert steered.observation_dims() == {"state": PROPRIO_SIZE + 14,
                                          "privileged_state": steered.view.observation_dims()["privileged_state"]}
    venv = steered.vec_env(RslVecEnv(VectorEnv.of(steered.view, 2, "native", 1), seed=3))
    pilot = load_policy(ROOT / student_config.soccer.pilot)[0]
    piloted = build_env(student_config, progress=False)  # the student steered by the same pilot, as eval plays it
    vector = VectorEnv.of(piloted, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(3))
    student = load_policy(ROOT / STUDENT)[0]
    used = jax.jit(jax.vmap(piloted.used_estimate))
    for _ in range(3):
        obs = venv.get_observations()
        estimate = student.act({k: np.asarray(batch.state.obs[k]) for k in student.inputs})
        np.testing.assert_allclose(obs["state"][:, :PROPRIO_SIZE].numpy(),
                                   np.asarray(batch.state.obs["state"][:, :PROPRIO_SIZE]), atol=1e-6)
        np.testing.assert_allclose(obs["state"][:, PROPRIO_SIZE:].numpy(),
                                   np.asarray(used(batch.state, estimate)), atol=1e-5)
        venv.step(torch.as_tensor(pilot.act(obs["state"].numpy())))
        batch, _ = vector.step(batch, jax.numpy.asarray(estimate))
        np.testing.assert_allclose(np.asarray(venv.inner.batch.state.pipeline_state.qpos),
                                   np.asarray(batch.state.pipeline_state.qpos), atol=1e-4)


def test_steered_student_names_a_vision_student_of_the_same_game_and_skills():
    """A steered pilot is a state soccer player on the placo prior, and its student a vision student that
    estimates that game with the same walker: anything else is refused by name before anything compiles."""
    from policies.soccer.steered import steered_env

    with pytest.raises(ConfigError,
                       match="soccer.steered_student .* needs a state soccer task with soccer.command_prior=placo"):
        TrainConfig(task="soccer-1v1", soccer=SoccerTrainConfig(steered_student=STUDENT)).resolved()
    with pytest.raises(ConfigError, match="a vision student that estimates the game"):
        steered_env(_pilot_config({"steered_student": str(ROOT / "assets/policies/op3-soccer-1v1")}))
    with pytest.raises(ConfigError, match="this run must command the same"):
        steered_env(_pilot_config({"getup": ""}))


def test_a_steered_pilot_trains_in_its_students_game(tmp_path):
    """`legged train --set soccer.steered_student=...` from the shipped pilot (init_from): train_rsl plays the student's
    game, wraps it in the steered VecEnv, warm-starts the learner by its state layout and writes a checkpoint."""
    from policies.training import _train

    pilot = str(ROOT / RunDir(ROOT / STUDENT).load_config().soccer.pilot)
    config = _pilot_config(num_envs=4, timesteps=4 * 24, threads=1, checkpoint_every=1, init_from=pilot,
                           random_episode_start=False)
    run = RunDir(tmp_path / "steered").create(config)
    record = _train(config, run, resume=False, progress=False)
    assert record["step"] == 4 * 24 and np.isfinite(record["reward_per_step"])
    assert run.latest_checkpoint().name == f"step_{4 * 24:012d}.pt"
