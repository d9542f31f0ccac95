"""The OP3 skills: op3-walk (the placo gait as its reference) and op3-getup, and their drills."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.cli import main
from legged.soccer.placo.player import actions_of
from legged.skills.config import WalkSkillConfig
from legged.tasks import make


@pytest.fixture(scope="module")
def env():
    return make("op3-walk", residual=False)  # actions are the joints' own (the residual skill: tests/test_walker.py)


def _rollout(env, policy: str, steps: int = 60, n: int = 4) -> dict:
    from legged.envs.vector import VectorEnv

    vector = VectorEnv.of(env, n, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(0))
    sums = {"standing": float(np.mean(np.asarray(jax.vmap(lambda s: env.standing(_bodies(env, s)))(
        batch.state.pipeline_state))))}
    reference = jax.jit(jax.vmap(lambda info: actions_of(env.reference(info), env.tables.default_pose,
                                                         env.robot.action_scale)))
    for _ in range(steps):
        action = jnp.zeros((n, env.action_size)) if policy == "zero" else reference(batch.state.info)
        batch, _ = vector.step(batch, action)
        for k, v in batch.state.metrics.items():
            sums[k] = sums.get(k, 0.0) + float(np.mean(np.asarray(v))) / steps
    return sums


def _bodies(env, view):
    from legged.soccer.observe import read_bodies

    return read_bodies(env.game.layout, view.qpos, view.qvel)


def test_observations_and_reference(env):
    dims = env.observation_dims()
    assert dims["state"] == 66 + 3 + 3 + 2 and dims["privileged_state"] == dims["state"] + 3 + 1 + 1 + 20
    info = {"gait_phase": jnp.float32(0.25), "gait_command": jnp.array([0.2, 0.0, 0.0])}
    assert env.reference(info).shape == (20,)


def test_playing_the_reference_earns_the_imitation_reward(env):
    zero, played = _rollout(env, "zero"), _rollout(env, "reference")
    assert played["imitation_rms_rad"] < 0.6 * zero["imitation_rms_rad"]      # measured: 0.08 vs 0.17 rad
    assert played["reward/imitation"] > zero["reward/imitation"]
    assert played["speed_mps"] > 2 * zero["speed_mps"]                        # it walks; standing does not
    assert zero["reward/fall"] == 0.0 and played["reward/fall"] == 0.0
    assert zero["standing"] == 1.0                                            # the getup drill's criterion
    # tracked on the velocity filtered over half a stride, the gait pays more than standing (0.75 vs 0.67,
    # 0.059 vs 0.063 m/s); its instantaneous error, swaying within each step, is higher (0.089 m/s)
    assert played["reward/tracking_lin_vel"] > zero["reward/tracking_lin_vel"]
    assert played["smoothed_tracking_error_mps"] < min(zero["smoothed_tracking_error_mps"],
                                                       played["tracking_error_mps"])


def test_walk_drill_measures_the_yaw_rate_error():
    """A robot that stands still while told to turn at 0.4 rad/s (and walk 0.1 m/s) misses both by all of it."""
    still = _rollout(make("op3-walk", residual=False, command_low=(0.1, 0.0, 0.4), command_high=(0.1, 0.0, 0.4)),
                     "zero", steps=40)
    assert abs(still["smoothed_yaw_rate_error_radps"] - 0.4) < 0.05
    assert abs(still["smoothed_tracking_error_mps"] - 0.1) < 0.02


def test_getup_starts_lying_and_rewards_rising():
    getup = make("op3-getup", residual=False)  # zero actions hold the default pose (no script)
    assert getup.observation_dims() == {"state": 68, "privileged_state": 93}
    lying = _rollout(getup, "zero", steps=40)
    assert lying["standing"] == 0.0 and lying["stood"] == 0.0
    assert lying["reward/standing"] == 0.0 and lying["reward/height"] < 0.2   # lying low: little height reward
    # the first observation already lies flat: torso height and up axis before the reference's 20 targets
    from legged.envs.vector import VectorEnv

    batch = VectorEnv.of(getup, 4, "native", 1).reset(jax.random.PRNGKey(1))
    privileged = np.asarray(batch.state.obs["privileged_state"])
    assert np.all(privileged[:, -22] < 0.12) and np.all(np.abs(privileged[:, -21]) < 0.3)


def test_getup_motions_are_robotis_key_poses_between_default_poses():
    """The scripted get-ups start and end in the default pose, pass through ROBOTIS' key poses mirrored
    left to right, and the one that plays is the front one only for a robot lying face down."""
    from legged.robots.op3 import OP3
    from legged.soccer.getup_motion import getup_motion, lies_on_back, motion_features, motion_targets

    motion, default = getup_motion(), np.asarray(OP3.default_pose)
    index = {name: i for i, name in enumerate(OP3.joint_names)}
    for back in (0.0, 1.0):
        at = lambda t: np.asarray(motion_targets(motion, jnp.float32(back), jnp.float32(t)))  # noqa: E731
        np.testing.assert_allclose(at(0.0), default, atol=1e-6)
        np.testing.assert_allclose(at(float(motion.length[int(back)])), default, atol=1e-6)
        second = float(motion.starts[int(back), 1] + motion.moves[int(back), 1])   # the second key pose reached
        np.testing.assert_allclose(at(second), np.asarray(motion.poses[int(back), 2]), atol=1e-5)
        for joint in ("sho_pitch", "el", "hip_pitch", "knee", "ank_pitch"):
            assert at(second)[index[f"l_{joint}"]] == pytest.approx(-at(second)[index[f"r_{joint}"]], abs=1e-6)
        assert np.asarray(motion_features(motion, jnp.float32(back), jnp.float32(99.0))).tolist() == [back, 1.0]
    front_knee = np.asarray(motion.poses[0, 3])[index["l_knee"]]
    assert front_knee == pytest.approx(2.457, abs=1e-3)  # ROBOTIS' deepest crouch, inside the widened range
    gravity = jnp.asarray([[0.9, 0.0, -0.1], [-0.9, 0.0, -0.1], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])
    assert np.asarray(lies_on_back(gravity)).tolist() == [0.0, 1.0, 1.0, 1.0]  # face down, back, side, upright


def test_bad_walk_configs_and_drills_fail_in_one_line(tmp_path, capsys):
    with pytest.raises(ValueError, match="command_low"):
        WalkSkillConfig(command_low=(0.3, 0.0, 0.0))
    with pytest.raises(ValueError, match="command_seconds"):
        WalkSkillConfig(command_seconds=0.0)
    from policies.config import TrainConfig
    from policies.run_dir import RunDir

    walker = RunDir(tmp_path / "walker")
    walker.create(TrainConfig(task="op3-walk").resolved())
    assert main(["drill", "empty-goal", "--player", str(walker.path)]) == 2
    err = capsys.readouterr().err
    assert "does the walk drill, not empty-goal" in err and err.count("\n") == 1, err
    soccer = RunDir(tmp_path / "soccer")
    soccer.create(TrainConfig(task="soccer-1v1").resolved())
    assert main(["drill", "getup", "--player", str(soccer.path)]) == 2
    err = capsys.readouterr().err
    assert "needs placo or an op3-getup run" in err and err.count("\n") == 1, err


def test_getup_drill_reports_success_and_time(capsys):
    import json

    assert main(["drill", "getup", "--player", "placo", "--episodes", "2", "--threads", "1", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["drill"] == "getup" and report["episode_seconds"] == pytest.approx(5.0)
    assert report["success_rate"] == 0.0 and report["time_to_stand_s"] is None  # the placo player cannot get up


def test_robotis_scripted_getup_stands_within_the_drill(capsys):
    """ROBOTIS' get-ups, played open loop in this model (its widened joint ranges, limbs touching the floor),
    stand the robot up from lying starts within the drill's 5 s, with the game's randomisation on."""
    import json

    assert main(["drill", "getup", "--player", "script", "--episodes", "4", "--num-envs", "4", "--threads", "1",
                 "--randomize", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["success_rate"] == 1.0 and 2.0 < report["time_to_stand_s"] < 5.0
    assert main(["drill", "walk", "--player", "script"]) == 2
    err = capsys.readouterr().err
    assert "the getup drill only" in err and err.count("\n") == 1, err
