"""The multi-agent soccer environments: shapes, the laws of the game, observations, opponents as data."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from legged.envs.config import NoiseConfig
from legged.envs.native import NativeEnvs
from legged.envs.physics import PhysicsView, view_of_mjx
from legged.tasks import make
from legged.soccer import observe
from legged.soccer.opponents import OpponentNet, network_opponent, opponent_actions, scripted_opponent
from legged.soccer.pitch import kickoff_poses
from legged.soccer.randomize import SoccerRandomization


@pytest.fixture(scope="module")
def game():
    """soccer-1v1 with a jitted batched reset and step and an unbatched transition."""
    env = make("soccer-1v1", randomization=SoccerRandomization(), noise=NoiseConfig())  # the nominal game

    class Game:
        pass

    g = Game()
    g.env, g.reset, g.step = env, jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step))
    g.transition = jax.jit(env.transition)
    g.one = jax.tree_util.tree_map(lambda x: x[0], g.reset(jax.random.split(jax.random.PRNGKey(0), 2)))
    return g


def _with_ball(g, xyz, state=None):
    """A state whose physics has the ball moved to xyz (and the transition's output from it)."""
    state = g.one if state is None else state
    adr = g.env.layout.ball_qpos_adr
    data = _view(state.pipeline_state)
    data = data.replace(qpos=data.qpos.at[adr:adr + 3].set(jnp.asarray(xyz)))
    return g.transition(state, data, jnp.zeros((g.env.n_agents, g.env.action_size)))


def _view(data):
    """What the transition reads of an MJX data (or a view, as it is)."""
    return data if isinstance(data, PhysicsView) else view_of_mjx(data, jnp.zeros(0), False)


def test_per_agent_shapes_and_no_nan_under_random_actions(game):
    env = game.env
    state = game.reset(jax.random.split(jax.random.PRNGKey(1), 2))
    assert state.obs["state"].shape == (2, 2, env.policy_state_size) == (2, 2, 80)
    assert state.obs["privileged_state"].shape == (2, 2, 97)
    assert state.reward.shape == (2, 2)
    key = jax.random.PRNGKey(2)
    for _ in range(15):
        key, k = jax.random.split(key)
        state = game.step(state, jax.random.uniform(k, (2, 2, env.action_size), minval=-1.0, maxval=1.0))
        for leaf in jax.tree_util.tree_leaves((state.obs, state.reward, state.metrics)):
            assert bool(jnp.all(jnp.isfinite(leaf)))
    terms = [k for k in state.metrics if k.startswith("reward/")]
    assert {"reward/goal", "reward/vel_to_ball", "reward/ball_vel_to_goal", "reward/upright", "reward/fall",
            "reward/torques", "reward/action_rate"} <= set(terms)
    assert all(state.metrics[k].shape == (2, 2) for k in terms)
    assert np.allclose(sum(state.metrics[k] for k in terms), state.reward, atol=1e-5)
    assert float(state.metrics["diverged"].max()) == 0.0


def test_mjx_game_physics_matches_native_mujoco(game):
    """Two control steps of the 1v1 game (10 physics steps, every contact pair type) against mj_step."""
    env = game.env
    state = game.reset(jax.random.split(jax.random.PRNGKey(7), 2))
    data = mujoco.MjData(env.mj_model)
    data.qpos[:] = np.asarray(state.pipeline_state.qpos[0])
    data.ctrl[:] = env.layout.default_ctrl(env.mj_model)
    mujoco.mj_forward(env.mj_model, data)
    for _ in range(2):
        state = game.step(state, jnp.zeros((2, env.n_agents, env.action_size)))
        for _ in range(env.n_substeps):
            mujoco.mj_step(env.mj_model, data)
    assert np.abs(np.asarray(state.pipeline_state.qpos[0]) - data.qpos).max() < 1e-3
    assert np.abs(np.asarray(state.pipeline_state.qvel[0]) - data.qvel).max() < 2e-2


def test_a_goal_scores_for_one_team_and_restarts_from_kickoff(game):
    env, scene = game.env, game.env.config.scene
    behind = scene.field_length / 2 + scene.ball_radius + 0.05
    home_goal = _with_ball(game, [behind, 0.1, scene.ball_radius])  # into the away goal at +x: home scores
    assert np.allclose(home_goal.metrics["reward/goal"], [1.0, -1.0])
    assert np.array_equal(home_goal.info["score"], [1, 0]) and float(home_goal.done) == 0.0
    lay = env.layout
    qpos = np.asarray(home_goal.pipeline_state.qpos)
    assert np.allclose(qpos[lay.ball_qpos_adr:lay.ball_qpos_adr + 3], [0.0, 0.0, scene.ball_radius])
    assert np.allclose(qpos[lay.root_qpos_adr[:, None] + np.arange(2)], kickoff_poses(scene)[:, :2], atol=1e-6)
    assert np.allclose(home_goal.pipeline_state.qvel, 0.0)
    assert bool(home_goal.info["teleported"])  # the engines load the moved bodies
    away_goal = _with_ball(game, [-behind, 0.0, scene.ball_radius])
    assert np.allclose(away_goal.metrics["reward/goal"], [-1.0, 1.0])
    assert np.array_equal(away_goal.info["score"], [0, 1])


def test_a_ball_out_of_play_is_put_back_inside_the_line(game):
    scene, inset = game.env.config.scene, game.env.config.restart_inset
    adr = game.env.layout.ball_qpos_adr
    over_touch = _with_ball(game, [1.0, scene.field_width / 2 + 0.2, scene.ball_radius])
    wide_of_goal = _with_ball(game, [scene.field_length / 2 + 0.2, 1.0, scene.ball_radius])
    for state, expected_xy in ((over_touch, [1.0, scene.field_width / 2 - inset]),
                               (wide_of_goal, [scene.field_length / 2 - inset, 1.0])):
        assert float(state.metrics["out_of_play"]) == 1.0
        assert np.allclose(state.metrics["reward/goal"], 0.0)
        assert np.allclose(state.pipeline_state.qpos[adr:adr + 2], expected_xy, atol=1e-6)
    in_play = _with_ball(game, [1.0, 0.5, scene.ball_radius])
    assert float(in_play.metrics["out_of_play"]) == 0.0


def test_the_learners_fall_ends_the_episode_and_the_time_limit_truncates(game):
    env = game.env
    adr = env.layout.root_qpos_adr[1]
    data = _view(game.one.pipeline_state)
    opponent_down = game.transition(game.one, data.replace(qpos=data.qpos.at[adr + 2].set(0.1)),
                                    jnp.zeros((2, env.action_size)))
    assert np.array_equal(opponent_down.metrics["fell"], [0.0, 1.0]) and float(opponent_down.done) == 0.0
    assert np.allclose(opponent_down.metrics["reward/fall"], [0.0, env.config.rewards.fall])
    again = game.transition(opponent_down, opponent_down.pipeline_state, jnp.zeros((2, env.action_size)))
    assert np.allclose(again.metrics["reward/fall"], 0.0)  # the fall penalty is paid once
    learner = env.layout.root_qpos_adr[0]
    learner_down = game.transition(game.one, data.replace(qpos=data.qpos.at[learner + 2].set(0.1)),
                                   jnp.zeros((2, env.action_size)))
    assert float(learner_down.done) == 1.0 and float(learner_down.info["truncation"]) == 0.0
    last = game.one.replace(info={**game.one.info, "step": jnp.int32(env.config.episode_steps - 1)})
    timed_out = game.transition(last, data, jnp.zeros((2, env.action_size)))
    assert float(timed_out.done) == 1.0 and float(timed_out.info["truncation"]) == 1.0


def test_egocentric_observations_are_the_same_for_mirrored_players(game):
    """At a kick-off with the ball on the spot the two players see mirror images: identical features."""
    env = game.env
    lay = env.layout
    qpos = env._qpos0
    b = observe.read_bodies(lay, qpos, jnp.zeros(env.mj_model.nv))
    features = np.asarray(observe.game_features(b, lay.team, env._goals, observe.others_of(lay)))
    assert np.allclose(features[0], features[1], atol=1e-5)
    assert np.allclose(features[0][:3], [1.0, 0.0, env.config.scene.ball_radius - env.robot.standing_height], atol=1e-5)
    assert np.allclose(features[0][6:10], [-1.5, 0.0, 3.5, 0.0], atol=1e-5)  # own goal behind, opponent's ahead
    heading = np.asarray(observe.attack_direction(b, lay.team, env._goals))  # a vision player's, vision_heading
    assert np.allclose(heading, [[1.0, 0.0], [1.0, 0.0]], atol=1e-5)  # both face the way they attack
    quarter = b.rot.at[0].set(b.rot[0] @ jnp.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    turned = np.asarray(observe.attack_direction(dataclasses.replace(b, rot=quarter), lay.team, env._goals))
    assert np.allclose(turned[0], [0.0, -1.0], atol=1e-5)  # turned 90 degrees left: the attack is to its right


def test_others_come_teammates_first():
    class Layout:
        n_agents, team = 4, np.array([0, 0, 1, 1])
    assert observe.others_of(Layout()).tolist() == [[1, 2, 3], [0, 2, 3], [3, 0, 1], [2, 0, 1]]


def test_the_named_layout_covers_the_observations_and_maps_1v1_onto_2v2():
    """A 1v1 player's ball, goals and opponent reach a 2v2 player's (warm start); the teammate and the second
    opponent are new inputs."""
    from legged.soccer.learner import LearnerView
    from policies.warm_start import element_names, input_map

    layouts = {}
    for task, extra in (("soccer-1v1", {}), ("soccer-2v2", {}), ("soccer-1v1-vision", {}),
                        ("soccer-1v1-vision", {"vision_heading": True}),
                        ("soccer-1v1-vision", {"vision_heading": True, "vision_sightings": True})):
        env = LearnerView(make(task, **extra))
        layouts[task] = layout = env.observation_layout()
        dims = env.observation_dims()
        assert {k: sum(n for _, n in v) for k, v in layout.items()} == {k: dims[k] for k in layout}, task
        assert (("attack_direction", 2) in layout["state"]) == bool(extra), task
        sightings = [("ball_sighting", 4), ("own_goal_sighting", 4), ("opponent_goal_sighting", 4)]
        assert (layout["state"][-3:] == sightings) == ("vision_sightings" in extra), task
    names = {t: element_names(layouts[t]["state"]) for t in ("soccer-1v1", "soccer-2v2")}
    mapping = input_map(names["soccer-1v1"], names["soccer-2v2"])
    for i, name in enumerate(names["soccer-2v2"]):
        expected = -1 if name.startswith(("teammate0", "opponent1")) else names["soccer-1v1"].index(name)
        assert mapping[i] == expected, name


def test_opponents_are_data_and_the_script_watches_the_ball():
    obs = jnp.zeros((3, 80)).at[:, observe.PROPRIO_SIZE:observe.PROPRIO_SIZE + 3].set(jnp.array([1.0, 1.0, 0.0]))
    scripted = scripted_opponent(80, 20, (8,))
    actions = opponent_actions(OpponentNet(), scripted, obs, 0.3)
    assert np.allclose(actions[:, 0], np.pi / 4 / 0.3, atol=1e-5)  # head pans 45 degrees toward the ball
    assert np.all(actions[:, 1] < 0) and np.allclose(actions[:, 2:], 0.0)  # looks down, stands still
    rng = np.random.default_rng(0)
    net = network_opponent(np.zeros(80), np.ones(80), [(rng.normal(size=(80, 8)), np.zeros(8)),
                                                       (rng.normal(size=(8, 20)), np.zeros(20))])
    assert jax.tree_util.tree_structure(net) == jax.tree_util.tree_structure(scripted)
    fn = jax.jit(lambda o, x: opponent_actions(OpponentNet(), o, x, 0.3))
    a_script, a_net = fn(scripted, obs), fn(net, obs)
    assert fn._cache_size() == 1  # swapping the opponent changed data, not the program
    assert np.allclose(a_script, actions) and not np.allclose(a_net, a_script)



def test_soccer_config_is_checked():
    from legged.soccer.config import SoccerConfig

    with pytest.raises(ValueError, match="end_on_fall must be"):
        SoccerConfig(end_on_fall="sometimes")
    with pytest.raises(ValueError, match="vision_heading .* needs vision"):
        SoccerConfig(vision_heading=True)
    with pytest.raises(ValueError, match="vision_sightings .* needs vision"):
        SoccerConfig(vision_sightings=True)
    with pytest.raises(ValueError, match="vision_sighted_ball .* needs vision_sightings"):
        SoccerConfig(vision=True, vision_sighted_ball=True)
    with pytest.raises(ValueError, match="randomization.ball_mass must be a range"):
        SoccerConfig(randomization=dataclasses.replace(SoccerConfig().randomization, ball_mass=(0.3, 0.1)))


def test_soccer_randomisation_is_one_function_for_both_engines():
    from legged.soccer.env import SoccerEnv
    from legged.soccer.randomize import OP3_RANDOMIZATION, randomized_fields, sample
    from legged.soccer.config import SoccerConfig

    env = SoccerEnv(SoccerConfig(randomization=OP3_RANDOMIZATION))
    m, where, ball = env.mj_model, env._dynamics, env.layout.ball_body
    assert where.ball_pairs.sum() >= 3 and where.floor_pairs.sum() >= 2 * 4  # 2 robots x (2 feet, torso, head)
    assert not where.robot_bodies[ball] and not where.robot_bodies[0]
    draws = [sample(jax.random.PRNGKey(k), env.config.randomization, m, 0.2, 2, 20, env.n_substeps) for k in range(3)]
    batch = jax.tree_util.tree_map(lambda *x: np.stack(x), *draws)
    base = {k: np.array(getattr(m, k)) for k in env._base_fields}
    rows = randomized_fields(base, batch, where, xp=np)                       # native: rows of a batch
    assert {"dof_damping", "dof_armature", "dof_frictionloss", "pair_solref"} <= set(rows)
    for k, dr in enumerate(draws):                                            # MJX: one episode under vmap
        one = randomized_fields({n: jnp.asarray(v) for n, v in base.items()}, dr, where)
        assert set(one) == set(rows)
        for name in one:
            np.testing.assert_allclose(np.asarray(one[name]), rows[name][k], rtol=1e-6)
    assert np.allclose(rows["body_mass"][:, ball], [float(d["ball_mass"]) for d in draws])
    assert np.allclose(rows["pair_friction"][:, where.ball_floor_pair, 2], [float(d["rolling"]) for d in draws])
    assert np.ptp(rows["actuator_gainprm"][:, :, 0], axis=0).min() > 0  # each draw its own motors
    assert np.allclose(rows["actuator_biasprm"][:, :, 1], -rows["actuator_gainprm"][:, :, 0])  # still a servo
    static = ~where.robot_bodies & (np.arange(m.nbody) != ball)
    assert np.array_equal(rows["body_mass"][:, static], np.broadcast_to(base["body_mass"][static], (3, static.sum())))
    spawned = env.spawn(jax.random.PRNGKey(4)).info
    fields = env.native_model_fields(jax.tree_util.tree_map(lambda x: np.asarray(x)[None], spawned), np.array([0]))
    np.testing.assert_allclose(fields["body_mass"][0], np.asarray(env.mjx_model_for(spawned).body_mass), rtol=1e-6)
    from legged.soccer.drills import DrillConfig, DrillEnv
    from legged.soccer.learner import LearnerView

    for view in (LearnerView(env), DrillEnv(DrillConfig(), env.config)):  # the single-agent views randomise too
        info = view.spawn(jax.random.PRNGKey(4)).info
        assert not np.allclose(np.asarray(view.mjx_model_for(info).body_mass), m.body_mass)
        rows = view.native_model_fields(jax.tree_util.tree_map(lambda x: np.asarray(x)[None], info), np.array([0]))
        np.testing.assert_allclose(rows["actuator_gainprm"][0], np.asarray(view.mjx_model_for(info).actuator_gainprm))


def test_a_kickoff_starts_every_robots_walker_over(game):
    """After a goal the robots stand at their kick-off poses: mid-stride clocks and filters would not match."""
    scene = game.env.config.scene
    info = dict(game.one.info, walker_state=jnp.ones_like(game.one.info["walker_state"]))
    mid_game = game.one.replace(info=info)
    behind = scene.field_length / 2 + scene.ball_radius + 0.05
    after_goal = _with_ball(game, [behind, 0.1, scene.ball_radius], mid_game)
    assert np.array_equal(after_goal.info["score"], [1, 0])
    assert np.allclose(after_goal.info["walker_state"], 0.0)
    play_on = _with_ball(game, [0.5, 0.1, scene.ball_radius], mid_game)
    assert np.allclose(play_on.info["walker_state"], 1.0)


def test_approach_offset_aims_vel_to_ball_behind_the_ball():
    """A home robot beside the ball (attacking +x) walking toward the goal passes the ball: no reward for it
    at offset 0 (it moves across the bearing to the ball), a penalty with an offset (it leaves the spot behind
    the ball); walking back toward that spot is rewarded; lined up behind the ball it walks into it."""
    from legged.soccer.config import SoccerSceneConfig
    from legged.soccer.pitch import goal_centres
    from legged.soccer.rewards import reward_terms
    from legged.soccer.rules import BallCall
    from legged.soccer.config import SoccerRewards

    zeros = jnp.zeros((2, 20))

    def vel_to_ball(offset: float, vx: float, at=(1.0, 0.3)) -> float:
        b = observe.Bodies(pos=jnp.array([[at[0], at[1], 0.24], [-2.0, 0.0, 0.24]]),
                           rot=jnp.tile(jnp.eye(3), (2, 1, 1)), vel=jnp.array([[vx, 0.0, 0.0], [0.0, 0.0, 0.0]]),
                           gyro=jnp.zeros((2, 3)), q=zeros, qd=zeros, ball_pos=jnp.array([1.0, 0.0, 0.07]),
                           ball_vel=jnp.zeros(3))
        no = jnp.array(False)
        terms = reward_terms(SoccerRewards(vel_to_ball=1.0, approach_offset=offset), b, BallCall(no, no, no),
                             np.array([0, 1]), goal_centres(SoccerSceneConfig()), jnp.zeros(2), zeros, zeros, zeros,
                             zeros, jnp.tile(jnp.array([-3.0, 3.0]), (2, 20, 1)), 0.025)
        return float(terms["vel_to_ball"][0])

    assert vel_to_ball(0.0, 0.2) == pytest.approx(0.0, abs=1e-6)
    assert vel_to_ball(0.3, 0.2) == pytest.approx(-0.2 / np.sqrt(2), abs=1e-5)   # spot at (0.7, 0)
    assert vel_to_ball(0.3, -0.2) == pytest.approx(0.2 / np.sqrt(2), abs=1e-5)
    # lined up behind the ball (past the spot at 0.7): walking into the ball is rewarded, as at offset 0
    assert vel_to_ball(0.3, 0.2, at=(0.8, 0.0)) == pytest.approx(0.2, abs=1e-5)
    # at 45 degrees behind the ball the spot sits (1 - cos 45 deg) of the offset behind it
    spot = np.array([1.0 - 0.3 * (1.0 - np.cos(np.pi / 4)), 0.0])
    expected = float(np.dot([0.2, 0.0], spot - [0.6, -0.4]) / np.linalg.norm(spot - [0.6, -0.4]))
    assert vel_to_ball(0.3, 0.2, at=(0.6, -0.4)) == pytest.approx(expected, abs=1e-5)
    with pytest.raises(ValueError, match="approach_offset"):
        make("soccer-1v1", rewards=SoccerRewards(approach_offset=-0.1))


def test_estimate_noise_is_stationary_and_shaped_like_a_tracked_estimate():
    from legged.soccer.vision.estimate_noise import EstimateNoise, blurred, error_size, first_error, next_error

    noise = EstimateNoise(enabled=True, correlation_s=0.5)
    start = first_error(jax.random.PRNGKey(0), 20000, 1)
    error, key = start, jax.random.PRNGKey(1)
    for _ in range(20):  # 0.5 s: the correlation falls to 1/e
        key, k = jax.random.split(key)
        error = next_error(noise, error, k, 0.025)
    assert error.shape == (20000, error_size(1)) == (20000, 11)
    np.testing.assert_allclose(np.asarray(error).std(0), 1.0, atol=0.03)
    correlation = [np.corrcoef(np.asarray(start)[:, i], np.asarray(error)[:, i])[0, 1] for i in range(11)]
    np.testing.assert_allclose(correlation, np.exp(-1.0), atol=0.03)
    # ball 0.3 m ahead, still; goals 2 m behind and 3 m ahead; the opponent 2 m to the left, walking
    game = jnp.asarray([[0.3, 0.0, -0.17, 0.0, 0.0, 0.0, -2.0, 0.0, 3.0, 0.0, 0.0, 2.0, 0.1, 0.0]])
    out = np.asarray(blurred(noise, error[:, None].reshape(20000, 11), jnp.broadcast_to(game, (20000, 14))))
    diff = out - np.asarray(game)
    assert np.all(diff[:, [2, 5]] == 0)  # the ball's height and vertical velocity stay exact
    np.testing.assert_allclose(diff[:, 0:2].std(0), noise.ball + 0.3 * noise.ball_per_m, rtol=0.05)
    np.testing.assert_allclose(diff[:, 3:5].std(0), noise.ball_vel, rtol=0.05)
    np.testing.assert_allclose(diff[:, 10:12].std(0), noise.players + 2.0 * noise.players_per_m, rtol=0.05)
    np.testing.assert_allclose(diff[:, 12:].std(0), noise.player_vel, rtol=0.05)
    # the goals move together: one pose error (their separation keeps its length), the far one more across
    np.testing.assert_allclose(np.linalg.norm(out[:, 8:10] - out[:, 6:8], axis=-1), 5.0, rtol=1e-5)
    assert diff[:, 9].std() > diff[:, 7].std() > noise.pose_xy
    np.testing.assert_allclose(diff[:, 8].std(), noise.pose_xy, rtol=0.1)


def test_estimate_noise_sight_gives_the_ball_seen_held_then_guessed():
    """`estimate_noise.sight`: the ball exact-ish in the head camera's field, held where last seen for
    `memory_s`, then guessed with a larger error; a restart forgets it."""
    from legged.soccer.vision.estimate_noise import (UNSEEN, EstimateNoise, blurred, first_sighting, held_ball,
                                                     in_sight, next_sighting)

    noise = EstimateNoise(enabled=True, sight=True)
    ahead = jnp.asarray([[1.0, 0.0], [-1.0, 0.0], [0.1, 0.0], [5.0, 0.0], [0.5, 0.9], [1.0, 0.5]])
    assert np.asarray(in_sight(noise, ahead)).tolist() == [True, False, False, False, False, True]
    with pytest.raises(ValueError, match="sight_near_m"):
        EstimateNoise(sight_near_m=5.0).validate()
    # two players at the origin: one facing the ball 1 m along +x, one facing away
    pos, yaw, ball = jnp.zeros((2, 2)), jnp.asarray([0.0, np.pi]), jnp.asarray([1.0, 0.0])
    sighting = next_sighting(noise, first_sighting(2), pos, yaw, ball, 0.025, jnp.bool_(False))
    np.testing.assert_allclose(sighting[0], [1.0, 0.0, 0.0])
    assert float(sighting[1, 2]) >= UNSEEN
    # the ball rolls away behind the first: it is held where it was seen, ageing; a restart forgets it
    later = next_sighting(noise, sighting, pos, jnp.asarray([np.pi, np.pi]), jnp.asarray([2.0, 0.0]), 0.5,
                          jnp.bool_(False))
    np.testing.assert_allclose(later[0], [1.0, 0.0, 0.5])
    assert float(next_sighting(noise, sighting, pos, jnp.asarray([np.pi, np.pi]), ball, 0.5, jnp.bool_(True))[0, 2]) \
        >= UNSEEN
    np.testing.assert_allclose(held_ball(later, jnp.asarray([[0.5, 0.0], [0.0, 0.0]]), jnp.asarray([np.pi / 2, 0.0])),
                               [[0.0, -0.5], [0.0, 0.0]], atol=1e-6)  # to the right of one turned left
    # features of 3 players, the ball 0.5 m ahead of each: seen now, held 0.5 s at a stale spot, unseen 2 s
    n = 20000
    game = jnp.broadcast_to(jnp.asarray([0.5, 0.0, -0.17, 0.0, 0.0, 0.0, -2.0, 0.0, 3.0, 0.0, 0.0, 2.0, 0.1, 0.0]),
                            (n, 14))
    error = jax.random.normal(jax.random.PRNGKey(2), (n, 11))
    for where, age, centre, size in (((0.5, 0.0), 0.0, (0.5, 0.0), noise.ball),
                                     ((0.2, 0.3), 0.5, (0.2, 0.3), noise.ball),
                                     ((0.2, 0.3), 2.0, (0.5, 0.0), noise.unseen_ball + 0.5 * noise.ball_per_m)):
        out = np.asarray(blurred(noise, error, game, (jnp.broadcast_to(jnp.asarray(where), (n, 2)), jnp.full(n, age))))
        np.testing.assert_allclose(out[:, 0:2].mean(0), centre, atol=0.01)
        np.testing.assert_allclose(out[:, 0:2].std(0), size, rtol=0.05)
        np.testing.assert_array_equal(out[:, 2:], np.asarray(blurred(EstimateNoise(), error, game))[:, 2:])


def test_estimate_noise_blurs_only_the_deployable_game_features(game):
    from legged.soccer.env import SoccerEnv
    from legged.soccer.vision.estimate_noise import EstimateNoise, blurred, held_ball, in_sight
    from legged.soccer.config import SoccerConfig

    with pytest.raises(ValueError, match="estimate_noise .* vision player"):
        SoccerConfig(vision=True, estimate_noise=EstimateNoise(enabled=True))
    with pytest.raises(ValueError, match="correlation_s positive"):
        SoccerConfig(estimate_noise=EstimateNoise(correlation_s=0.0))
    env = SoccerEnv(SoccerConfig(estimate_noise=EstimateNoise(enabled=True, sight=True)))
    keys = jax.random.split(jax.random.PRNGKey(3), 2)
    # both games in the native engine (what the noise is checked against is the same game's truth, not MJX's):
    # the clean one is the module's soccer-1v1 (SoccerConfig's defaults)
    noisy_game, clean_game = NativeEnvs(env, 2, threads=1), NativeEnvs(game.env, 2, threads=1)
    state, clean = noisy_game.reset(keys), clean_game.reset(keys)
    assert "ball_sighting" not in clean.info  # kept for estimate_noise.sight only
    for _ in range(2):
        zeros = jnp.zeros((2, env.n_agents, env.action_size))
        state, clean = noisy_game.step(state, zeros), clean_game.step(clean, zeros)
    size = env.policy_state_size
    np.testing.assert_allclose(state.obs["privileged_state"], clean.obs["privileged_state"], atol=1e-6)  # same game
    noisy, truth = state.obs["state"], state.obs["privileged_state"][..., :size]
    p = observe.PROPRIO_SIZE
    np.testing.assert_allclose(noisy[..., :p], truth[..., :p], atol=1e-6)
    # every player's last sighting of the ball is kept: seen now (age 0), or aged by steps
    sighting = state.info["ball_sighting"].reshape(4, -1)
    ball, age = truth[..., p:p + 2].reshape(4, 2), np.asarray(sighting[:, 2])
    seen = np.asarray(in_sight(env.config.estimate_noise, ball))
    assert np.all(age[seen] == 0) and np.all(age[~seen] > 0)
    where = lambda q, v: (lambda b: (b.pos[:, :2], b.yaw))(observe.read_bodies(env.layout, q, v))
    pos, yaw = jax.vmap(where)(state.pipeline_state.qpos, state.pipeline_state.qvel)
    held = (held_ball(sighting, pos.reshape(4, 2), yaw.reshape(4)), sighting[:, 2])
    blur = blurred(env.config.estimate_noise, state.info["estimate_error"].reshape(4, -1),
                   truth[..., p:].reshape(4, -1), held)
    np.testing.assert_allclose(noisy[..., p:].reshape(4, -1), blur, atol=1e-5)
    assert float(jnp.abs(noisy[..., p:p + 2] - truth[..., p:p + 2]).min()) > 0  # every player, every game blurred
