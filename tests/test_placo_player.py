"""The placo soccer player as data: its motion modes, its soccer decisions, and where it plays (drills,
opponents, PettingZoo); errors of `legged drill` and `legged eval --opponent`."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.cli import main
from legged.soccer.placo.player import (BLEND, KICK, STAND, START, STOP, WALK, PlayerMemory, initial_memory,
                                        load_tables, motion_step, soccer_request)


@pytest.fixture(scope="module")
def tables():
    return load_tables()


def _run(tables, memory, request, kick, side, steps):
    step = jax.jit(lambda m, r, k, s: motion_step(tables, m, r, k, s))
    modes, targets = [], []
    for _ in range(steps):
        q, memory = step(memory, jnp.asarray(request, jnp.float32), jnp.bool_(kick), jnp.float32(side))
        modes.append(int(PlayerMemory.unpack(memory).mode))
        targets.append(np.asarray(q))
    return memory, modes, np.array(targets)


def test_modes_blend_start_walk_stop_kick_stand(tables):
    memory = initial_memory(1)[0]
    memory, modes, targets = _run(tables, memory, (0.1, 0.0, 0.0), False, 0, 120)
    assert modes[0] == BLEND and START in modes and modes[-1] == WALK
    assert np.allclose(targets[0], tables.default_pose, atol=0.1)     # out of the default pose, smoothly
    assert np.abs(np.diff(targets, axis=0)).max() < 0.2                # no jumps between modes
    memory, modes, _ = _run(tables, memory, (0.1, 0.0, 0.0), True, 1, 200)  # ask to kick: stop first
    kick = modes.index(KICK)
    assert modes.index(STOP) < kick and STAND in modes[kick:]             # kicks, then stands
    assert float(PlayerMemory.unpack(memory).side) == 1.0
    memory, modes, _ = _run(tables, memory, (0.0, 0.0, 0.0), False, 0, 130)
    assert modes[-5:] == [STAND] * 5                                   # no request: the kick ends, it stands
    memory, modes, _ = _run(tables, memory, (0.0, 0.0, 0.3), False, 0, 5)
    assert modes[0] == START                                           # a request: it walks again


def test_soccer_decisions(tables):
    goal = jnp.array([3.0, 0.0])
    command, ready, side = soccer_request(tables, jnp.array([1.0, 0.0]), jnp.zeros(2), goal)
    assert command[0] > 0 and not bool(ready)                          # ball ahead: walk to it
    aim = np.asarray(tables.kick.ball[0])
    command, ready, side = soccer_request(tables, jnp.asarray(aim), jnp.zeros(2), goal)
    assert bool(ready) and int(side) == 0                              # at the aim point, facing the goal: kick
    _, ready, _ = soccer_request(tables, jnp.asarray(aim), jnp.array([0.5, 0.0]), goal)
    assert not bool(ready)                                             # not while the ball rolls
    command, _, _ = soccer_request(tables, jnp.array([-0.5, 0.0]), jnp.zeros(2), jnp.array([-3.0, 0.0]))
    assert abs(float(command[2])) > 0.1                                # goal behind: turn


def test_placo_opponent_keeps_memory_per_robot(tables):
    from legged.soccer.observe import PROPRIO_SIZE
    from legged.soccer.opponents import OpponentNet, network_opponent, opponent_step, placo_opponent

    size = PROPRIO_SIZE + 14
    obs = jnp.zeros((1, size)).at[0, PROPRIO_SIZE].set(1.0).at[0, PROPRIO_SIZE + 8].set(3.0)
    memory = initial_memory(1)
    actions, moved, _ = opponent_step(OpponentNet(), placo_opponent(size, 20), obs, memory, tables, 0.3)
    assert actions.shape == (1, 20) and float(moved[0, 1]) > 0.0       # its sequence clock advanced
    net = network_opponent(np.zeros(size), np.ones(size), [(np.zeros((size, 20)), np.ones(20))])
    actions, kept, _ = opponent_step(OpponentNet(), net, obs, memory, tables, 0.3)
    assert np.allclose(actions, 1.0) and np.array_equal(kept, memory)  # a network ignores the memory


def test_drill_and_opponent_errors_are_one_line(tmp_path, capsys):
    from policies.config import TrainConfig
    from policies.run_dir import RunDir

    flat = RunDir(tmp_path / "flat")
    flat.create(TrainConfig(task="go1-flat").resolved())
    cases = [(["drill", "dribble"], "unknown drill 'dribble'"),
             (["drill", "walk", "--player", str(tmp_path / "none")], "is not a run directory"),
             (["drill", "empty-goal", "--player", str(flat.path)], "not go1-flat"),
             (["drill", "walk", "--checkpoint", str(tmp_path / "step_1.pt")], "--player placo has none"),
             (["eval", str(flat.path), "--opponent", "placo"], "applies to soccer tasks")]
    for argv, message in cases:
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    from legged.soccer.drills import DrillConfig

    with pytest.raises(ValueError, match="positive length, got episode_seconds=0"):
        DrillConfig(name="walk", episode_seconds=0.0)


def test_dashboard_rolls_out_against_the_placo_player():
    from legged.robots.op3 import OP3
    from web.source import ViewRequest, resolve

    resolved = resolve(ViewRequest(task="soccer-1v1", physics="native", opponent="placo", port=None), log=lambda m: None)
    trajectory = resolved.source.record(30, seed=1)
    assert trajectory.info["opponent"] == "placo"
    layout = resolved.source.env.game.layout
    legs = [i for i, name in enumerate(OP3.joint_names) if "head" not in name]
    away = np.asarray(trajectory.qpos)[-1, 0, layout.joint_qpos_adr[1][legs]]
    # the placo player bends into its walking stance (the standing script keeps the default pose)
    assert np.abs(away - np.asarray(OP3.default_pose)[legs]).max() > 0.05


def test_view_opponent_needs_a_soccer_task(capsys):
    assert main(["view", "--task", "go1-flat", "--opponent", "placo", "--save", "x.npz"]) == 2
    err = capsys.readouterr().err
    assert "applies to soccer tasks" in err and err.count("\n") == 1, err
