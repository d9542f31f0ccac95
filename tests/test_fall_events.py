"""Falls counted as they happen (legged.envs.events): in a real game a robot knocked over twice that gets up once
counts 2 falls, 1 get-up completed and the time it lay; a Go1 that falls ends its episode with 1 fall; the
summaries name what they count."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.math import quat_to_mat
from legged.envs.vector import VectorEnv
from legged.robots.op3 import OP3
from legged.soccer.config import SoccerConfig
from legged.soccer.env import SoccerEnv
from legged.soccer.getup_motion import getup_motion
from legged.soccer.learner import LearnerView
from legged.soccer.observe import PROPRIO_SIZE
from legged.soccer.opponents import OpponentNet, network_opponent
from legged.soccer.placo.gait_table import load_gait_table
from legged.skills.config import WalkSkillConfig
from legged.soccer.walker import Walker
from legged.tasks import make
from policies.evaluate import fall_figures, summarize

pytestmark = pytest.mark.slow


def _standing_walker() -> Walker:
    """A walker whose network asks for nothing (the robot holds its default pose), with the scripted get-up."""
    walk, n = WalkSkillConfig(), PROPRIO_SIZE + 8
    zero = [(np.zeros((n, 20), np.float32), np.zeros(20, np.float32))]
    return Walker(policy=network_opponent(np.zeros(n), np.ones(n), zero), net=OpponentNet("elu"),
                  command_low=walk.command_low, command_high=walk.command_high, gait=load_gait_table(),
                  dt=walk.ctrl_dt, residual=False, default_pose=tuple(OP3.default_pose),
                  action_scale=OP3.action_scale, getup_motion=getup_motion())


def _knock_over(vector, batch, env):
    """The learner put on its back, at rest, in the engine and in the state (as a push that floored it would)."""
    adr = int(env.game.layout.root_qpos_adr[0])
    qpos = np.array(batch.state.pipeline_state.qpos)
    qpos[0, adr + 2] = 0.09
    qpos[0, adr + 3:adr + 7] = [np.cos(np.pi / 4), 0.0, -np.sin(np.pi / 4), 0.0]  # pitched back a quarter turn
    qvel = np.zeros_like(np.asarray(batch.state.pipeline_state.qvel))
    vector.native.physics.load(np.array([0]), qpos, qvel, np.asarray(batch.state.pipeline_state.ctrl), fresh=False)
    state = batch.state.replace(pipeline_state=batch.state.pipeline_state.replace(qpos=jnp.asarray(qpos),
                                                                                  qvel=jnp.asarray(qvel)))
    return dataclasses.replace(batch, state=state)


def _down(env, batch) -> bool:
    """The game's fall rule for the learner, read from its pose: torso low or tilted."""
    config, adr = env.game.config, int(env.game.layout.root_qpos_adr[0])
    qpos = np.asarray(batch.state.pipeline_state.qpos)[0]
    up_z = float(np.asarray(quat_to_mat(jnp.asarray(qpos[adr + 3:adr + 7])))[2, 2])
    return bool(qpos[adr + 2] < config.fall_height or up_z < config.flip_up_z)


def test_a_robot_knocked_over_twice_that_gets_up_once_counts_two_falls_and_one_getup():
    scene = dataclasses.replace(SoccerConfig().scene, limb_floor_contacts=True)
    game = SoccerEnv(SoccerConfig(end_on_fall="never", scene=scene, episode_seconds=60.0))
    env = LearnerView(game, walker=_standing_walker())
    vector = VectorEnv(env, 1, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(0))
    still = jnp.zeros((1, env.action_size))
    down_steps, steps, knocks = 0, 0, 0
    batch = _knock_over(vector, batch, env)
    knocks += 1
    while steps < 600:
        batch, result = vector.step(batch, still)
        steps += 1
        down_steps += _down(env, batch)
        assert not bool(result.done[0])
        if float(batch.sums["events/getups_completed"][0]) == 1.0:
            break
    assert float(batch.sums["events/getups_completed"][0]) == 1.0, "the scripted get-up did not stand the robot"
    for _ in range(10):  # standing again, walking in place
        batch, _ = vector.step(batch, still)
        down_steps += _down(env, batch)
    batch = _knock_over(vector, batch, env)
    batch, _ = vector.step(batch, still)  # the step that sees the second fall
    down_steps += _down(env, batch)
    sums = {k: float(v[0]) for k, v in batch.sums.items()}
    assert sums["events/falls"] == 2.0
    assert sums["events/getups_started"] == 1.0 and sums["events/getups_completed"] == 1.0
    assert sums["events/seconds_down"] == pytest.approx(down_steps * env.dt, abs=1e-4)
    assert down_steps > 10  # it lay for a while
    assert sums["reward/fall"] / game.config.rewards.fall == pytest.approx(sums["events/falls"])


def test_a_go1_fall_ends_its_episode_with_one_fall():
    env = make("go1-flat")
    vector = VectorEnv(env, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(0))
    qpos = np.array(batch.state.pipeline_state.qpos)
    qpos[0, 2] = 0.1  # the trunk on the floor
    vector.native.physics.load(np.array([0]), qpos[:1], np.zeros_like(np.asarray(batch.state.pipeline_state.qvel))[:1],
                               np.asarray(batch.state.pipeline_state.ctrl)[:1], fresh=False)
    batch, result = vector.step(batch, jnp.zeros((2, env.action_size)))
    assert bool(result.done[0]) and not bool(result.done[1])
    finished = {k: np.asarray(v) for k, v in result.finished.items()}
    assert finished["events/falls"][0] == 1.0 and finished["events/seconds_down"][0] == pytest.approx(env.dt)
    report = summarize([{k: float(v[0]) for k, v in finished.items()}], False)
    assert report["falls"] == 1 and report["episodes_with_a_fall"] == 1.0 and "fall_rate" not in report


def test_fall_figures_count_every_fall_not_the_last_step():
    finals = [{"events/falls": 3.0, "events/seconds_down": 4.5, "events/getups_started": 3.0,
               "events/getups_completed": 2.0, "fell": 0.0},
              {"events/falls": 0.0, "events/seconds_down": 0.0, "events/getups_started": 0.0,
               "events/getups_completed": 0.0, "fell": 0.0}]
    assert fall_figures(finals) == {"falls": 3, "falls_per_episode": 1.5, "episodes_with_a_fall": 0.5,
                                    "seconds_down_per_episode": 2.25, "getups_started_per_episode": 1.5,
                                    "getups_completed_per_episode": 1.0}
    assert fall_figures([{"return": 1.0}]) == {}
