"""Height scans equal MuJoCo's own ray casts (mj_ray) on the compiled scene, floor and ceiling."""

import mujoco
import numpy as np

from legged.sensors.heightscan import surface_height
from legged.worlds import Terrain, compile_scene, generate_world
from tests.planner_support import ray_heights
from legged.robots import GO1

TOLERANCE_M = 1e-5
"""Scan-vs-ray agreement; the height field is stored in float32, so about 1e-7 is expected."""


def test_surface_height_matches_mj_ray_on_tiled_terrain():
    terrain = Terrain.from_worlds([generate_world(s, s % 3) for s in range(4)])
    model = compile_scene(terrain, GO1)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(0)
    lo, hi = terrain.origin, terrain.origin + terrain.resolution * (np.array(terrain.shape) - 1)
    checked = 0
    for xy in rng.uniform(lo, hi, (3000, 2)):
        floor = surface_height(terrain.floor, terrain.origin, terrain.resolution, xy)
        ceiling = surface_height(terrain.ceiling, terrain.origin, terrain.resolution, xy, anti_diagonal=True)
        if ceiling - floor < 0.02:
            continue  # inside a wall: no free space to cast from
        ray_floor, ray_ceiling = ray_heights(model, data, xy, (floor + ceiling) / 2)
        assert abs(ray_floor - floor) < TOLERANCE_M, xy
        assert abs(ray_ceiling - ceiling) < TOLERANCE_M, xy
        checked += 1
    assert checked > 1000


def test_env_scans_match_mj_ray_at_scan_points(confined):
    env = confined.env
    state = confined.reset(confined.keys(3))
    data = mujoco.MjData(env.mj_model)
    mujoco.mj_forward(env.mj_model, data)
    scan_cfg = env.config.scan
    n = scan_cfg.num_points
    for b in range(2):
        qpos = np.asarray(state.pipeline_state.qpos[b])
        base, yaw = qpos[:3], 2 * np.arctan2(qpos[6], qpos[3])
        pts = scan_cfg.points()
        c, s = np.cos(yaw), np.sin(yaw)
        world = base[:2] + np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]], -1)
        obs = np.asarray(state.obs["state"][b])
        ceiling_obs, floor_obs = obs[-2 * n:-n], obs[-n:]
        for k, xy in enumerate(world):
            ray_floor, ray_ceiling = ray_heights(env.mj_model, data, xy, base[2])
            clip = scan_cfg.clip
            assert abs(np.clip(ray_floor - base[2], -clip, clip) - floor_obs[k]) < 1e-4
            assert abs(np.clip(ray_ceiling - base[2], -clip, clip) - ceiling_obs[k]) < 1e-4
