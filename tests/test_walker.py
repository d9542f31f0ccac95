"""Soccer players that command a frozen walking skill (legged.soccer.walker)."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.vector import VectorEnv
from legged.soccer.learner import LearnerView
from legged.soccer.observe import PROPRIO_SIZE
from legged.soccer.opponents import OpponentNet, network_opponent
from legged.skills.config import WalkSkillConfig
from legged.soccer.walker import Walker
from legged.tasks import make

WALK = WalkSkillConfig()


def _walker(layers, residual=False) -> Walker:
    from legged.robots.op3 import OP3
    from legged.soccer.placo.gait_table import load_gait_table

    n = layers[0][0].shape[0]
    return Walker(policy=network_opponent(np.zeros(n), np.ones(n), layers), net=OpponentNet("elu"),
                  command_low=WALK.command_low, command_high=WALK.command_high, gait=load_gait_table(),
                  dt=WALK.ctrl_dt, residual=residual, default_pose=tuple(OP3.default_pose),
                  action_scale=OP3.action_scale)


def _walk_state(env, steps: int):
    """A batch of 2 op3-walk episodes `steps` control steps in (zero actions), with their walker states."""
    vector = VectorEnv.of(env, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(3))
    for _ in range(steps):
        batch, _ = vector.step(batch, jnp.zeros((2, env.action_size)))
    info = batch.state.info
    return batch, jnp.concatenate([info["gait_phase"][:, None], info["gait_command"], jnp.zeros((2, 3))], axis=1)


def _action_of(command):
    """The commanding action in [-1, 1] of a velocity command in the walk skill's range."""
    low, high = np.asarray(WALK.command_low), np.asarray(WALK.command_high)
    return 2.0 * (np.asarray(command) - low) / (high - low) - 1.0


def test_the_walker_reads_what_the_walk_skill_observes():
    """A walker whose network is the identity hands back its input: the walk skill's `state`, entry for entry."""
    env = make("op3-walk", residual=False)
    batch, walker_state = _walk_state(env, 7)  # some steps on: a non-zero gait clock
    state = np.asarray(batch.state.obs["state"])
    command = np.asarray(jax.vmap(env.command)(batch.state.info))
    identity = _walker([(np.eye(state.shape[1], dtype=np.float32), np.zeros(state.shape[1], np.float32))])
    rebuilt = identity.actions(jnp.asarray(state[:, :PROPRIO_SIZE]), jnp.asarray(_action_of(command)), walker_state)
    np.testing.assert_allclose(np.asarray(rebuilt), state, atol=1e-5)
    np.testing.assert_allclose(np.asarray(identity.command(jnp.array([-1.0, 0.0, 1.0]))),
                               [WALK.command_low[0], 0.0, WALK.command_high[2]], atol=1e-6)


def test_a_residual_walker_adds_the_reference_and_keeps_the_skills_clock():
    """A residual walker with a zero network plays what the residual walk skill plays for a zero action, and
    its state steps as the skill's gait clock and filtered command do."""
    env = make("op3-walk")
    assert env.config.residual
    batch, walker_state = _walk_state(env, 30)
    info = batch.state.info
    zero = _walker([(np.zeros((PROPRIO_SIZE + 8, 20), np.float32), np.zeros(20, np.float32))], residual=True)
    action = jnp.asarray(_action_of(np.asarray(jax.vmap(env.command)(info))))
    played = jax.vmap(lambda s: env.learner_actions(s, jnp.zeros(20))[0])(batch.state)
    walked = zero.actions(batch.state.obs["state"][:, :PROPRIO_SIZE], action, walker_state)
    np.testing.assert_allclose(np.asarray(walked), np.asarray(played), atol=1e-5)
    assert float(jnp.abs(played).max()) > 0.1  # the reference moves the legs
    advanced = jax.vmap(env._advance)(info)
    expected = jnp.concatenate([advanced["gait_phase"][:, None], advanced["gait_command"], jnp.zeros((2, 3))], axis=1)
    proprio = batch.state.obs["state"][:, :PROPRIO_SIZE]
    np.testing.assert_allclose(np.asarray(zero.step(walker_state, action, proprio)), np.asarray(expected), atol=1e-5)


def test_a_commanding_learner_and_its_opponents_walk_through_the_walker():
    """A linear walker that copies the forward command into the first joint: the learner's 3 actions reach its
    joints through it, a network opponent's too, and every robot's gait clock runs."""
    size = PROPRIO_SIZE + 8
    w = np.zeros((size, 20), np.float32)
    w[PROPRIO_SIZE, 0] = 1.0                                   # joint 0 <- commanded vx
    walker = _walker([(w, np.zeros(20, np.float32))])
    view = LearnerView(make("soccer-1v1"), walker=walker)
    assert view.action_size == 3
    features = view.game.policy_state_size
    opponent = network_opponent(np.zeros(features), np.ones(features),
                                [(np.zeros((features, 3), np.float32), np.array([1.0, 0.0, 0.0], np.float32))])
    vector = VectorEnv.of(view, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(0))
    batch, _ = vector.step(batch, jnp.asarray([[-1.0, 0.3, 0.0], [0.5, 0.0, 0.0]]), opponent)
    joints = np.asarray(batch.state.info["last_action"])[:, :, 0]  # [env, robot] joint 0's action
    vx_low, vx_high = WALK.command_low[0], WALK.command_high[0]
    np.testing.assert_allclose(joints[:, 0], [vx_low, vx_low + 0.75 * (vx_high - vx_low)], atol=1e-6)
    np.testing.assert_allclose(joints[:, 1], vx_high, atol=1e-6)  # the opponent commands vx = +1
    phase = np.asarray(batch.state.info["walker_state"])[:, :, 0]
    np.testing.assert_allclose(phase, view.dt / float(walker.gait.period), atol=1e-6)  # every robot's clock runs


def test_with_the_placo_prior_actions_correct_the_placo_players_command():
    """A walker that copies the command into joints 0-2: with zero actions the learner and a network opponent
    walk the placo player's command for their own game features; an action adds to it, in action units."""
    from legged.soccer.placo.player import load_tables, request_from_features
    from policies.config import ConfigError, TrainConfig
    from policies.soccer.config import SoccerTrainConfig

    size = PROPRIO_SIZE + 8
    w = np.zeros((size, 20), np.float32)
    w[PROPRIO_SIZE:PROPRIO_SIZE + 3, :3] = np.eye(3)
    walker = dataclasses.replace(_walker([(w, np.zeros(20, np.float32))]), prior=load_tables())
    view = LearnerView(make("soccer-1v1"), walker=walker)
    features = view.game.policy_state_size
    opponent = network_opponent(np.zeros(features), np.ones(features),
                                [(np.zeros((features, 3), np.float32), np.zeros(3, np.float32))])
    vector = VectorEnv.of(view, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(4))
    seen = np.asarray(batch.state.info["game_obs"]["privileged_state"])[:, :, :features]  # [env, robot, features]
    batch, _ = vector.step(batch, jnp.asarray([[0.0, 0.0, 0.0], [0.0, 0.0, 0.5]]), opponent)
    tables = load_tables()
    asked = np.asarray(jax.vmap(jax.vmap(lambda f: request_from_features(tables, f)[0]))(jnp.asarray(seen)))
    expected = np.clip(asked, WALK.command_low, WALK.command_high)
    expected[1, 0, 2] = min(expected[1, 0, 2] + 0.25 * (WALK.command_high[2] - WALK.command_low[2]),
                            WALK.command_high[2])
    assert np.abs(asked[:, :, 2]).max() > 0.05  # the script does ask something of each robot
    np.testing.assert_allclose(np.asarray(batch.state.info["last_action"])[:, :, :3], expected, atol=1e-5)
    estimating = LearnerView(make("soccer-1v1-vision"), walker=walker)  # the prior from its estimate of the game
    assert estimating.estimates_world and estimating.action_size == 3 + 14
    labelled = VectorEnv.of(LearnerView(make("soccer-1v1-vision"), walker=walker, teacher_prior=True), 1, "native", 1)
    state = labelled.reset(jax.random.PRNGKey(4)).state
    obs = state.obs  # its teacher's labels are clipped by the true command
    np.testing.assert_allclose(np.asarray(obs["command_prior"]),
                               np.asarray(walker.prior_actions(obs["features"], tables)), atol=1e-6)
    state = jax.tree.map(lambda x: x[0], state)  # its estimate's errors: every part, and the ball only when near
    for ball_xy, near in (((0.5, -0.6), 1.0), ((0.9, 0.5), 0.0)):
        truth = state.info["game_obs"]["features"].at[0, PROPRIO_SIZE:PROPRIO_SIZE + 2].set(jnp.asarray(ball_xy))
        placed = state.replace(info={**state.info, "game_obs": {**state.info["game_obs"], "features": truth}})
        action = jnp.concatenate([jnp.zeros(3), truth[0, PROPRIO_SIZE:]]).at[3:5].add(jnp.asarray([0.3, -0.4]))
        sq, steps = estimating._estimate_sq(placed, action)
        np.testing.assert_allclose(np.asarray(sq), [0.25, 0.0, 0.0, 0.0, 0.25 * near], atol=1e-6)
        np.testing.assert_allclose(np.asarray(steps), [1.0, 1.0, 1.0, 1.0, near])
    plain = dataclasses.replace(walker, prior=None)  # a vision student's: it commands the whole command
    student = VectorEnv.of(LearnerView(make("soccer-1v1-vision"), walker=plain, teacher_prior=True), 2, "native", 1)
    obs = student.reset(jax.random.PRNGKey(4)).state.obs
    np.testing.assert_allclose(np.asarray(obs["command_prior"]),
                               np.asarray(plain.prior_actions(obs["features"], tables)), atol=1e-6)
    np.testing.assert_allclose(np.asarray(plain.command(obs["command_prior"])),
                               np.clip(np.asarray(jax.vmap(lambda f: request_from_features(tables, f)[0])(
                                   obs["features"])), WALK.command_low, WALK.command_high), atol=1e-5)
    with pytest.raises(ConfigError, match="command_prior must be"):
        TrainConfig(task="soccer-1v1", soccer=SoccerTrainConfig(command_prior="placo")).resolved()


@pytest.fixture(scope="module")
def estimating():
    """(a walker with the placo prior, the first state of a vision game whose player estimates the game, gazes
    and sights): one reset, compiled once for the tests that read it."""
    from legged.soccer.placo.player import load_tables

    size = PROPRIO_SIZE + 8
    walker = dataclasses.replace(_walker([(np.zeros((size, 20), np.float32), np.full(20, 0.1, np.float32))]),
                                 prior=load_tables())
    view = LearnerView(make("soccer-1v1-vision", vision_gaze=True, vision_sightings=True), walker=walker)
    return walker, jax.tree.map(lambda x: x[0], VectorEnv.of(view, 1, "native", 1).reset(jax.random.PRNGKey(5)).state)


def test_a_gazing_vision_player_pans_its_head_toward_the_ball_it_estimates(estimating):
    """vision_gaze: the head pan joint's action faces the estimated ball (clipped to HEAD_PAN_LIMIT); every other
    joint is the walker's; it needs a player that estimates the game."""
    from legged.robots.op3 import OP3
    from legged.soccer.opponents import HEAD_PAN_LIMIT

    walker, state = estimating
    views = {gaze: LearnerView(make("soccer-1v1-vision", vision_gaze=gaze, vision_sightings=True), walker=walker)
             for gaze in (False, True)}
    action = jnp.zeros(17).at[3:5].set(jnp.asarray([1.0, 1.0]))  # no corrections; the ball 45 degrees left
    joints = {gaze: np.asarray(views[gaze].learner_actions(state, action)[0]) for gaze in (False, True)}
    assert joints[False][0] == pytest.approx(0.1, abs=1e-6)  # the walker's head
    assert joints[True][0] == pytest.approx(np.pi / 4 / OP3.action_scale, rel=1e-5)
    np.testing.assert_allclose(joints[True][1:], joints[False][1:])
    behind = np.asarray(views[True].learner_actions(state, action.at[3:5].set(jnp.asarray([-1.0, -0.01])))[0])
    assert behind[0] == pytest.approx(-HEAD_PAN_LIMIT / OP3.action_scale, rel=1e-5)
    with pytest.raises(ValueError, match="estimates the game"):
        LearnerView(make("soccer-1v1-vision", vision_gaze=True), walker=dataclasses.replace(walker, prior=None))
    with pytest.raises(ValueError, match="needs vision"):
        make("soccer-1v1", vision_gaze=True)


def test_a_walker_must_step_at_the_games_control_rate():
    from legged.tasks import learner_env, task_entry

    game = make("soccer-1v1", dataclasses.replace(make("soccer-1v1").config, ctrl_dt=0.05))
    layers = [(np.zeros((PROPRIO_SIZE + 8, 20)), np.zeros(20))]
    with pytest.raises(ValueError, match="set env.ctrl_dt=0.025"):
        learner_env(task_entry("soccer-1v1"), game, walker=_walker(layers))
    from legged.soccer.drills import DrillConfig, DrillEnv

    with pytest.raises(ValueError, match="set env.ctrl_dt=0.025"):  # a drill the player trains on, too
        DrillEnv(DrillConfig(name="empty-goal"), game.config, walker=_walker(layers))


def test_a_walker_must_be_an_op3_walk_run(tmp_path):
    from policies.config import ConfigError, TrainConfig
    from policies.soccer.config import SoccerTrainConfig
    from policies.policy_io import load_walker
    from policies.run_dir import RunDir

    with pytest.raises(ConfigError, match="soccer.walker .* is for soccer tasks"):
        TrainConfig(task="go1-flat", soccer=SoccerTrainConfig(walker="somewhere")).resolved()
    with pytest.raises(ConfigError, match="soccer.selfplay.script"):
        from policies.config import apply_overrides

        apply_overrides(TrainConfig(task="soccer-1v1").resolved(), ["soccer.selfplay.script=goalie"]).resolved()
    other = RunDir(tmp_path / "flat")
    other.create(TrainConfig(task="go1-flat").resolved())
    with pytest.raises(ValueError, match="a walker is an op3-walk run"):
        load_walker(other.path)
    walk = RunDir(tmp_path / "walk")
    walk.create(TrainConfig(task="op3-walk").resolved())
    with pytest.raises(ValueError, match="a get-up skill is `script` or an op3-getup run"):
        load_walker(walk.path, other.path)


def test_in_2v2_the_teammate_and_the_other_team_play_from_their_own_opponents():
    view = LearnerView(make("soccer-2v2"))
    features = view.game.policy_state_size
    constant = lambda value: network_opponent(np.zeros(features), np.ones(features), [
        (np.zeros((features, 20), np.float32), np.full(20, value, np.float32))])
    vector = VectorEnv.of(view, 1, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(1))
    batch, _ = vector.step(batch, jnp.full((1, 20), 0.1), constant(0.5), constant(-0.5))
    first_joint = np.asarray(batch.state.info["last_action"])[0, :, 0]
    team = view.game.layout.team
    expected = np.where(team == team[0], -0.5, 0.5)
    expected[0] = 0.1
    np.testing.assert_allclose(first_joint, expected, atol=1e-6)


def test_a_fallen_robot_gets_up_through_the_getup_skill_then_walks_again():
    """With a get-up skill the walker hands a robot tilted past 60 degrees to it (the back or front script,
    chosen from gravity, its clock running, the policy's corrections added), ignores its command and restarts
    its gait clock, gives it back once it stands upright near its default pose, and restarts a script that
    ended without standing."""
    from legged.soccer.getup_motion import getup_motion, motion_targets
    from legged.soccer.placo.player import actions_of
    from legged.soccer.walker import GETUP_RETRY_S

    walker = _walker([(np.zeros((PROPRIO_SIZE + 8, 20), np.float32), np.zeros(20, np.float32))])
    n = PROPRIO_SIZE + 2  # the get-up policy reads the script's two features after the proprioception
    getup = network_opponent(np.zeros(n), np.ones(n), [(np.zeros((n, 20), np.float32), np.full(20, 0.7, np.float32))])
    motion = getup_motion()
    walker = dataclasses.replace(walker, getup_motion=motion, getup=getup, getup_net=OpponentNet("elu"))

    def proprio(up_z, pose, face_down=False):  # gravity in the torso frame: tipped sideways, or face down
        tipped = [np.sqrt(1 - up_z ** 2), 0.0] if face_down else [0.0, -np.sqrt(1 - up_z ** 2)]
        return jnp.asarray([tipped + [-up_z, 0, 0, 0] + [pose] * 20 + [0.0] * 40], jnp.float32)

    command = jnp.ones((1, 3))
    walking = jnp.asarray([[0.3, 0.1, 0.0, 0.2, 0.0, 0.0, 0.0]])
    assert float(jnp.abs(walker.actions(proprio(1.0, 0.0), command, walking)).max()) == 0.0  # the walk net
    stays = walker.step(walking, command, proprio(0.8, 0.0))
    assert float(stays[0, 4]) == 0.0 and float(stays[0, 0]) > 0.3  # 37 degrees of tilt: still walking
    fallen = walker.step(walking, command, proprio(0.2, 0.0))
    np.testing.assert_allclose(np.asarray(fallen), [[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0]])  # on its side: the back script
    face_down = walker.step(walking, command, proprio(0.2, 0.0, face_down=True))
    assert float(face_down[0, 4]) == 1.0 and float(face_down[0, 6]) == 0.0                  # the front script
    later = walker.step(fallen, command, proprio(0.3, 0.0, face_down=True))
    np.testing.assert_allclose(np.asarray(later[0, 4:]), [1.0, walker.dt, 1.0], atol=1e-6)  # same script, clock on
    midway = later.at[0, 5].set(2.0)
    script = actions_of(motion_targets(motion, jnp.float32(1.0), jnp.float32(2.0)), jnp.asarray(walker.default_pose),
                        walker.action_scale)
    assert float(jnp.abs(script).max()) > 1.0  # two seconds in, the back script is far from the default pose
    np.testing.assert_allclose(np.asarray(walker.actions(proprio(0.3, 0.0), command, midway))[0], 0.7 + script,
                               atol=1e-5)
    alone = dataclasses.replace(walker, getup=None, getup_net=None)  # `getup=script`: the script alone
    np.testing.assert_allclose(np.asarray(alone.actions(proprio(0.3, 0.0), command, midway))[0], script, atol=1e-5)
    ended = later.at[0, 5].set(float(motion.length[1]) + GETUP_RETRY_S)
    again = walker.step(ended, command, proprio(0.2, 0.0, face_down=True))
    np.testing.assert_allclose(np.asarray(again[0, 4:]), [1.0, 0.0, 0.0])  # still down: the (front) script restarts
    crouched = walker.step(fallen, command, proprio(0.95, 0.5))  # upright but far from the standing pose
    assert float(crouched[0, 4]) == 1.0
    stood = walker.step(fallen, command, proprio(0.95, 0.1))
    assert float(stood[0, 4]) == 0.0 and float(stood[0, 0]) > 0.0  # walking again, the clock running


def test_getup_needs_a_walker_and_games_that_go_on_after_a_fall():
    from policies.config import ConfigError, TrainConfig, apply_overrides
    from policies.soccer.config import SoccerTrainConfig

    with pytest.raises(ConfigError, match="soccer.getup .* needs soccer.walker"):
        TrainConfig(task="soccer-1v1", soccer=SoccerTrainConfig(getup="up")).resolved()
    with pytest.raises(ConfigError, match="end_on_fall=never"):
        TrainConfig(task="soccer-1v1", soccer=SoccerTrainConfig(getup="up", walker="walk")).resolved()
    with pytest.raises(ConfigError, match="limb_floor_contacts=true"):
        apply_overrides(TrainConfig(task="soccer-1v1").resolved(),
                        ["soccer.getup=up", "soccer.walker=walk", "env.end_on_fall=never"])
    assert apply_overrides(TrainConfig(task="soccer-1v1").resolved(), [
        "soccer.getup=up", "soccer.walker=walk", "env.end_on_fall=never",
        "env.scene.limb_floor_contacts=true"]).soccer.getup == "up"


def test_what_a_vision_player_that_estimates_the_game_steers_by(estimating):
    """The estimate the placo command is computed from (`used_estimate`): the network's; with vision_sighted_ball
    the ball the camera sees, when it sees it; with estimate_oracle the truth for the parts named (diagnostics).
    A state pilot (`steer_with`) replaces the player's own corrections by its network's at that estimate."""
    from legged.soccer.vision.sightings import SIGHTED, SIGHTING_SIZE

    walker, state = estimating
    size = PROPRIO_SIZE + 14  # a state player's features: proprioception and the game
    view = lambda **extra: LearnerView(make("soccer-1v1-vision", vision_sightings=True, **extra), walker=walker)
    plain, sighted, oracle = view(), view(vision_sighted_ball=True), view(estimate_oracle=("ball", "own_goal"))
    action = jnp.arange(17, dtype=jnp.float32) / 10.0
    np.testing.assert_array_equal(np.asarray(plain.used_estimate(state, action)), np.asarray(action[3:]))
    obs = state.info["game_obs"]
    first = obs["state"].shape[-1] - len(SIGHTED) * SIGHTING_SIZE  # the state ends with the sightings, kept in info
    np.testing.assert_array_equal(np.asarray(obs["state"][:, first:]), np.asarray(state.info["sightings"]))
    for seen, expected in ((1.0, [0.7, -0.2, 0.05]), (0.0, np.asarray(action[3:6]))):
        row = state.info["sightings"].at[0, :4].set(jnp.asarray([seen, 0.7, -0.2, 0.05]))  # the ball's leads
        seeing = state.replace(info={**state.info, "sightings": row})
        used = np.asarray(sighted.used_estimate(seeing, action))
        np.testing.assert_allclose(used[:3], expected, atol=1e-6)
        np.testing.assert_array_equal(used[3:], np.asarray(action[6:]))
    truth = np.asarray(obs["features"][0, PROPRIO_SIZE:])
    used = np.asarray(oracle.used_estimate(state, action))
    np.testing.assert_array_equal(used[:3], truth[:3])         # ball
    np.testing.assert_array_equal(used[6:8], truth[6:8])       # own goal
    np.testing.assert_array_equal(used[3:6], np.asarray(action[6:9]))  # the rest: its own
    np.testing.assert_array_equal(used[8:], np.asarray(action[11:]))
    piloted = view()
    bias = np.array([0.3, -0.6, 0.2], np.float32)
    piloted.steer_with(network_opponent(np.zeros(size), np.ones(size),
                                        [(np.zeros((size, 3), np.float32), bias)]))
    joints, walker_state = piloted.learner_actions(state, action)
    expected = plain.learner_actions(state, action.at[:3].set(jnp.asarray(bias)))
    np.testing.assert_allclose(np.asarray(joints), np.asarray(expected[0]), atol=1e-6)
    np.testing.assert_allclose(np.asarray(walker_state), np.asarray(expected[1]), atol=1e-6)
    with pytest.raises(ValueError, match="reads 10 features"):
        view().steer_with(network_opponent(np.zeros(10), np.ones(10), [(np.zeros((10, 3)), np.zeros(3))]))
    with pytest.raises(ValueError, match="unknown: goal"):
        view(estimate_oracle=("goal",))
    no_prior = dataclasses.replace(walker, prior=None)
    with pytest.raises(ValueError, match="estimate_oracle replaces"):
        LearnerView(make("soccer-1v1-vision", estimate_oracle=("ball",)), walker=no_prior)
    with pytest.raises(ValueError, match="a state pilot steers"):
        LearnerView(make("soccer-1v1-vision"), walker=no_prior).steer_with(network_opponent(
            np.zeros(size), np.ones(size), [(np.zeros((size, 3)), np.zeros(3))]))


def test_a_shipped_piloted_vision_player_brings_its_pilot_to_games_and_drills():
    """A vision student whose config names a pilot (TrainConfig.soccer.pilot;
    assets/policies/op3-soccer-1v1-vision-piloted) is steered by it wherever it plays: in games (build_env: eval,
    view, DAgger) and in drills (drill_env); kl refuses it. A run that is not a state soccer player commanding the
    same walker is refused by name."""
    from pathlib import Path

    from legged.soccer.drills import DrillConfig
    from policies.soccer.drill import drill_env
    from policies.evaluate import state_player_game, steer_with_pilot
    from policies.run_dir import RunDir
    from policies.config import ConfigError
    from policies.training import build_env, refuse_pilot

    piloted = Path(__file__).resolve().parents[1] / "assets/policies/op3-soccer-1v1-vision-piloted"
    config = RunDir(piloted).load_config()
    assert config.soccer.pilot == "assets/policies/op3-soccer-1v1-pilot-steered"
    game = build_env(config, progress=False)
    assert game.state_pilot is not None and game.pilot_name == config.soccer.pilot
    assert game.state_pilot.mean.shape[-1] == PROPRIO_SIZE + game.world_size
    drill = drill_env(str(piloted), DrillConfig(name="empty-goal"), randomize=False)
    assert drill.state_pilot is not None and drill.pilot_name == config.soccer.pilot
    on_the_drill = dataclasses.replace(config, soccer=dataclasses.replace(config.soccer, drill="empty-goal"))
    trained_on_the_drill = build_env(on_the_drill, progress=False)  # its eval
    assert trained_on_the_drill.state_pilot is not None
    with pytest.raises(ValueError, match="pilot assets/policies/op3-walker: a soccer opponent is"):
        steer_with_pilot(game, "assets/policies/op3-walker")
    refuse_pilot(config)  # DAgger learns the estimate in the piloted games: its labels do not depend on who acts
    with pytest.raises(ConfigError, match="distil by kl without it"):
        refuse_pilot(dataclasses.replace(config, algo="kl"))  # kl's PPO would learn corrections the pilot ignores
    # `legged eval --compare-pilot` (and --compare-teacher) count on the state player's game starting as the
    # student's for the same reset key: the pilot, trained on estimate errors, plays them at the truth
    truth = state_player_game(RunDir(config.soccer.pilot).load_config())
    assert not truth.config.estimate_noise.enabled
    key = jax.random.fold_in(jax.random.PRNGKey(34567), 0)
    starts = [np.asarray(VectorEnv.of(env, 2, "native", 1).reset(key).state.obs["privileged_state"])
              for env in (game, truth)]
    np.testing.assert_array_equal(starts[0], starts[1])


def test_a_walker_that_reads_a_velocity_estimate_gets_the_games_own():
    """With env.velocity_in_state the walk skill's state ends with the torso's velocity in its own frame as a state
    estimator gives it (the truth within the noise); a walker trained on it reads the game's estimate of each robot,
    and a game that keeps none is refused in one line naming the field."""
    from legged.soccer.observe import local_velocity, read_bodies

    env = make("op3-walk", residual=False, velocity_in_state=True)
    layout = env.observation_layout()
    assert layout["state"][-1] == ("lin_vel", 3)
    batch, walker_state = _walk_state(env, 7)
    state = np.asarray(batch.state.obs["state"])
    for group, parts in layout.items():
        assert batch.state.obs[group].shape[-1] == sum(n for _, n in parts), group
    data = batch.state.pipeline_state
    truth = np.stack([np.asarray(local_velocity(read_bodies(env.game.layout, data.qpos[i], data.qvel[i])))[0]
                      for i in range(2)])
    error = state[:, -3:] - truth
    assert np.abs(error).max() <= env.config.noise.lin_vel + 1e-6 and np.abs(error).max() > 0
    assert np.abs(truth).max() > 0.01  # the robots move: the estimate is not a constant
    command = np.asarray(jax.vmap(env.command)(batch.state.info))
    identity = dataclasses.replace(_walker([(np.eye(state.shape[1], dtype=np.float32),
                                             np.zeros(state.shape[1], np.float32))]), velocity_input=True)
    estimate = batch.state.info["velocity_estimate"][:, 0]
    rebuilt = identity.actions(jnp.asarray(state[:, :PROPRIO_SIZE]), jnp.asarray(_action_of(command)), walker_state,
                               estimate)
    np.testing.assert_allclose(np.asarray(rebuilt), state, atol=1e-5)
    with pytest.raises(ValueError, match="env.velocity_in_state"):
        identity.actions(jnp.asarray(state[:, :PROPRIO_SIZE]), jnp.asarray(_action_of(command)), walker_state)

    size = PROPRIO_SIZE + 11
    w = np.zeros((size, 20), np.float32)
    w[size - 3, 0] = 1.0  # joint 0 <- the estimated forward velocity
    walker = dataclasses.replace(_walker([(w, np.zeros(20, np.float32))]), velocity_input=True)
    with pytest.raises(ValueError, match="set env.velocity_in_state=true"):
        LearnerView(make("soccer-1v1"), walker=walker)
    view = LearnerView(make("soccer-1v1", velocity_in_state=True), walker=walker)
    vector = VectorEnv.of(view, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(0))
    moving = batch.state.info["velocity_estimate"] + jnp.array([0.3, 0.0, 0.0])
    batch = dataclasses.replace(batch, state=batch.state.replace(info=dict(batch.state.info, velocity_estimate=moving)))
    features = view.game.policy_state_size  # a network opponent walks through the walker too
    opponent = network_opponent(np.zeros(features), np.ones(features),
                                [(np.zeros((features, 3), np.float32), np.zeros(3, np.float32))])
    batch, _ = vector.step(batch, jnp.zeros((2, 3)), opponent)
    joints = np.asarray(batch.state.info["last_action"])[:, :, 0]  # [env, robot]: both robots read their estimate
    np.testing.assert_allclose(joints, np.asarray(moving)[:, :, 0], atol=1e-6)
    with pytest.raises(ValueError, match="op3-getup does not read a velocity estimate"):
        make("op3-getup", velocity_in_state=True)


def test_a_walker_warm_started_with_a_velocity_estimate_first_walks_as_before():
    """op3-walk with env.velocity_in_state from the shipped walker trained without it: its inputs are mapped by name
    (SkillEnv.observation_layout), the estimate starts at zero weight, so the first policy is the walker's."""
    from pathlib import Path

    import torch

    from policies.config import PPOConfig
    from tests.warm_support import saved_actor, warm_started

    source = Path(__file__).resolve().parents[1] / "assets" / "policies" / "op3-walker-v1"
    env = make("op3-walk", velocity_in_state=True)
    ppo = PPOConfig(actor_hidden=(512, 256, 128), critic_hidden=(512, 256, 128))
    new, obs, note = warm_started(source, env, "op3-walk", 20, ppo, seed=2)
    size = env.observation_dims()["state"]
    assert f"state: {size - 3} of {size}" in note, note
    walker = saved_actor(source, make("op3-walk").observation_dims(), 20, ppo)
    old = obs.clone()
    old["state"] = obs["state"][:, :-3]
    with torch.no_grad():
        assert torch.allclose(new.actor(obs, stochastic_output=False), walker.actor(old, stochastic_output=False),
                              atol=1e-5)
