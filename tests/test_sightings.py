"""The ball and goal detector on the head camera's images (legged.soccer.vision.sightings) against where MuJoCo puts the
ball and the goals, and a student whose state grew by the sightings starting as its source."""

import dataclasses

import jax
import mujoco
import numpy as np
import pytest
import torch
from tensordict import TensorDict

from legged.envs.math import yaw_rotate
from legged.sensors.raycam import poses_of, render
from legged.soccer import KICKOFF_KEY
from legged.soccer.observe import game_features, read_bodies
from legged.soccer.vision.sightings import camera_agents
from legged.tasks import make


def test_the_sightings_find_the_ball_and_the_goals_where_mujoco_puts_them():
    env = make("soccer-1v1-vision", vision_sightings=True)
    scene = dataclasses.replace(env.config.scene, head_camera_fovy_deg=70.0)
    env = type(env)(dataclasses.replace(env.config, scene=scene))
    model, layout = env.mj_model, env.layout
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(KICKOFF_KEY).id)
    mujoco.mj_forward(model, data)
    b = read_bodies(layout, data.qpos, data.qvel)
    pos, yaw = np.asarray(b.pos[0]), float(b.yaw[0])
    adr = layout.ball_qpos_adr
    draw = jax.jit(lambda p: render(env.camera, p))
    for ahead in ([0.5, 0.0], [1.2, 0.4], [2.5, -0.5], [-1.0, 0.0]):  # in the heading frame of robot 0
        world_xy = pos[:2] + np.asarray(yaw_rotate(-yaw, np.asarray(ahead, np.float32)))
        data.qpos[adr:adr + 3] = [*world_xy, scene.ball_radius]
        mujoco.mj_forward(model, data)
        b = read_bodies(layout, data.qpos, data.qvel)
        sight = np.asarray(env.sightings(data, b, draw(poses_of(data))))  # [agents, ball, own goal, opponent goal]
        truth = np.asarray(game_features(b, env._team, env._goals, env._others))
        ball = np.array([*ahead, scene.ball_radius - pos[2]])
        if ahead[0] < 0:  # behind the robot: not seen, and nothing else (the red opponent) is taken for it
            assert np.array_equal(sight[0, :4], np.zeros(4))
        else:
            assert sight[0, 0] == 1.0 and np.linalg.norm(sight[0, 1:4] - ball) < 0.05, (ahead, sight[0, :4])
        for agent in range(2):  # at kick-off each faces the goal it attacks, its own goal behind it
            assert np.array_equal(sight[agent, 4:8], np.zeros(4)), agent
            opponent_goal = truth[agent, 8:10]
            assert sight[agent, 8] == 1.0 and np.linalg.norm(sight[agent, 9:11] - opponent_goal) < 0.45, agent
    with pytest.raises(ValueError, match="no robot's head camera"):
        camera_agents(np.array([layout.head_camera[0] + 100]), layout.head_camera)


def test_a_student_whose_state_grew_starts_acting_as_its_source():
    """`distill.student_init_whole` from a student with a shorter state (e.g. before `env.vision_sightings`):
    the new entries reach the GRU and the head through zero weights, so the new student acts as the old one."""
    from policies.algorithms import CAMERA_CNN
    from policies.students import _grown_state
    from policies.memory_models import MemoryCNNModel

    def student(state: int, seed: int) -> MemoryCNNModel:
        torch.manual_seed(seed)
        obs = TensorDict({"state": torch.randn(3, state), "camera": torch.rand(3, 4, 30, 40)}, batch_size=[3])
        model = MemoryCNNModel(obs, {"actor": ["state", "camera"]}, "actor", 2, memory_dim=6, hidden_dims=[8],
                               obs_normalization=True, cnn_cfg=dict(CAMERA_CNN),
                               distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})
        model.update_normalization(obs)
        return model.eval()

    old, new = student(5, 0), student(9, 1)
    new.load_state_dict(_grown_state(old.state_dict(), new.state_dict(), new.cnn_latent_dim), strict=True)
    assert int(new.obs_normalizer.count) <= int(old.obs_normalizer.count)
    for _ in range(3):  # the memory carries over steps: the new entries must not reach it either
        state, camera = torch.randn(3, 5), torch.rand(3, 4, 30, 40)
        grown = torch.cat([state, 10 * torch.randn(3, 4)], -1)
        with torch.no_grad():
            expected = old(TensorDict({"state": state, "camera": camera}, batch_size=[3]))
            got = new(TensorDict({"state": grown, "camera": camera}, batch_size=[3]))
        torch.testing.assert_close(got, expected)
    same = _grown_state(old.state_dict(), old.state_dict(), old.cnn_latent_dim)
    assert all(torch.equal(torch.as_tensor(same[k]), v) for k, v in old.state_dict().items())
