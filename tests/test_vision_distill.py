"""Vision students of a state soccer player (`legged distill TEACHER --task soccer-1v1-vision --method
dagger|kl`): the KL loss, the errors, and a tiny distillation by each method in native physics."""

import dataclasses
import json
import warnings

import numpy as np
import pytest
import torch
from rsl_rl.models import MLPModel
from tensordict import TensorDict

from legged.cli import main
from policies.algorithms import build_algorithm
from policies.config import TrainConfig, apply_overrides
from policies.rsl_backend import dummy_observations, load_checkpoint, save_checkpoint
from policies.run_dir import RunDir
from policies.soccer.config import SoccerTrainConfig
from policies.teacher_kl import TeacherKL

TINY = ["ppo.actor_hidden=[16]", "ppo.critic_hidden=[16]", "ppo.num_steps_per_env=4", "ppo.num_mini_batches=2",
        "env.episode_seconds=0.5"]


def _gaussian_mlp(n_in: int, seed: int) -> MLPModel:
    torch.manual_seed(seed)
    obs = TensorDict({"x": torch.zeros(1, n_in)}, batch_size=[1])
    return MLPModel(obs, {"actor": ["x"]}, "actor", 2, hidden_dims=[8], obs_normalization=False,
                    distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})


def test_teacher_kl_is_zero_for_the_teacher_itself_and_trains_the_student_only():
    teacher, student = _gaussian_mlp(3, 0), _gaussian_mlp(3, 0)
    batch = type("Batch", (), {"observations": TensorDict({"x": torch.randn(64, 3)}, batch_size=[64])})()
    kl = TeacherKL(teacher, weight=2.0, decay=0.5, iteration=1)
    assert kl.weight == pytest.approx(1.0)  # 2 x 0.5^1: a resumed run goes on with its weight
    student(batch.observations, stochastic_output=True)
    assert float(kl.compute_loss(student, batch, 64).detach()) == pytest.approx(0.0, abs=1e-6)
    other = _gaussian_mlp(3, 1)
    other(batch.observations, stochastic_output=True)
    loss = kl.compute_loss(other, batch, 64)
    loss.backward()
    assert float(loss.detach()) > 0.01 and all(p.grad is None for p in teacher.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in other.parameters())
    kl.end_iteration()
    assert kl.weight == pytest.approx(0.5) and kl.means()["teacher_kl"] > 0


def test_teacher_kl_of_a_student_that_estimates_the_game_uses_the_teachers_labels():
    """KL on the corrections against the teacher's labels (clipped by its margin), squared error on the rest."""
    from torch.distributions import Normal

    from policies.algorithms import WorldLabeller

    torch.manual_seed(0)
    n, features, world = 16, 9, 4
    obs = TensorDict({"features": torch.randn(n, features), "command_prior": torch.rand(n, 3) * 2 - 1}, batch_size=[n])
    teacher = WorldLabeller(obs, {"teacher": ["features"]}, "teacher", 3 + world, corrections=3, margin=0.0,
                            hidden_dims=[8], distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})
    with torch.no_grad():
        teacher.mlp[-1].bias.fill_(3.0)  # corrections the clip cuts: raw and clipped labels differ
        labels = teacher(obs)
    teacher_std = torch.full((n, 3), 0.5)

    class Student:  # the actor's side of the seam: its last distribution and the KL of its distribution type
        output_distribution_params = (labels.clone(), torch.cat([teacher_std, torch.full((n, world), 0.1)], -1))

        @staticmethod
        def get_kl_divergence(old, new):
            return torch.distributions.kl_divergence(Normal(*old), Normal(*new)).sum(-1)

    batch = type("Batch", (), {"observations": obs})()
    kl = TeacherKL(teacher, weight=1.0, decay=1.0)
    assert float(kl.compute_loss(Student, batch, n)) == pytest.approx(0.0, abs=1e-6)
    means = kl.means()
    assert means["teacher_kl"] == pytest.approx(0.0, abs=1e-6) and means["estimate_mse"] == pytest.approx(0.0)
    Student.output_distribution_params[0][:, 3:] += 0.5  # the estimate off by 0.5 everywhere
    assert float(kl.compute_loss(Student, batch, n)) == pytest.approx(0.25)
    Student.output_distribution_params[0][:, :3] = teacher.mlp(teacher.get_latent(obs)).detach()  # raw corrections
    assert kl.compute_loss(Student, batch, n) > 1.0  # beyond the clip: far from the teacher's clipped labels


@pytest.fixture(scope="module")
def soccer_teacher(tmp_path_factory):
    """An (untrained) state soccer player: config and one checkpoint."""
    from legged.soccer.learner import LearnerView
    from legged.tasks import make

    cfg = apply_overrides(TrainConfig(task="soccer-1v1", physics="native", threads=1, num_envs=2, timesteps=8,
                                      checkpoint_every=1).resolved(), TINY)
    run = RunDir(tmp_path_factory.mktemp("soccer") / "teacher")
    run.create(cfg)
    sizes = LearnerView(make("soccer-1v1")).observation_dims()
    alg = build_algorithm(cfg, dummy_observations(sizes, 2), 2, 20, "cpu")
    save_checkpoint(run, alg, 1, 8, sizes, 20)
    return run.path


def test_vision_distillation_errors_are_one_line(soccer_teacher, tmp_path, capsys):
    flat = RunDir(tmp_path / "flat")
    flat.create(TrainConfig(task="go1-flat").resolved())
    cases = [([str(soccer_teacher), "--method", "rma", "--task", "soccer-1v1-vision"], "learns by dagger or kl"),
             ([str(flat.path), "--method", "kl", "--task", "soccer-1v1-vision"], "cannot teach soccer-1v1-vision"),
             ([str(soccer_teacher), "--method", "dagger", "--task", "soccer-2v2-vision"], "cannot teach")]
    for argv, message in cases:
        assert main(["distill", *argv, "--run-dir", str(tmp_path / "student")]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


@pytest.fixture(scope="module")
def dagger_student(soccer_teacher, tmp_path_factory):
    """A tiny memoryless DAgger vision student of `soccer_teacher` (run directory, last record)."""
    from policies.distill import start_distill

    out = tmp_path_factory.mktemp("vision") / "dagger"
    return out, start_distill(str(soccer_teacher), "dagger", str(out), timesteps=16, progress=False,
                              task="soccer-1v1-vision")


@pytest.mark.parametrize("method", ["kl", "dagger"])
def test_a_vision_student_learns_from_the_state_player(soccer_teacher, tmp_path, method, request):
    from policies.distill import start_distill
    from policies.policy_io import load_policy

    if method == "dagger":
        out, record = request.getfixturevalue("dagger_student")
    else:
        out = tmp_path / method
        record = start_distill(str(soccer_teacher), method, str(out), timesteps=16, progress=False,
                               task="soccer-1v1-vision")
    assert record["step"] == 16
    losses = [v for k, v in record.items() if k.startswith("loss_")]
    assert losses and all(np.isfinite(losses))
    if method == "kl":
        assert record["teacher_kl"] > 0 and record["teacher_kl_weight"] == pytest.approx(0.995)  # the second iteration's
    student, cfg = load_policy(out)
    assert cfg.task == "soccer-1v1-vision" and cfg.env.vision and cfg.algo == method
    assert student.inputs == ("state", "camera") and student.num_actions == 20
    assert dataclasses.replace(cfg.env, vision=False) == RunDir(soccer_teacher).load_config().env


WALKER = "assets/policies/op3-walker-v1"
DRILL_S = 1.0
"""Episodes of the tests' drills (40 control steps; the drill's own 20 s took 5 minutes on a slow machine)."""


def _placo_teacher_config() -> TrainConfig:
    """A tiny state soccer player whose commands correct the placo player's."""
    return apply_overrides(TrainConfig(task="soccer-1v1", physics="native", threads=1, num_envs=2, timesteps=8,
                                       checkpoint_every=1,
                                       soccer=SoccerTrainConfig(walker=WALKER, command_prior="placo")).resolved(), TINY)


def _state_sizes() -> dict:
    from legged.soccer.learner import LearnerView
    from legged.tasks import make
    from policies.policy_io import load_walker

    return LearnerView(make("soccer-1v1"), walker=load_walker(WALKER, prior="placo")).observation_dims()


@pytest.fixture(scope="module")
def placo_teacher(tmp_path_factory):
    """The run directory of an untrained `_placo_teacher_config` player (a checkpoint of its initial networks)."""
    cfg, sizes = _placo_teacher_config(), _state_sizes()
    teacher = RunDir(tmp_path_factory.mktemp("placo") / "teacher").create(cfg)
    save_checkpoint(teacher, build_algorithm(cfg, dummy_observations(sizes, 2), 2, 3, "cpu"), 1, 8, sizes, 3)
    return teacher.path


def test_a_teacher_that_corrected_the_placo_command_teaches_the_whole_command(placo_teacher, tmp_path):
    from rsl_rl.utils import resolve_class

    from policies.algorithms import teacher_model
    from policies.distill import start_distill
    from policies.policy_io import load_policy

    cfg, sizes = _placo_teacher_config(), _state_sizes()
    obs = dummy_observations(sizes, 2)
    obs["features"], obs["command_prior"] = torch.randn(2, sizes["state"]), torch.randn(2, 3)
    cls, kwargs = resolve_class(teacher_model(cfg))
    corrector = cls(obs, {"teacher": ["features"]}, "teacher", 3, **kwargs)
    plain = MLPModel(obs, {"teacher": ["features"]}, "teacher", 3, **kwargs)
    plain.load_state_dict(corrector.state_dict())
    torch.testing.assert_close(corrector(obs), (plain(obs) + obs["command_prior"]).clamp(-1.0, 1.0))
    assert (plain(obs) + obs["command_prior"]).abs().max() > 1.0  # the clip was exercised
    corrector(obs, stochastic_output=True)
    plain(obs, stochastic_output=True)
    torch.testing.assert_close(corrector.output_mean, (plain.output_mean + obs["command_prior"]).clamp(-1.0, 1.0))

    record = start_distill(str(placo_teacher), "dagger", str(tmp_path / "student"), timesteps=16, progress=False,
                           task="soccer-1v1-vision")
    assert record["step"] == 16 and np.isfinite(record["loss_behavior"])
    assert "loss_behavior_ball" not in record  # a whole-command student has no label groups
    student, scfg = load_policy(tmp_path / "student")
    assert scfg.soccer.command_prior == "" and scfg.distill.teacher_prior and scfg.game_gives_placo_command
    assert scfg.soccer.walker == WALKER
    assert student.inputs == ("state", "camera") and student.num_actions == 3
    from policies.soccer.drill import run_drill  # the student does the empty-goal drill through its own camera

    report = run_drill("empty-goal", str(tmp_path / "student"), episodes=1, seed=0, threads=1, progress=False,
                       num_envs=1, seconds=DRILL_S)
    assert report["episodes"] == 1 and report["goal_rate"] in (0.0, 1.0)


def test_a_student_that_estimates_the_game_adds_the_placo_command_from_its_estimate(placo_teacher, tmp_path, capsys):
    import jax
    import jax.numpy as jnp
    from rsl_rl.utils import resolve_class

    from legged.envs.vector import VectorEnv
    from legged.soccer.learner import LearnerView
    from legged.soccer.observe import PROPRIO_SIZE
    from legged.tasks import make
    from policies.algorithms import teacher_model
    from policies.distill import start_distill
    from policies.soccer.drill import run_drill
    from policies.policy_io import load_policy, load_walker

    walker = load_walker(WALKER, prior="placo")
    view = LearnerView(make("soccer-1v1-vision"), walker=walker)
    assert view.estimates_world and view.world_size == 14 and view.action_size == 17 and view.player_action_size == 3
    # a native reset: the check is of the actions, and MJX would compile the game and its camera for it
    state = jax.tree.map(lambda x: x[0], VectorEnv.of(view, 1, "native", 1).reset(jax.random.PRNGKey(0)).state)
    truth = state.obs["features"][PROPRIO_SIZE:]
    correction = jnp.array([0.1, -0.2, 0.3])
    joints = lambda world: view.learner_actions(state, jnp.concatenate([correction, world]))[0]
    proprio = state.info["game_obs"]["state"][:1, :PROPRIO_SIZE]
    command = walker.with_prior(correction[None], jnp.concatenate([proprio, truth[None]], -1))  # placo from the truth
    expected = walker.actions(proprio, command, state.info["walker_state"][:1])[0]
    np.testing.assert_allclose(joints(truth), expected, atol=1e-5)
    assert jnp.abs(joints(truth.at[:2].add(jnp.array([-1.0, 1.0]))) - expected).max() > 1e-3  # the estimate counts

    cfg = _placo_teacher_config()
    sizes = _state_sizes()
    obs = dummy_observations(sizes, 2)
    obs["features"] = torch.randn(2, sizes["state"])
    student_cfg = dataclasses.replace(cfg, task="soccer-1v1-vision", algo="dagger",
                                      env=dataclasses.replace(cfg.env, vision=True))
    cls, kwargs = resolve_class(teacher_model(cfg, student_cfg))
    labeller = cls(obs, {"teacher": ["features"]}, "teacher", 17, **kwargs)
    plain = MLPModel(obs, {"teacher": ["features"]}, "teacher", 3, **{k: v for k, v in kwargs.items()
                                                                       if k not in ("corrections", "margin")})
    plain.load_state_dict(labeller.state_dict())
    torch.testing.assert_close(labeller(obs), torch.cat([plain(obs), obs["features"][:, PROPRIO_SIZE:]], -1))
    obs["command_prior"] = torch.tensor([[0.9, -0.2, 0.0], [-1.0, 0.5, 1.0]])  # the placo command at the truth
    torch.testing.assert_close(labeller(obs)[:, :3], plain(obs))  # by default the raw corrections
    for margin in (0.0, 0.5):  # what a clip of the command to [-1 - margin, 1 + margin] leaves of the corrections
        margin_cfg = dataclasses.replace(student_cfg, distill=dataclasses.replace(student_cfg.distill,
                                                                                  correction_margin=margin))
        cls, kwargs = resolve_class(teacher_model(cfg, margin_cfg))
        with_margin = cls(obs, {"teacher": ["features"]}, "teacher", 17, **kwargs)
        with_margin.load_state_dict(labeller.state_dict())
        clipped = (plain(obs) + obs["command_prior"]).clamp(-1 - margin, 1 + margin) - obs["command_prior"]
        torch.testing.assert_close(with_margin(obs)[:, :3], clipped)
        assert (clipped + obs["command_prior"]).abs().max() <= 1.0 + margin

    assert main(["train", "soccer-1v1-vision", "--run-dir", str(tmp_path / "ppo"), "--set",
                 f"soccer.walker={WALKER}", "--set", "soccer.command_prior=placo"]) == 2
    err = capsys.readouterr().err
    assert "only a distilled student" in err and err.count("\n") == 1, err
    record = start_distill(str(placo_teacher), "dagger", str(tmp_path / "student"), timesteps=16, progress=False,
                           task="soccer-1v1-vision", overrides=["soccer.command_prior=placo"])
    assert record["step"] == 16 and np.isfinite(record["loss_behavior"]) and "loss_behavior_ball" in record
    student, scfg = load_policy(tmp_path / "student")
    assert scfg.estimates_world and scfg.distill.teacher_prior and student.num_actions == 17  # raw labels
    assert not scfg.game_gives_placo_command  # it computes the command from its estimate; raw labels need none
    report = run_drill("empty-goal", str(tmp_path / "student"), episodes=1, seed=0, threads=1, progress=False,
                       num_envs=1, checkpoint=str(RunDir(tmp_path / "student").latest_checkpoint()), seconds=DRILL_S)
    assert report["episodes"] == 1 and report["checkpoint"].endswith(".pt")
    assert 0.0 < report["episode_seconds"] <= DRILL_S + 1e-6  # the drill's length is the one asked for
    assert sorted(report["estimate_rms_m"]) == ["ball", "ball_near", "ball_near_share", "first_other",
                                                "opponent_goal", "own_goal"]
    capsys.readouterr()
    assert main(["eval", str(tmp_path / "student"), "--opponent", "placo", "--episodes", "1", "--num-envs", "1",
                 "--physics", "native", "--threads", "1", "--json", "--compare-teacher"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["teacher"]["run"] == str(placo_teacher)  # its teacher played the same game
    assert report["goals_vs_teacher"]["games"] == 1
    assert report["goals_vs_teacher"]["baseline_goals"] == report["teacher"]["goals_for_per_episode"]
    errors = report["estimate_rms_m"]  # how far its estimate was from the truth
    near, share = errors.pop("ball_near"), errors.pop("ball_near_share")  # the ball when near: some steps or none
    assert sorted(errors) == ["ball", "first_other", "opponent_goal", "own_goal"]
    assert all(0.0 < e < 100.0 for e in errors.values())
    assert 0.0 <= share <= 1.0 and (near is None if share == 0.0 else 0.0 < near < 100.0)

    # KL-regularised RL from that student: its critic learns first, its actor held still, then both
    record = start_distill(str(placo_teacher), "kl", str(tmp_path / "kl"), timesteps=16, progress=False,
                           task="soccer-1v1-vision", overrides=["soccer.command_prior=placo", "checkpoint_every=1",
                                                                f"distill.student_init={tmp_path / 'student'}",
                                                                "distill.student_init_whole=true",
                                                                "distill.critic_warmup=1"])
    assert record["actor_frozen"] == 0.0 and np.isfinite(record["estimate_mse"]) and record["teacher_kl"] > 0
    first, last = (load_checkpoint(path)["alg"]["actor_state_dict"] for path in RunDir(tmp_path / "kl").checkpoints())
    dagger = load_checkpoint(RunDir(tmp_path / "student").latest_checkpoint())["alg"]["student_state_dict"]
    learned = [k for k in first if not k.startswith("obs_normalizer.")]
    assert all(torch.equal(first[k], dagger[k]) for k in learned)  # held still in the critic's warm-up
    assert any(not torch.equal(last[k], first[k]) for k in learned)  # then trained
    kl_student, kl_cfg = load_policy(tmp_path / "kl")
    assert kl_cfg.algo == "kl" and kl_cfg.estimates_world and kl_student.num_actions == 17


def test_a_curriculum_distils_on_the_empty_goal_drill_then_takes_that_student_whole(placo_teacher, tmp_path, capsys):
    from legged.soccer.drills import DrillConfig, DrillEnv
    from policies.distill import start_distill
    from policies.soccer.drill import drill_env
    from policies.training import build_env

    student = ["soccer.command_prior=placo", "env.vision_gaze=true", "env.scene.head_camera_fovy_deg=70"]
    sets = lambda extra: sum((["--set", o] for o in student + extra), [])
    distill = ["distill", str(placo_teacher), "--method", "dagger", "--task", "soccer-1v1-vision", "--run-dir"]
    for extra, message in ((["soccer.drill=walk"], "soccer.drill must be ''"),
                           (["distill.student_init_whole=true"], "name that run")):
        assert main(distill + [str(tmp_path / "bad"), *sets(extra)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    drill = tmp_path / "drill"
    record = start_distill(str(placo_teacher), "dagger", str(drill), timesteps=16, progress=False,
                           task="soccer-1v1-vision", overrides=student + ["soccer.drill=empty-goal"])
    assert record["step"] == 16 and np.isfinite(record["loss_behavior"])
    assert not TrainConfig(task="soccer-1v1",  # nobody else plays a drill
                           soccer=SoccerTrainConfig(drill="empty-goal")).resolved().self_play
    env = build_env(RunDir(drill).load_config())
    assert isinstance(env, DrillEnv) and env.drill.name == "empty-goal" and env.config.end_on_goal
    seen = drill_env(str(drill), DrillConfig(name="empty-goal"), randomize=False)  # `legged drill` sees as it learned
    assert seen.config.vision_gaze and seen.config.scene.head_camera_fovy_deg == 70.0
    assert main(["eval", str(drill), "--opponent", "placo", "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert "nobody else plays" in err and err.count("\n") == 1, err

    assert main(distill + [str(tmp_path / "bad"), *sets([f"distill.student_init={drill}/checkpoints/step_9.pt"])]) == 2
    err = capsys.readouterr().err
    assert "no such checkpoint" in err and err.count("\n") == 1, err
    whole = tmp_path / "whole"  # the second stage, in the game, starts as the drill's student (and barely moves)
    start_distill(str(placo_teacher), "dagger", str(whole), timesteps=8, progress=False, task="soccer-1v1-vision",
                  overrides=student + [f"distill.student_init={RunDir(drill).latest_checkpoint()}",
                                       "distill.student_init_whole=true", "distill.learning_rate=1e-12"])
    assert build_env(RunDir(whole).load_config()).__class__.__name__ == "LearnerView"
    before, after = (load_checkpoint(RunDir(run).latest_checkpoint())["alg"]["student_state_dict"]
                     for run in (drill, whole))
    assert sorted(before) == sorted(after)
    for key in before:
        if not key.startswith("obs_normalizer."):  # the normaliser's statistics follow the new data
            torch.testing.assert_close(after[key], before[key], atol=1e-6, rtol=0)
    assert main(distill + [str(tmp_path / "memory"), *sets([f"distill.student_init={drill}", "distill.student_memory=8",
                                                          "distill.student_init_whole=true"])]) == 2
    err = capsys.readouterr().err
    assert "does not fit this one whole" in err and err.count("\n") == 1, err


def test_dagger_beta_falls_linearly_to_zero():
    from policies.distill import teacher_share

    assert [teacher_share(0.5, 4, k) for k in (0, 2, 4, 9)] == [0.5, 0.25, 0.0, 0.0]
    assert teacher_share(0.3, 0, 100) == 0.3 and teacher_share(0.0, 10, 0) == 0.0


def test_the_game_gives_the_placo_command_to_a_corrector_or_to_clip_an_estimating_students_labels():
    vision = dataclasses.replace(TrainConfig(task="soccer-1v1-vision").resolved(), algo="dagger")
    corrected = dataclasses.replace(vision.distill, teacher_prior=True)
    assert not vision.game_gives_placo_command  # a teacher that did not correct the placo command
    assert dataclasses.replace(vision, distill=corrected).game_gives_placo_command  # the observation command_prior
    estimating = dataclasses.replace(vision, soccer=SoccerTrainConfig(command_prior="placo"), distill=corrected)
    assert estimating.estimates_world and not estimating.game_gives_placo_command  # raw labels: not needed
    clipped = dataclasses.replace(estimating, distill=dataclasses.replace(corrected, correction_margin=0.5))
    assert clipped.game_gives_placo_command  # to clip its correction labels


def test_a_memory_student_starts_from_another_remembers_forgets_on_reset_and_exports(soccer_teacher, dagger_student,
                                                                                   tmp_path, capsys):
    from policies.distill import start_distill
    from policies.export import export_onnx
    from policies.policy_io import load_policy

    memory = ["distill.student_memory=8", "distill.gradient_length=2"]
    for method, extra, message in (("kl", memory + ["ppo.num_mini_batches=4"], "a multiple of ppo.num_mini_batches"),
                                   ("dagger", ["distill.critic_warmup=2"], "is for --method kl"),
                                   ("kl", ["distill.teacher_act_fraction=0.5"], "DAgger's beta"),
                                   ("dagger", ["distill.student_init=" + str(soccer_teacher)], "not a dagger vision")):
        assert main(["distill", str(soccer_teacher), "--method", method, "--task", "soccer-1v1-vision", "--run-dir",
                     str(tmp_path / method), *sum((["--set", o] for o in extra), [])]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    first = dagger_student[0]  # a memoryless student whose camera encoder the memory student starts from
    record = start_distill(str(soccer_teacher), "dagger", str(tmp_path / "memory"), timesteps=16, progress=False,
                           task="soccer-1v1-vision", overrides=memory + [
                               f"distill.student_init={first}", "distill.teacher_act_fraction=0.5",
                               "env.vision_heading=true"])  # its state grows by the attacking direction
    assert record["step"] == 16 and np.isfinite(record["loss_behavior"])
    policy, cfg = load_policy(tmp_path / "memory")
    assert policy.recurrent and cfg.distill.student_memory == 8 and cfg.env.vision_heading
    assert policy.obs_sizes["state"] == load_policy(first)[0].obs_sizes["state"] + 2
    rng = np.random.default_rng(0)
    obs = {"state": rng.normal(size=(3, policy.obs_sizes["state"])).astype(np.float32),
           "camera": rng.random((3, *policy.obs_sizes["camera"]), dtype=np.float32)}
    first_step, second_step = policy.act(obs), policy.act(obs)
    assert np.abs(first_step - second_step).max() > 1e-6  # the same observation, another memory
    done = np.array([True, False, False])
    done.flags.writeable = False  # as the envs hand it; torch would warn on a read-only array
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        policy.reset(done)
    third_step = policy.act(obs)
    np.testing.assert_allclose(third_step[0], first_step[0], atol=1e-6)  # episode 0 starts afresh
    policy.reset()
    np.testing.assert_allclose(policy.act(obs), first_step, atol=1e-6)
    check = export_onnx(policy, tmp_path / "memory.onnx", samples=4)
    assert check["inputs"] == ["obs", "camera", "memory"] and check["max_abs_diff"] <= 1e-4
    record = start_distill(str(soccer_teacher), "kl", str(tmp_path / "kl"), timesteps=16, progress=False,
                           task="soccer-1v1-vision", overrides=memory + [  # PPO on its trajectories, with memory
                               f"distill.student_init={tmp_path / 'memory'}", "distill.student_init_whole=true",
                               "env.vision_heading=true"])
    assert record["step"] == 16 and np.isfinite(record["loss_surrogate"]) and record["teacher_kl"] > 0
    assert load_policy(tmp_path / "kl")[0].recurrent


def test_the_deployed_memory_actor_computes_what_the_trained_model_does():
    """Steps of MemoryCNNModel (as rsl-rl's Distillation runs it) against DeployedMemoryActor, with a reset of one
    episode in between."""
    from policies.algorithms import CAMERA_CNN
    from policies.memory_models import MemoryCNNModel

    torch.manual_seed(0)
    n = 3
    obs = TensorDict({"state": torch.randn(n, 5), "camera": torch.rand(n, 4, 30, 40)}, batch_size=[n])
    model = MemoryCNNModel(obs, {"actor": ["state", "camera"]}, "actor", 2, memory_dim=6, hidden_dims=[8],
                           obs_normalization=True, cnn_cfg=dict(CAMERA_CNN),
                           distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})
    model.update_normalization(obs)  # statistics that are not the identity
    deployed = model.as_onnx().eval()
    model.eval()
    memory = deployed.initial_memory(n)
    for step in range(4):
        frame = TensorDict({"state": torch.randn(n, 5), "camera": torch.rand(n, 4, 30, 40)}, batch_size=[n])
        with torch.no_grad():
            expected = model(frame)
            actions, memory = deployed(frame["state"], frame["camera"], memory)
        torch.testing.assert_close(actions, expected)
        if step == 1:  # episode 1 ends: both forget it
            done = torch.tensor([0, 1, 0])
            model.reset(done)
            memory[:, done == 1] = 0.0
    torch.testing.assert_close(memory, model.get_hidden_state())


def test_a_memory_actor_reads_padded_trajectories_as_it_read_their_steps():
    """PPO's update (rsl-rl's recurrent mini-batches: trajectories split at episode ends, padded, with the
    memory at each trajectory's start) gives a MemoryCNNModel's outputs of the rollout's steps."""
    from rsl_rl.utils import split_and_pad_trajectories

    from policies.algorithms import CAMERA_CNN
    from policies.memory_models import MemoryCNNModel

    torch.manual_seed(0)
    steps, n = 5, 3
    rollout = TensorDict({"state": torch.randn(steps, n, 5), "camera": torch.rand(steps, n, 4, 30, 40)},
                         batch_size=[steps, n])
    dones = torch.zeros(steps, n, 1)
    dones[1, 0] = dones[3, 2] = 1  # episodes end after these steps
    model = MemoryCNNModel(rollout[0], {"actor": ["state", "camera"]}, "actor", 2, memory_dim=6, hidden_dims=[8],
                           obs_normalization=True, cnn_cfg=dict(CAMERA_CNN),
                           distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.5})
    model.update_normalization(rollout[0])
    model.eval()
    model.reset(hidden_state=torch.randn(1, n, 6))  # an earlier rollout's memory
    start = model.get_hidden_state().clone()
    expected = []
    with torch.no_grad():
        for t in range(steps):
            expected.append(model(rollout[t]))
            model.reset(dones[t, :, 0])
        padded, masks = split_and_pad_trajectories(rollout, dones)
        first = torch.cat([start[:, :1], torch.zeros(1, 1, 6), start[:, 1:], torch.zeros(1, 1, 6)], dim=1)
        actual = model(padded, masks=masks, hidden_state=first)  # trajectories: env 0 twice, 1, 2 twice
    torch.testing.assert_close(actual, torch.stack(expected))


def test_label_weights_weigh_named_groups_and_the_drill_ignores_the_absent_opponent():
    import torch.nn.functional as F

    from policies.algorithms import weighted_labels
    from policies.config import ConfigError
    from policies.distill import GroupedLoss

    from policies.config import DistillConfig

    student = apply_overrides(TrainConfig(task="soccer-1v1-vision", algo="dagger", distill=DistillConfig(teacher="t")),
                              [f"soccer.walker={WALKER}", "soccer.command_prior=placo"])
    labels = weighted_labels(student)
    assert list(labels["label_groups"]) == ["corrections", "ball", "ball_vel", "own_goal", "opponent_goal",
                                            "opponent0"] and labels["label_weights"] == [1.0] * 17
    on_the_drill = dataclasses.replace(student, soccer=dataclasses.replace(student.soccer, drill="empty-goal"))
    drill = weighted_labels(on_the_drill)["label_weights"]
    assert drill[:13] == [1.0] * 13 and drill[13:] == [0.0] * 4  # the opponent goal still counts
    weighted = apply_overrides(student, ["distill.label_weights={ball: 4, corrections: 0.5}"])
    assert weighted_labels(weighted)["label_weights"][:7] == [0.5] * 3 + [4.0] * 3 + [1.0]
    twice = apply_overrides(weighted, ["distill.label_weights.ball=2", "distill.label_weights.own_goal=3"])
    assert twice.distill.label_weights == {"ball": 2.0, "corrections": 0.5, "own_goal": 3.0}  # entries of the mapping
    assert weighted.distill.label_weights == {"ball": 4.0, "corrections": 0.5}  # the original stays as it was
    for bad, message in (("{bal: 4}", "no label group"), ("{ball: -1}", r"in \[0, 1000\]"), ("4", "a mapping"),
                         ("{ball:4}", "a space after each colon")):
        with pytest.raises(ConfigError, match=message):
            apply_overrides(student, [f"distill.label_weights={bad}"])
    with pytest.raises(ConfigError, match="estimates the game"):
        apply_overrides(TrainConfig(task="soccer-1v1"), ["distill.label_weights={ball: 2}"])

    actions, targets = torch.randn(5, 4, 17), torch.randn(5, 4, 17)
    plain = GroupedLoss(labels["label_groups"], labels["label_weights"])
    torch.testing.assert_close(plain(actions, targets), F.mse_loss(actions, targets))
    report = plain.report()
    torch.testing.assert_close(torch.tensor(report["behavior_ball"]), F.mse_loss(actions[..., 3:6], targets[..., 3:6]))
    assert sorted(report) == sorted(f"behavior_{name}" for name in labels["label_groups"]) and plain.count == 0
    only_ball = GroupedLoss(labels["label_groups"], [0.0] * 3 + [1.0] * 3 + [0.0] * 11)
    torch.testing.assert_close(only_ball(actions, targets), F.mse_loss(actions[..., 3:6], targets[..., 3:6]) * 3 / 17)
