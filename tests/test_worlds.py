"""World generator: reproducibility, clearance bounds, free start/goal, files and errors."""

import json

import mujoco
import numpy as np
import pytest

from legged.cli import main
from legged.robots import GO1
from legged.worlds import Terrain, World, WorldConfig, WorldError, generate_world


@pytest.mark.parametrize("difficulty", [0, 1, 2, 4])
def test_same_seed_same_world_and_lengths(difficulty):
    a, b = generate_world(7, difficulty), generate_world(7, difficulty)
    assert np.array_equal(a.floor, b.floor) and np.array_equal(a.ceiling, b.ceiling)
    assert np.array_equal(a.start, b.start) and np.array_equal(a.goal, b.goal)
    cfg = WorldConfig()
    assert np.isclose(a.goal[0] - a.start[0], 2 * cfg.endpoint_fraction * cfg.length(difficulty))
    assert not np.array_equal(a.ceiling, generate_world(8, difficulty).ceiling)


@pytest.mark.parametrize("seed", range(12))
def test_clearance_bounds_and_free_endpoints(seed):
    cfg = WorldConfig()
    w = generate_world(seed, seed % 3, cfg)
    assert w.resolution == cfg.resolution
    free = w.clearance > 1e-6
    assert w.clearance[free].min() >= cfg.min_clearance - 1e-6
    assert w.ceiling.max() <= cfg.ceiling_nominal + 1e-6
    drop = cfg.ceiling_nominal - w.ceiling[free]
    assert drop.max() <= cfg.ceiling_pyramid_height[1] + 1e-6
    assert drop.max() > 0.05, "ceiling pyramids must be present"
    for point in (w.start, w.goal):
        i, j = w.cell_of(point)
        box_top = point[2] + GO1.body_box_half_extents[2]
        r = int(np.ceil(0.25 / w.resolution))
        patch = (slice(i - r, i + r + 1), slice(j - r, j + r + 1))
        assert w.floor[patch].max() < point[2] - GO1.body_box_half_extents[2]
        assert w.ceiling[patch].min() > box_top


def test_save_load_roundtrip_and_errors(tmp_path):
    w = generate_world(3, 1)
    back = World.load(w.save(tmp_path / "w.npz"))
    assert np.array_equal(back.floor, w.floor) and back.summary() == w.summary()
    with pytest.raises(WorldError, match="not found"):
        World.load(tmp_path / "missing.npz")
    np.savez(tmp_path / "bad.npz", floor=np.zeros((3, 3)))
    with pytest.raises(WorldError, match="lacks arrays"):
        World.load(tmp_path / "bad.npz")
    with pytest.raises(WorldError, match="difficulty"):
        generate_world(0, -1)
    with pytest.raises(WorldError, match="min_clearance"):
        generate_world(0, 0, WorldConfig(min_clearance=0.9))


def test_tiling_keeps_each_world(tmp_path):
    worlds = [generate_world(s, s % 3) for s in range(5)]
    t = Terrain.from_worlds(worlds)
    assert t.num_tiles == 5
    for w, start in zip(worlds, t.starts):
        i = np.rint((start[:2] - t.origin) / t.resolution).astype(int)
        k = np.rint((w.start[:2] - w.origin) / w.resolution).astype(int)
        assert np.isclose(t.ceiling[i[0], i[1]], w.ceiling[k[0], k[1]])


def test_cli_world_writes_npz_and_standalone_xml(tmp_path, capsys):
    assert main(["world", "--seed", "5", "--difficulty", "2", "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    data = np.load(tmp_path / "world.npz")
    for key in ("floor", "ceiling", "resolution", "origin", "start", "goal"):
        assert key in data.files
    assert summary["start"] == [round(v, 4) for v in data["start"].tolist()]
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "world.xml"))
    d = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, d, 0)
    mujoco.mj_forward(model, d)
    assert np.allclose(d.xpos[model.body("trunk").id][:2], data["start"][:2], atol=1e-3)


def test_cli_reports_unwritable_output(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["world", "--out", str(blocker / "sub")]) == 2
    assert "cannot create output directory" in capsys.readouterr().err
