"""Every `legged` sub-command fed bad input: one line on stderr naming the cause, exit code 2, no traceback,
nothing half-written, and nothing that runs long (absurd numbers are refused before any work starts).

The CLI runs in this process (`legged.cli.main`), so the whole file takes seconds.
"""

import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml

from legged.cli import main
from policies.config import TrainConfig, to_dict


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Malformed inputs of every kind the CLI reads."""
    d = tmp_path_factory.mktemp("bad")
    (d / "empty").write_bytes(b"")
    (d / "text.txt").write_text("not what you think\n")
    (d / "bad.xml").write_text("<mujoco><worldbody><geom type='box'/></wrong></mujoco>")
    np.savez(d / "other.npz", x=np.zeros(3))
    with zipfile.ZipFile(d / "truncated.npz", "w") as z:
        z.writestr("qpos.npy", b"\x93NUMPY trunc")
    # a run directory whose checkpoints are damaged in every way
    run = d / "run"
    (run / "checkpoints").mkdir(parents=True)
    config = TrainConfig(task="go1-flat").resolved()
    (run / "config.yaml").write_text(yaml.safe_dump(to_dict(config)))
    (run / "checkpoints" / "step_000000000010.pt").write_bytes(b"\x80\x04truncated")
    (run / "checkpoints" / "step_000000000020.pt").write_text("plain text")
    # a pickle that would run code when loaded: it must be refused, never executed
    torch.save(_Boom(), run / "evil.pt")
    # a run directory with a config that is not one
    broken = d / "broken-run"
    broken.mkdir()
    (broken / "config.yaml").write_text("task: [unclosed\n")
    # box tunnels to navigate: an open one, and one walled off in the middle
    from legged.robots import GO1
    from planners.narrow_scenes import block, tunnel_xml

    (d / "tunnel.xml").write_text(tunnel_xml([]))
    (d / "walled.xml").write_text(tunnel_xml([block(GO1, 0.0, 0.0)]))
    return d


FOLLOWER = str(Path(__file__).resolve().parents[1] / "assets" / "policies" / "go1-confined-follower")
PILOTED = str(Path(__file__).resolve().parents[1] / "assets" / "policies" / "op3-soccer-1v1-vision-piloted")
"""A vision student steered by a state pilot (TrainConfig.soccer.pilot)."""
"""The shipped waypoint follower (navigate's bad-input cases need a policy that can navigate)."""


class _Boom:
    def __reduce__(self):
        return (exec, ("raise SystemExit('pickle code ran')",))


CASES = {
    # (argv, words the one error line must contain)
    "world: bad seed": (["world", "--seed", "abc", "--out", "{d}/w"], "expected a whole number"),
    "world: absurd difficulty": (["world", "--difficulty", "999999999", "--out", "{d}/w"], "between 0 and 20"),
    "world: unwritable out": (["world", "--out", "/proc/legged-world"], "cannot create"),
    "tasks: unknown option": (["tasks", "--frobnicate"], "unrecognized arguments"),
    "plan: nan start": (["plan", "--start", "nan,0,0.27"], "finite"),
    "plan: two coordinates": (["plan", "--goal", "1,2"], "X,Y,Z"),
    "plan: zero time limit": (["plan", "--time-limit", "0"], "greater than 0"),
    "plan: missing scene": (["plan", "--scene", "{d}/none.xml", "--start", "0,0,0.27", "--goal", "1,0,0.27"],
                            "not found"),
    "plan: malformed scene": (["plan", "--scene", "{d}/bad.xml", "--start", "0,0,0.27", "--goal", "1,0,0.27"],
                              "cannot load scene"),
    "plan: unknown planner": (["plan", "--planner", "teleport"], "teleport"),
    "bench env: unknown task": (["bench", "env", "--task", "nope"], "unknown task"),
    "bench env: zero batch": (["bench", "env", "--batch", "0"], "integers from 1"),
    "bench env: absurd batch": (["bench", "env", "--batch", "100000000"], "integers from 1"),
    "bench env: zero seconds": (["bench", "env", "--seconds", "0"], "greater than 0"),
    "bench env: endless seconds": (["bench", "env", "--seconds", "1e30"], "at most 3600"),
    "bench env: unknown physics": (["bench", "env", "--physics", "warp"], "choose from"),
    "bench env: zero threads": (["bench", "env", "--threads", "0"], "between 1"),
    "bench soccer: zero peer steps": (["bench", "soccer", "--peer-steps", "0"], "between 1"),
    "bench soccer: three a side": (["bench", "soccer", "--team-sizes", "3"], "1 and/or 2"),
    "bench plan: no worlds": (["bench", "plan", "--worlds", "0"], "between 1"),
    "bench navigate: no scene directory": (["bench", "navigate", "--scenes", "{d}/none"], "scene directory not found"),
    "bench navigate: a broken scene": (["bench", "navigate", "--scenes", "{d}"], "cannot load scene"),
    "bench navigate: zero seeds": (["bench", "navigate", "--scenes", "{d}", "--seeds", "0"], "between 1"),
    "bench soak: unknown task": (["bench", "soak", "--tasks", "nope"], "unknown task"),
    "bench physics: unknown task": (["bench", "physics", "nope"], "unknown task"),
    "bench physics: unknown variant": (["bench", "physics", "go1-flat", "--variants", "rk4"], "unknown physics variant"),
    "bench soak: absurd steps": (["bench", "soak", "--steps", "1e99"], "whole number"),
    "train: no task": (["train"], "name a task"),
    "train: unknown task": (["train", "nope", "--run-dir", "{d}/t1"], "unknown task"),
    "train: zero envs": (["train", "go1-flat", "--num-envs", "0"], "between 1"),
    "train: absurd timesteps": (["train", "go1-flat", "--timesteps", "10000000000000000"], "between 1"),
    "train: unknown physics": (["train", "go1-flat", "--physics", "gpu"], "invalid choice"),
    "train: brax on native": (["train", "go1-flat", "--backend", "brax", "--physics", "native", "--run-dir", "{d}/t2"],
                              "needs --physics mjx"),
    "train: bad override": (["train", "go1-flat", "--set", "ppo.learning_rate", "--run-dir", "{d}/t3"],
                            "path.to.field=value"),
    "train: unknown field": (["train", "go1-flat", "--set", "ppo.speed=9", "--run-dir", "{d}/t4"], "no field"),
    "train: wrong kind of value": (["train", "go1-flat", "--set", "ppo.learning_rate=fast", "--run-dir", "{d}/t5"],
                                   "expected float"),
    "train: negative learning rate": (["train", "go1-flat", "--set", "ppo.learning_rate=-1", "--run-dir", "{d}/t6"],
                                      "learning_rate"),
    "train: resume nothing": (["train", "--resume", "{d}/none"], "not a run directory"),
    "train: resume broken config": (["train", "--resume", "{d}/broken-run"], "unusable"),
    "train: resume with overrides": (["train", "--resume", "{d}/run", "--set", "ppo.learning_rate=1e-4"],
                                     "drop --set"),
    "train: resume with a task": (["train", "go1-flat", "--resume", "{d}/run"], "drop the task"),
    "eval: missing run": (["eval", "{d}/none"], "not a run directory"),
    "eval: zero episodes": (["eval", "{d}/run", "--episodes", "0"], "between 1"),
    "eval: absurd episodes": (["eval", "{d}/run", "--episodes", "10000000000"], "between 1"),
    "eval: truncated checkpoint": (["eval", "{d}/run", "--checkpoint", "{d}/run/checkpoints/step_000000000010.pt"],
                                   "cannot be read"),
    "eval: text as checkpoint": (["eval", "{d}/run"], "cannot be read"),
    "eval: empty checkpoint": (["eval", "{d}/run", "--checkpoint", "{d}/empty"], "cannot be read"),
    "eval: code in a pickle": (["eval", "{d}/run", "--checkpoint", "{d}/run/evil.pt"], "not loaded"),
    "eval: missing checkpoint": (["eval", "{d}/run", "--checkpoint", "{d}/none.pt"], "not found"),
    "export: no format": (["export", "{d}/run"], "choose a format"),
    "export: damaged checkpoint": (["export", "{d}/run", "--onnx", "--out", "{d}/p.onnx"], "cannot be read"),
    "camera: not soccer": (["camera", "--task", "go1-flat"], "not a soccer task"),
    "camera: unknown task": (["camera", "--task", "nope"], "unknown task"),
    "demo: unknown physics": (["demo", "--physics", "bullet"], "bullet"),
    "demo: policy of another task": (["demo", "--policy", "{d}/run"], "does not follow waypoints"),
    "navigate: policy of another task": (["navigate", "--policy", "{d}/run"], "does not follow waypoints"),
    "navigate: missing policy": (["navigate", "--policy", "{d}/none"], "not a run directory"),
    "navigate: start in a wall": (["navigate", "--policy", FOLLOWER, "--scene", "{d}/tunnel.xml", "--start",
                                   "-1.5,0.5,0.27", "--goal", "1.5,0,0.27"], "start pose"),
    "navigate: goal off the map": (["navigate", "--policy", FOLLOWER, "--scene", "{d}/tunnel.xml", "--start",
                                    "-1.5,0,0.27", "--goal", "9,0,0.27"], "off the scene"),
    "navigate: scene without start": (["navigate", "--policy", FOLLOWER, "--scene", "{d}/tunnel.xml"],
                                      "needs --start"),
    "navigate: zero speed limit": (["navigate", "--max-speed", "0"], "greater than 0"),
    "navigate: negative speed limit": (["navigate", "--max-speed", "-1"], "greater than 0"),
    "navigate: absurd speed limit": (["navigate", "--max-speed", "1e9"], "at most 10"),
    "bench navigate: zero speed limit": (["bench", "navigate", "--scenes", "{d}", "--max-speed", "0"],
                                         "greater than 0"),
    "train: negative speed limit": (["train", "confined-waypoints", "--set", "env.max_speed=-1", "--run-dir",
                                     "{d}/t11"], "max_speed"),
    "train: speed range upside down": (["train", "confined-waypoints", "--set", "env.speed_range=[0.8, 0.3]",
                                        "--run-dir", "{d}/t12"], "speed_range"),
    "train: brax with the curriculum": (["train", "confined-waypoints", "--backend", "brax", "--run-dir", "{d}/t7"],
                                        "env.curriculum=false"),
    "train: warm start from nothing": (["train", "confined-waypoints", "--init-from", "{d}/none", "--run-dir",
                                        "{d}/t8"], "not a run directory"),
    "eval: difficulty of a flat task": (["eval", "{d}/run", "--difficulty", "1"], "apply to confined tasks"),
    "eval: set outside env": (["eval", "{d}/run", "--set", "ppo.learning_rate=1"], "evaluated environment only"),
    "eval: set no field": (["eval", "{d}/run", "--set", "env.randomization.cone=1"], "no field 'cone'"),
    "bench settings: unknown change": (["bench", "settings", "go1-flat", "--changes", "cheap"], "unknown setting"),
    "eval: negative difficulty": (["eval", "{d}/run", "--difficulty", "-1"], "from 0 to 20"),
    "eval: pilot of a flat task": (["eval", "{d}/run", "--pilot", "teacher"], "apply to soccer vision students"),
    "eval: compare with no pilot": (["eval", "{d}/run", "--compare-pilot"], "has no pilot"),
    "eval: placo as a pilot": (["eval", PILOTED, "--pilot", "placo"], "a pilot is the run directory"),
    "train: pilot of a state player": (["train", "soccer-1v1", "--set", "soccer.pilot=" + PILOTED, "--run-dir",
                                        "{d}/t9"], "needs a vision student that estimates the game"),
    "distill: with a pilot": (["distill", PILOTED.replace("-vision-piloted", ""), "--task", "soccer-1v1-vision",
                               "--method", "kl", "--set", "soccer.command_prior=placo", "--set",
                               "soccer.pilot=" + PILOTED, "--run-dir", "{d}/t10"], "distil by kl without it"),
    "eval: oracle of a flat task": (["eval", "{d}/run", "--oracle", "ball"], "apply to soccer vision students"),
    "eval: tracker of a flat task": (["eval", "{d}/run", "--tracker"], "apply to soccer vision students"),
    "eval: teacher of a flat task": (["eval", "{d}/run", "--compare-teacher"], "not a soccer student distilled"),
    "eval: ood and nominal": (["eval", "{d}/run", "--ood", "--nominal"], "choose one"),
    "eval: teacher on another robot": (["eval", PILOTED, "--compare-teacher", "--robot", "menagerie"],
                                       "play on the project's robot model"),
    "view: too many envs": (["view", "--num-envs", "64"], "between 1 and 16"),
    "view: missing trajectory": (["view", "--trajectory", "{d}/none.npz", "--port", "0"], "not found"),
    "view: empty trajectory": (["view", "--trajectory", "{d}/empty", "--port", "0"], "{d}/empty"),
    "view: wrong-kind trajectory": (["view", "--trajectory", "{d}/other.npz", "--port", "0"], "other.npz"),
    "view: truncated trajectory": (["view", "--trajectory", "{d}/truncated.npz", "--port", "0"], "truncated.npz"),
    "view: bad port": (["view", "--port", "99999"], "between 0 and 65,535"),
    "plot: missing run": (["plot", "{d}/none"], "no records"),
    "plot: unknown metric": (["plot", "{d}/run", "--y", "nope"], "no records"),
    "convert: untrusted pickles": (["convert-checkpoints", "{d}/none"], "not a run directory"),
    "slim: not a run": (["slim", "{d}/none"], "not a run directory"),
    "average: one source": (["average", "{d}/run", "--out", "{d}/avg"], "at least two"),
    "average: missing source": (["average", "{d}/run", "{d}/none", "--out", "{d}/avg"], "neither a run directory"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_is_one_line_and_exit_2(name, files, capsys):
    argv, words = CASES[name]
    argv = [a.replace("{d}", str(files)) for a in argv]
    words = words.replace("{d}", str(files))
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith(("WARNING", "Failed to import"))]
    assert code == 2, (name, code, err)
    assert len(lines) == 1, (name, err)
    assert "Traceback" not in err and words in lines[0], (name, lines[0])


def test_nothing_half_written(files):
    for name in ("t1", "t2", "t3", "t4", "t5", "t6", "t7", "t8", "t9", "t10", "t11", "t12", "w"):
        assert not (files / name).exists(), name
    assert not (files / "p.onnx").exists()


def test_navigate_reports_an_unreachable_goal_as_such(files, capsys):
    """A walled-off goal is an outcome, not a crash: one line saying it cannot be reached, exit code 1, found by
    the planner before anything is compiled."""
    code = main(["navigate", "--policy", FOLLOWER, "--scene", str(files / "walled.xml"), "--start", "-1.5,0,0.27",
                 "--goal", "1.5,0,0.27", "--json"])
    out = capsys.readouterr().out.strip().splitlines()
    assert code == 1 and len(out) == 1
    report = __import__("json").loads(out[0])
    assert report["success"] is False and report["reachable"] is False and "cannot be reached" in report["error"]
