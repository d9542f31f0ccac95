"""go1-rough: the terrain generator, the curriculum, pushes, the state history and the privileged state, in
native physics (one small environment compiled once)."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.config import RandomizationConfig
from legged.envs.vector import VectorEnv
from legged.envs.rough import RoughConfig, RoughEnv, commanded_displacement
from legged.worlds import WorldError
from legged.worlds.rough import KINDS, RoughTerrainConfig, rough_terrain
from policies.evaluate import held_out, ood_config
from policies.rsl_vecenv import RslVecEnv

SMALL = RoughTerrainConfig(levels=2, tile_size=2.0, border=1.0)
"""Two rows of 2 m tiles: quick to build and to collide with."""


def test_tiles_reach_their_maxima_and_join_at_zero():
    cfg = RoughTerrainConfig(levels=3)
    terrain = rough_terrain(0, cfg)
    n = int(round(cfg.tile_size / cfg.resolution)) + 1  # samples per tile side (tiles sit side by side)
    pad = int(round(cfg.border / cfg.resolution))
    assert terrain.num_tiles == 3 * len(KINDS) and list(terrain.difficulties) == [0] * 5 + [1] * 5 + [2] * 5
    hardest = terrain.floor[pad + 2 * n: pad + 3 * n]  # the last row of tiles
    slope = hardest[:, pad: pad + n]
    step = np.abs(np.diff(slope, axis=0)).max() / cfg.resolution
    assert np.degrees(np.arctan(step)) == pytest.approx(cfg.max_slope_deg, abs=0.01)
    stairs = hardest[:, pad + 2 * n: pad + 3 * n]
    assert np.abs(np.diff(stairs, axis=0)).max() == pytest.approx(cfg.max_step_height, abs=1e-6)
    assert set(np.round(np.unique(np.abs(stairs)) / cfg.max_step_height, 6)) <= set(float(k) for k in range(20))
    edges = lambda size: np.concatenate([np.arange(pad, size - pad, n), np.arange(pad + n - 1, size - pad, n)])
    assert np.abs(terrain.floor[edges(terrain.floor.shape[0])]).max() < 1e-6  # every tile border lies at 0
    assert np.abs(terrain.floor[:, edges(terrain.floor.shape[1])]).max() < 1e-6
    assert np.abs(terrain.floor[:pad]).max() == 0.0  # the flat border
    centre = terrain.starts[4]
    assert terrain.floor_at(centre[None, :2])[0] == pytest.approx(centre[2], abs=1e-6)  # robots start on the floor
    assert not np.array_equal(rough_terrain(1, cfg).floor, terrain.floor)  # bumps differ by seed


@pytest.mark.parametrize("bad, match", [(dict(kinds=("lava",)), "kinds"), (dict(levels=0), "levels"),
                                        (dict(flat_radius=5.0), "flat_radius"), (dict(max_slope_deg=70), "slope")])
def test_bad_terrain_configs_name_the_field(bad, match):
    with pytest.raises(WorldError, match=match):
        rough_terrain(0, dataclasses.replace(SMALL, **bad))


@pytest.fixture(scope="module")
def rough():
    config = RoughConfig(terrain=SMALL, history_steps=3, past_steps=2, episode_seconds=2.0,
                         randomization=RandomizationConfig(enabled=True, push_interval_s=0.1, push_velocity=1.0))
    env = RoughEnv(config)
    return env, VectorEnv.of(env, 4, "native", threads=1).native


def test_history_pushes_and_privileged_terrain(rough):
    env, native = rough
    state = native.reset(jax.random.split(jax.random.PRNGKey(0), 4))
    obs = state.obs
    first = np.asarray(obs["state"])
    assert obs["history"].shape == (4, 3 * first.shape[1])
    assert np.allclose(np.asarray(obs["history"]).reshape(4, 3, -1), first[:, None])  # a new episode repeats it
    layout = dict(env.observation_layout()["privileged_state"])
    assert layout["task"] == 4 * 9 + 1
    pushed, seen, clean = [], [first], np.asarray(obs["privileged_state"])[:, :first.shape[1]]
    for k in range(6):
        before = np.asarray(state.pipeline_state.qvel)
        state = native.step(state, jnp.zeros((4, 12)))
        history = np.asarray(state.obs["history"]).reshape(4, 3, -1)
        assert np.allclose(history[:, -1], state.obs["state"])  # newest last, oldest first
        assert np.allclose(history[:, -2], first)  # the step before
        first = np.asarray(state.obs["state"])
        seen.append(first)
        pushed.append(bool(np.asarray(state.info["teleported"]).all()))
        if pushed[-1]:  # the kick reached the engine: its velocity is the view's
            assert np.allclose(native.physics.batch.bind("qvel")[:, :2], np.asarray(state.pipeline_state.qvel)[:, :2])
            assert np.abs(np.asarray(state.pipeline_state.qvel)[:, :2] - before[:, :2]).max() > 0.05
    assert pushed == [False, False, False, False, True, False]  # every 0.1 s = 5 control steps
    names = [n for n, _ in env.observation_layout()["state"]]
    assert names[:2] == ["gravity", "gyro"]
    part = lambda name, obs: obs[:, slices[name]]
    slices, at = {}, 0
    for name, size in env.observation_layout()["state"]:
        slices[name], at = slice(at, at + size), at + size
    for name in ("joint_pos", "joint_vel", "last_action"):  # past_steps=2: the two steps before, as observed then
        past = part(f"past_{name}", seen[-1]).reshape(4, 2, 12)
        assert np.allclose(past[:, 1], part(name, seen[-2])) and np.allclose(past[:, 0], part(name, seen[-3]))
        assert np.allclose(part(f"past_{name}", seen[0]).reshape(4, 2, 12), part(name, clean)[:, None])  # a new
        # episode's: its first values (clean: no observation came before)  # the IMU's angular velocity, body frame, clean in the privileged copy
    assert np.allclose(np.asarray(state.obs["privileged_state"])[:, 3:6], np.asarray(state.pipeline_state.qvel)[:, 3:6])
    feet = np.asarray(jax.vmap(env.feet_positions)(state.pipeline_state))
    heights = np.asarray(state.obs["privileged_state"])[:, -37:-1].reshape(4, 4, 9)
    floor = env.terrain.floor_at(feet[..., :2].reshape(-1, 2)).reshape(4, 4)
    assert np.allclose(heights[:, :, 4], feet[..., 2] - floor, atol=1e-4)  # the centre sample: under each foot


def test_curriculum_moves_by_distance_walked_against_what_was_asked(rough):
    env, _ = rough  # 2 m tiles; 100 steps of 0.02 s at 1 m/s ask for 2 m
    info = lambda walked, fell, level=1, speed=1.0, yaw_rate=0.0: {
        "spawn_xy": jnp.zeros(2), "base_xy": jnp.array([walked, 0.0]), "level": jnp.int32(level),
        "truncation": jnp.float32(0.0 if fell else 1.0), "command": jnp.array([speed, 0.0, yaw_rate]),
        "step": jnp.int32(100)}
    level = lambda *args, **kw: int(env.carry(info(*args, **kw))["level"])
    assert level(1.5, False) == 2                    # 80% of half a tile (of the 2 m asked): up
    assert level(1.5, True) == 0                     # a fall: down
    assert level(0.7, False) == 0                    # less than half of the 2 m asked: down
    assert level(0.7, False, speed=0.5) == 1         # 70% of the 1 m asked: stays
    assert level(0.05, False, yaw_rate=np.pi) == 1   # a full circle asks for no displacement: stays
    assert level(0.0, True, level=0) == 0            # never below the easiest
    assert int(env.carry(info(1.5, False))["tile"]) == -1
    assert float(commanded_displacement(jnp.array([0.6, 0.8, 1.0]), 2.0)) == pytest.approx(2 * np.sin(1.0), rel=1e-6)
    assert float(commanded_displacement(jnp.array([0.6, 0.8, 0.0]), 2.0)) == pytest.approx(2.0, rel=1e-6)


def test_a_resumed_run_goes_on_at_each_environments_level(rough):
    env, _ = rough
    vector = VectorEnv.of(env, 4, "native", threads=1)
    assert RslVecEnv(vector, seed=0).curriculum_levels().tolist() == [0, 0, 0, 0]  # a new run: the easiest row
    saved = np.array([1, 0, 1, 1], np.int32)
    resumed = RslVecEnv(vector, seed=0, levels=saved)
    assert resumed.curriculum_levels().tolist() == saved.tolist()
    tiles = np.asarray(resumed.batch.state.info["tile"])
    assert env.terrain.difficulties[tiles].tolist() == saved.tolist()  # each plays a tile of its level


def test_held_out_and_ood_configs():
    config = RoughConfig()
    evaluation = held_out("go1-rough", config)
    assert evaluation.terrain_seed != config.terrain_seed and not evaluation.curriculum
    ood = ood_config(evaluation).randomization
    assert ood.friction == (0.1, 0.25) and ood.base_mass_offset == (4.0, 4.0) and ood.motor_strength == (0.7, 0.8)
    assert ood.push_velocity == pytest.approx(1.5 * config.randomization.push_velocity)
    with pytest.raises(ValueError, match="randomisation"):
        ood_config(object())


def test_a_fine_tune_of_the_same_task_goes_on_at_its_sources_levels(tmp_path, capsys):
    """`legged train go1-rough --init-from` a go1-rough run: every environment starts at the level the source's last
    checkpoint holds (edited here, so that dropping them would show), and the optimiser is the source's."""
    import torch

    from legged.cli import main
    from policies.checkpoints import load_rsl_checkpoint
    from policies.run_dir import RunDir

    common = ["--physics", "native", "--threads", "1", "--num-envs", "8", "--timesteps", "40",
              "--set", "ppo.num_steps_per_env=5", "--set", "ppo.num_mini_batches=2", "--set", "checkpoint_every=1",
              "--set", "ppo.actor_hidden=[32, 32]", "--set", "ppo.critic_hidden=[32, 32]",
              "--set", "env.terrain.levels=2", "--set", "env.terrain.tile_size=2.0", "--set", "env.terrain.border=1.0"]
    source, tuned = tmp_path / "source", tmp_path / "tuned"
    assert main(["train", "go1-rough", *common, "--run-dir", str(source)]) == 0
    last = RunDir(source).latest_checkpoint()
    payload = load_rsl_checkpoint(last)
    payload["curriculum_levels"] = torch.tensor([0, 1, 1, 0, 1, 1, 0, 1], dtype=torch.int32)
    torch.save(payload, last)
    capsys.readouterr()
    assert main(["train", "go1-rough", *common, "--run-dir", str(tuned), "--init-from", str(source)]) == 0
    out = capsys.readouterr().out
    assert "curriculum: from the levels of" in out and "its optimiser's moments and learning rate" in out, out
    # 5 steps of 20 s episodes end none, so each environment is still at the level it started at
    levels = load_rsl_checkpoint(RunDir(tuned).latest_checkpoint())["curriculum_levels"]
    assert levels.tolist() == [0, 1, 1, 0, 1, 1, 0, 1]
