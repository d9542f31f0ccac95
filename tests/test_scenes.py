"""The navigation benchmark's scenes: the committed files are the code's, each is a usable navigation (start and
goal on the floor, free, inside its map), the maps read what the primitives build, and bad scene files fail in one
line naming the cause."""

from pathlib import Path

import mujoco
import numpy as np
import pytest

from legged.worlds.bench_scenes import build
from legged.worlds.scenes import BODY_Z, SceneError, read_scene, scene_files, write_scenes
from planners import navigation_maps

SCENES = Path(__file__).resolve().parents[1] / "assets" / "scenes"


def test_committed_scenes_are_the_codes():
    built = {s.name: s for s in build()}
    files = scene_files(SCENES)
    assert sorted(p.stem for p in files) == sorted(built) and len(built) >= 12
    for path in files:
        assert path.read_text() == built[path.stem].xml, f"{path} differs from legged.worlds.bench_scenes: rewrite it " \
                                                          "with `legged scenes --out assets/scenes`"


@pytest.fixture(scope="module")
def maps():
    out = {}
    for path in scene_files(SCENES):
        model, scene = read_scene(path)
        out[scene.name] = (model, scene, navigation_maps(model, scene.start, scene.goal, 0.05))
    return out


def _at(maps, x, y, which="floor"):
    grid = getattr(maps, which)
    i, j = np.round((np.array([x, y]) - np.asarray(maps.origin)[:2]) / maps.resolution).astype(int)
    return float(grid[i, j])


def test_every_scene_is_a_navigation_with_room_at_both_ends(maps):
    for name, (model, scene, m) in maps.items():
        assert scene.time_limit_s >= 2 * np.linalg.norm(np.subtract(scene.goal, scene.start)[:2]) / 1.0, name
        for where in (scene.start, scene.goal):
            floor, ceiling = _at(m, *where[:2]), _at(m, *where[:2], "ceiling")
            assert where[2] == pytest.approx(floor + BODY_Z, abs=0.011), (name, where, floor)  # on the floor
            assert ceiling - floor > 0.45, (name, where)  # standing room (the maps are dilated by a cell)
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        assert model.ngeom >= 1 and np.isfinite(data.geom_xpos).all()


def test_maps_read_the_primitives(maps):
    _, _, corridor = maps["corridor-w100-roof50"]
    assert _at(corridor, 2.5, 0.0, "ceiling") == pytest.approx(0.50, abs=1e-6)   # the roof's underside
    assert _at(corridor, 2.5, 0.55) > 1.0                                          # a wall: no way past it
    _, _, crawl = maps["crawl-roof34"]
    assert _at(crawl, 2.5, 0.0, "ceiling") == pytest.approx(0.34, abs=1e-6)
    _, _, voids = maps["voids"]
    assert _at(voids, 1.0, 0.0) == pytest.approx(0.0, abs=1e-6)
    assert min(_at(voids, x, 0.0) for x in np.arange(3.2, 3.45, 0.05)) < -0.4        # the 22 cm gap, 0.5 m deep
    _, _, ramp = maps["ramp-up"]
    assert _at(ramp, 3.0, 0.0) == pytest.approx(0.10, abs=0.051)                  # the plateau (dilated a cell)
    _, scene, sky = maps["open-sky"]
    assert np.isinf(sky.ceiling).all() or (sky.ceiling > 1.5).all()                # open sky has no roof
    lo, hi = np.asarray(sky.origin)[:2], np.asarray(sky.origin)[:2] + sky.resolution * (np.array(sky.floor.shape) - 1)
    assert (lo <= np.array(scene.start[:2]) - 0.9).all() and (hi >= np.array(scene.goal[:2]) + 0.9).all()


def test_bad_scene_files_name_the_cause(tmp_path):
    cases = {"not_mjcf.xml": ("hello", "not an MJCF file"),
             "broken.xml": ("<mujoco><worldbody><geom type='box'/></worldbody>", "cannot load scene"),
             "no_start.xml": ("<mujoco><worldbody><geom type='plane' size='0 0 1'/><site name='goal'/></worldbody></mujoco>",
                              "no site named 'start'"),
             "no_limit.xml": ("<mujoco><worldbody><geom type='plane' size='0 0 1'/><site name='start'/><site name='goal'/>"
                              "</worldbody></mujoco>", "time_limit_s")}
    for name, (text, message) in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(SceneError, match=message):
            read_scene(tmp_path / name)
    with pytest.raises(SceneError, match="not found"):
        read_scene(tmp_path / "missing.xml")
    assert write_scenes(tmp_path / "empty", []) == []
    with pytest.raises(SceneError, match="holds no scene files"):
        scene_files(tmp_path / "empty")


def test_a_scene_row_pools_speeds_and_times_at_the_limit():
    from policies.nav_bench import scene_row

    scene = build()[0]
    report = lambda ok, t, speeds, falls=0: {
        "success": ok, "time_to_goal_s": t if ok else None, "path_length_m": 5.0, "speeds_mps": np.asarray(speeds),
        "collisions": 1, "falls": falls, "replans": 2, "plan_time_s": 0.1}
    row = scene_row(scene, [report(True, 6.0, [1.0] * 19 + [2.0]), report(True, 10.0, [0.5] * 20),
                            report(False, None, [0.0] * 20, falls=1)], speed=1.0)
    assert (row["successes"], row["episodes"], row["outcomes"]) == (2, 3, ["goal", "goal", "fell"])
    assert row["time_to_goal_s"] == 8.0 and row["time_vs_path_at_speed"] == pytest.approx(1.6)  # 8 s for 5 m at 1 m/s
    assert row["mean_speed_mps"] == pytest.approx((19 + 2 + 10) / 60, abs=1e-3)
    assert row["p95_speed_mps"] == pytest.approx(1.0) and row["falls_per_episode"] == pytest.approx(1 / 3, abs=1e-3)
