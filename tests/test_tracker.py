"""The vision player's tracker (legged.soccer.vision.tracker): odometry, lock-on, net corrections, ball memory, and
its features against the game's own (legged.soccer.observe.game_features)."""

import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.math import yaw_rotate
from legged.soccer.vision.tracker import (BALL_MEMORY_S, TRACKER_INPUT_SIZE, TRACKER_SIZE, tracked_features,
                                          tracked_pose, tracker_inputs, tracker_kickoff, tracker_sight, tracker_start,
                                          tracker_step)

OWN_XY, OPPONENT_XY = np.array([-2.5, 0.0]), np.array([2.5, 0.0])
NETS = np.array([[-2.8, 0.0], [2.8, 0.0]], np.float32)
GOAL_WIDTH = 0.8
PARTS = dict(ball=slice(0, 3), own_goal=slice(6, 8), opponent_goal=slice(8, 10))


def seen_from(pose, ball=None, own=False, opponent=False) -> jnp.ndarray:
    """Sightings [3, 4] a camera at the true `pose` (x, y, yaw) makes of the ball at `ball` and of the nets."""
    ego = lambda xy: np.asarray(yaw_rotate(jnp.float32(pose[2]), jnp.asarray(xy, jnp.float32) - jnp.asarray(pose[:2])))
    rows = [[0.0] * 4 if ball is None else [1.0, *ego(ball), 0.1],
            [1.0, *ego(NETS[0]), 0.2] if own else [0.0] * 4,
            [1.0, *ego(NETS[1]), 0.2] if opponent else [0.0] * 4]
    return jnp.asarray(rows, jnp.float32)


def sight(tracker, sightings):
    return tracker_sight(tracker, sightings, NETS, GOAL_WIDTH)


def test_odometry_moves_the_pose_in_the_world_by_the_command_and_the_gyro():
    tracker = tracker_kickoff(jnp.array([0.0, 0.0, np.pi / 2]))  # facing +y
    assert tracker.shape == (TRACKER_SIZE,)
    for _ in range(40):  # 1 s forward at 0.2 m/s while turning at 0.1 rad/s
        tracker = tracker_step(tracker, jnp.array([0.2, 0.0]), jnp.float32(0.1), jnp.bool_(False), 0.025)
    pose, locked = tracked_pose(tracker)
    assert bool(locked)
    assert float(pose[2]) == pytest.approx(np.pi / 2 + 0.1, abs=1e-5)
    assert np.asarray(pose[:2]) == pytest.approx([-0.01, 0.2], abs=2e-3)  # along +y, bending slightly left
    cov = np.asarray(tracker[3:12]).reshape(3, 3)
    assert np.all(np.diag(cov) > 1e-4)  # uncertainty grows while walking ...
    fallen = tracker_step(tracker, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(True), 0.025)
    walking = tracker_step(tracker, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), 0.025)
    assert np.all(np.diag(np.asarray(fallen[3:12]).reshape(3, 3)) > np.diag(np.asarray(walking[3:12]).reshape(3, 3)))


def test_it_locks_on_when_it_first_sees_the_opponent_net_then_corrects_by_both_nets():
    truth = np.array([-1.2, 0.3, 0.7])
    start = tracker_start(jnp.array([-1.0, 0.0, 0.0]))  # the kick-off pose; turned by 0.7 rad in truth
    blind = sight(start, seen_from(truth, own=True))  # the own net alone does not lock it on
    assert not bool(tracked_pose(blind)[1])
    np.testing.assert_array_equal(np.asarray(blind[:3]), np.asarray(start[:3]))
    locked = sight(start, seen_from(truth, opponent=True))
    pose, on = tracked_pose(locked)
    assert bool(on)
    assert float(pose[2]) == pytest.approx(truth[2], abs=0.1)  # the net's bearing from near the kick-off spot
    error = lambda t: np.linalg.norm(np.asarray(tracked_pose(t)[0][:2]) - truth[:2])
    before = error(locked)
    for _ in range(10):
        locked = sight(locked, seen_from(truth, own=True, opponent=True))
    assert error(locked) < 0.5 * before
    assert float(tracked_pose(locked)[0][2]) == pytest.approx(truth[2], abs=0.03)
    wrong = seen_from(truth, opponent=True).at[2, 1:3].set(jnp.array([0.5, -3.0]))  # a false sighting, far off
    np.testing.assert_array_equal(np.asarray(sight(locked, wrong)[:12]), np.asarray(locked[:12]))


def test_a_kickoff_puts_it_back_on_its_spot_and_the_ball_on_the_centre_spot():
    tracker = tracker_kickoff(jnp.array([-1.0, 0.0, 0.0]))
    pose, locked = tracked_pose(tracker)
    np.testing.assert_array_equal(np.asarray(pose), [-1.0, 0.0, 0.0])
    assert bool(locked)
    features = tracked_features(tracker, jnp.zeros(14), PARTS["ball"], PARTS["own_goal"], PARTS["opponent_goal"],
                                OWN_XY, OPPONENT_XY)
    np.testing.assert_allclose(np.asarray(features[:2]), [1.0, 0.0], atol=1e-6)  # 1 m ahead


def test_a_ball_seen_before_it_locks_on_is_forgotten_when_it_does():
    truth = np.array([-1.0, 0.0, 0.8])
    start = sight(tracker_start(jnp.array([-1.0, 0.0, 0.0])), seen_from(truth, ball=np.array([0.0, 0.5])))
    locked = sight(start, seen_from(truth, opponent=True))
    assert bool(tracked_pose(locked)[1])
    features = tracked_features(locked, jnp.full(14, 7.0), PARTS["ball"], PARTS["own_goal"], PARTS["opponent_goal"],
                                OWN_XY, OPPONENT_XY)
    np.testing.assert_array_equal(np.asarray(features[:3]), [7.0, 7.0, 7.0])  # its own estimate


def test_its_features_are_the_games_for_its_pose_and_the_ball_is_kept_then_forgotten():
    truth = np.array([0.4, -0.6, 2.0])
    tracker = tracker_kickoff(jnp.asarray(truth, jnp.float32))
    estimate = jnp.arange(14, dtype=jnp.float32)  # the player's own: ball (3), ball velocity (3), goals, opponent
    features = lambda t, *memory_s: np.asarray(tracked_features(t, estimate, PARTS["ball"], PARTS["own_goal"],
                                                                PARTS["opponent_goal"], OWN_XY, OPPONENT_XY,
                                                                *memory_s))
    ego = lambda xy: np.asarray(yaw_rotate(jnp.float32(truth[2]), jnp.asarray(xy - truth[:2], jnp.float32)))
    unseen = features(tracker)
    np.testing.assert_allclose(unseen[6:8], ego(OWN_XY), atol=1e-5)  # as game_features: goal - torso, heading frame
    np.testing.assert_allclose(unseen[8:10], ego(OPPONENT_XY), atol=1e-5)
    np.testing.assert_allclose(unseen[:2], ego(np.zeros(2)), atol=1e-5)  # at a kick-off: on the centre spot
    np.testing.assert_array_equal(unseen[2:6], np.asarray(estimate[2:6]))  # its height and velocity: its own
    np.testing.assert_array_equal(unseen[10:], np.asarray(estimate[10:]))
    ball = np.array([1.0, -0.2])
    tracker = sight(tracker, seen_from(truth, ball=ball))
    np.testing.assert_allclose(features(tracker)[:2], ego(ball), atol=1e-5)
    assert features(tracker)[2] == estimate[2]  # the height stays its own estimate
    steps = int(BALL_MEMORY_S / 0.025)
    for _ in range(steps):  # standing still, not seeing the ball: kept where it was seen ...
        tracker = tracker_step(tracker, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), 0.025)
    np.testing.assert_allclose(features(tracker)[:2], ego(ball), atol=1e-4)
    tracker = tracker_step(tracker, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), 0.025)
    np.testing.assert_array_equal(features(tracker)[:2], np.asarray(estimate[:2]))  # ... then forgotten
    np.testing.assert_allclose(features(tracker, 2 * BALL_MEMORY_S)[:2], ego(ball), atol=1e-4)  # unless kept longer


def test_with_ball_motion_it_follows_a_rolling_ball_and_rolls_it_on_out_of_view():
    """A ball rolling at 0.8 m/s, slowing by BALL_DECEL, sighted every period with 3 cm errors for 1 s, then out of
    view for 0.5 s: the filter's velocity and its ball rolled on are close to the truth, nearer than the ball held
    where it was last seen; without ball_motion the ball is held (as before)."""
    from legged.soccer.vision.tracker import BALL_DECEL

    truth, dt = np.array([-1.0, 0.2, 0.3]), 0.025
    noise = np.random.default_rng(0).normal(0.0, 0.03, (60, 2))
    ball, vel = np.zeros(2), np.array([0.0, 0.8])  # kicked off the centre spot
    moving, held = tracker_kickoff(jnp.asarray(truth, jnp.float32)), tracker_kickoff(jnp.asarray(truth, jnp.float32))
    estimate = jnp.zeros(14)
    features = lambda t, motion: np.asarray(tracked_features(t, estimate, PARTS["ball"], PARTS["own_goal"],
                                                             PARTS["opponent_goal"], OWN_XY, OPPONENT_XY,
                                                             ball_vel=slice(3, 6) if motion else None))
    ego = lambda xy: np.asarray(yaw_rotate(jnp.float32(truth[2]), jnp.asarray(xy, jnp.float32)))
    for k in range(60):
        seen = seen_from(truth, ball=ball + noise[k]) if k < 40 else seen_from(truth)
        moving = tracker_sight(tracker_step(moving, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), dt, True),
                               seen, NETS, GOAL_WIDTH, True)
        held = sight(tracker_step(held, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), dt), seen)
        if k == 39:
            np.testing.assert_allclose(features(moving, True)[3:5], ego(vel), atol=0.1)  # its velocity, 1 s on
            last_seen = ball + noise[k]
        ball, vel = ball + vel * dt, vel * (1 - BALL_DECEL * dt / np.linalg.norm(vel))
    np.testing.assert_allclose(features(held, False)[:2], ego(last_seen - truth[:2]), atol=1e-4)  # held
    rolled_on = np.linalg.norm(features(moving, True)[:2] - ego(ball - truth[:2]))
    assert rolled_on < 0.04 and rolled_on < np.linalg.norm(last_seen - ball) / 2
    np.testing.assert_array_equal(features(moving, False)[3:6], 0.0)  # velocity the player's own without ball_vel
    with pytest.raises(ValueError, match="vision_ball_velocity .* needs vision_tracker"):
        from legged.soccer.config import SoccerConfig

        SoccerConfig(vision=True, vision_ball_velocity=True)


def test_its_inputs_are_what_it_knows_and_zeros_elsewhere():
    truth = np.array([-0.8, 0.3, -0.5])
    inputs = lambda t: np.asarray(tracker_inputs(t, OWN_XY, OPPONENT_XY))
    ego = lambda xy: np.asarray(yaw_rotate(jnp.float32(truth[2]), jnp.asarray(xy - truth[:2], jnp.float32)))
    start = tracker_start(jnp.asarray(truth, jnp.float32))
    assert inputs(start).shape == (TRACKER_INPUT_SIZE,)
    np.testing.assert_array_equal(inputs(sight(start, seen_from(truth, ball=np.array([0.5, 0.0])))), 0.0)  # not locked
    known = tracker_kickoff(jnp.asarray(truth, jnp.float32))  # on its spot, the ball on the centre spot
    np.testing.assert_allclose(inputs(known), [1.0, *ego(OWN_XY), *ego(OPPONENT_XY), 1.0, *ego(np.zeros(2))],
                               atol=1e-5)
    for _ in range(int(BALL_MEMORY_S / 0.025) + 1):  # the ball unseen for longer than it is kept
        known = tracker_step(known, jnp.zeros(2), jnp.float32(0.0), jnp.bool_(False), 0.025)
    np.testing.assert_allclose(inputs(known), [1.0, *ego(OWN_XY), *ego(OPPONENT_XY), 0.0, 0.0, 0.0], atol=1e-4)


def test_in_a_game_it_tracks_the_players_pose_on_the_pitch():
    """A vision player (the shipped walker, the placo command from its estimate) in two 1v1 games of native
    physics: once locked on, the tracked pose agrees with MuJoCo's, and the goals it steers by are the true ones."""
    import dataclasses

    import jax

    from legged.envs.vector import VectorEnv
    from legged.soccer.learner import LearnerView
    from legged.soccer.observe import PROPRIO_SIZE, read_bodies
    from legged.envs.config import NoiseConfig
    from legged.soccer.randomize import SoccerRandomization
    from legged.tasks import make
    from policies.policy_io import load_walker

    config = make("soccer-1v1-vision").config  # the students' lens (70 degrees): it sees the goals more often
    config = dataclasses.replace(config, vision_tracker=True, vision_tracker_inputs=True,
                                 scene=dataclasses.replace(config.scene, head_camera_fovy_deg=70.0),
                                 randomization=SoccerRandomization(), noise=NoiseConfig())  # no sensor errors
    view = LearnerView(make("soccer-1v1-vision", config),
                       walker=load_walker("assets/policies/op3-walker-v1", prior="placo"))
    vector = VectorEnv.of(view, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(3))
    estimate = jnp.zeros((2, view.action_size)).at[:, 4].set(1.0)  # no corrections; "the ball 1 m left": it turns
    used = jax.jit(jax.vmap(view.used_estimate))
    for _ in range(200):  # 5 s
        batch, _ = vector.step(batch, estimate)
    state = batch.state
    pose, locked = jax.vmap(tracked_pose)(state.info["tracker"])
    assert np.all(np.asarray(locked))
    for k in range(2):
        bodies = read_bodies(view.game.layout, state.pipeline_state.qpos[k], state.pipeline_state.qvel[k])
        assert np.linalg.norm(np.asarray(pose[k, :2] - bodies.pos[0, :2])) < 0.4
        assert abs(float(jnp.angle(jnp.exp(1j * (pose[k, 2] - bodies.yaw[0]))))) < 0.15
    steered = np.asarray(used(state, estimate))
    truth = np.asarray(state.info["game_obs"]["features"][:, 0, PROPRIO_SIZE:])
    assert np.abs(steered[:, 6:10] - truth[:, 6:10]).max() < 0.6  # both goals, in its heading frame
    assert view.observation_layout()["state"][-1] == ("tracker", TRACKER_INPUT_SIZE)  # its network reads them too
    inputs = np.asarray(state.obs["state"][:, -TRACKER_INPUT_SIZE:])
    np.testing.assert_allclose(inputs, np.asarray(jax.vmap(lambda t: tracker_inputs(t, *view._goal_xy))(
        state.info["tracker"])), atol=1e-5)
    assert np.all(inputs[:, 0] == 1.0) and np.abs(inputs[:, 1:5] - truth[:, 6:10]).max() < 0.6


def test_a_tracker_needs_a_vision_player_that_estimates_the_game():
    import dataclasses

    from legged.soccer.learner import LearnerView
    from legged.tasks import make
    from policies.policy_io import load_walker

    with pytest.raises(ValueError, match="vision_tracker .* needs vision"):
        make("soccer-1v1", vision_tracker=True)
    with pytest.raises(ValueError, match="vision_tracker_inputs .* needs vision_tracker"):
        make("soccer-1v1-vision", vision_tracker_inputs=True)
    with pytest.raises(ValueError, match="vision_ball_memory_s must be > 0"):
        make("soccer-1v1-vision", vision_tracker=True, vision_ball_memory_s=0.0)
    walker = dataclasses.replace(load_walker("assets/policies/op3-walker-v1", prior="placo"), prior=None)
    with pytest.raises(ValueError, match="needs a player that estimates the game"):
        LearnerView(make("soccer-1v1-vision", vision_tracker=True), walker=walker)


def test_a_drill_refuses_a_player_that_reads_its_tracker(tmp_path):
    import dataclasses

    import yaml

    from policies.config import TrainConfig, to_dict
    from policies.soccer.drill import run_drill

    config = TrainConfig(task="soccer-1v1-vision").resolved()
    env = dataclasses.replace(config.env, vision_tracker=True, vision_tracker_inputs=True)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(to_dict(dataclasses.replace(config, env=env))))
    with pytest.raises(ValueError, match="drills play without the tracker"):
        run_drill("empty-goal", str(tmp_path), episodes=1, seed=0, progress=False)


def test_the_ball_decelerates_in_the_games_physics_as_the_filter_assumes():
    """BALL_DECEL against MuJoCo: a ball rolled across the default pitch slows at about that rate once it rolls."""
    import mujoco

    from legged.soccer.env import SoccerEnv
    from legged.soccer.config import SoccerConfig
    from legged.soccer.vision.tracker import BALL_DECEL

    env = SoccerEnv(SoccerConfig())
    model = env.mj_model
    data = mujoco.MjData(model)
    q, v = env.layout.ball_qpos_adr, env.layout.ball_dof_adr
    data.qpos[:] = np.asarray(env._qpos0)  # the robots on their kick-off spots
    data.qpos[q:q + 3], data.qvel[v] = [0.0, 1.0, env.config.scene.ball_radius], 1.2  # away from the robots
    every = round(0.025 / model.opt.timestep)
    speeds = []
    for k in range(round(2.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        if k % every == 0:
            speeds.append(np.linalg.norm(data.qvel[v:v + 2]))
    speeds, times = np.array(speeds), 0.025 * np.arange(len(speeds))
    rolling = (times > 0.1) & (speeds > 0.15)  # after the slide, before it stops
    assert rolling.sum() > 20
    assert abs(-np.polyfit(times[rolling], speeds[rolling], 1)[0] - BALL_DECEL) < 0.1
