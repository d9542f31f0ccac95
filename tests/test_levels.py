"""Level worlds d0-d4: reproducibility, what each level holds, clearance, free ends, MJCF agreement, planning."""

import functools
import hashlib
import math

import mujoco
import numpy as np
import pytest

from legged.robots import GO1
from legged.worlds import Terrain, WorldConfig, WorldError, compile_scene, generate_world
from legged.worlds.levels import LEVELS, LevelConfig, generate_level, level_layout, make_world
from tests.planner_support import ray_heights

CFG = LevelConfig()
SEEDS = range(20)
"""Seeds of the distribution checks: 20 worlds per level."""


@functools.cache
def _world(seed, level):
    return generate_level(seed, level)


@functools.cache
def _layout(seed, level):
    return level_layout(seed, level)


def _free(world):
    return world.ceiling - world.floor > 1e-6


def _cell_value(world, array, xy):
    i, j = world.cell_of(xy)
    return float(array[i, j])


def _heading(layout, s):
    return layout.point(s + 1e-3) - layout.point(s - 1e-3)


def _first(level, predicate):
    """The first seed whose layout at `level` satisfies `predicate`."""
    return next(seed for seed in range(200) if predicate(_layout(seed, level)))


@pytest.mark.parametrize("level", LEVELS)
def test_same_inputs_same_world(level):
    a, b = generate_level(11, level), generate_level(11, level)
    for name in ("floor", "ceiling", "origin", "start", "goal"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.difficulty == level and a.seed == 11
    other = generate_level(12, level)
    assert a.shape != other.shape or not np.array_equal(a.floor, other.floor) or not np.array_equal(a.ceiling,
                                                                                                    other.ceiling)
    if level == 0:
        tunnel = generate_world(11, 11 % 3)
        assert np.array_equal(a.floor, tunnel.floor) and np.array_equal(a.ceiling, tunnel.ceiling)


def test_make_world_terrain_and_errors():
    tunnels = WorldConfig()
    old, new = make_world(5, 2, tunnels, None), generate_world(5, 2, tunnels)
    assert np.array_equal(old.floor, new.floor) and old.difficulty == 2
    assert np.array_equal(make_world(5, 3, tunnels, CFG).floor, generate_level(5, 3).floor)
    with pytest.raises(WorldError, match="level must be one of 0, 1, 2, 3, 4, got 5"):
        make_world(0, 5, tunnels, CFG)
    with pytest.raises(WorldError, match="level must be one of"):
        generate_level(0, -1)
    with pytest.raises(WorldError, match="min_clearance"):
        generate_level(0, 1, LevelConfig(crawl_roof=(0.25, 0.3)))
    terrain = Terrain.generate(3, 1, (0, 1, 2))  # without levels: today's tunnels
    tiled = Terrain.from_worlds([generate_world(100_003 + k, k) for k in range(3)])
    assert np.array_equal(terrain.floor, tiled.floor) and np.array_equal(terrain.ceiling, tiled.ceiling)
    terrain = Terrain.generate(5, 1, (0, 1, 2, 3, 4), levels=CFG)
    assert terrain.difficulties.tolist() == [0, 1, 2, 3, 4]
    tiled = Terrain.from_worlds([generate_level(100_003 + k, k) for k in range(5)])
    assert np.array_equal(terrain.floor, tiled.floor) and np.allclose(terrain.goals, tiled.goals)


def test_level1_corridors_roofs_and_crawl_sections():
    layouts = [_layout(s, 1) for s in SEEDS]
    widths = np.array([lay.width for lay in layouts])
    assert widths.min() >= 0.5 and widths.max() <= 2.0 and widths.min() < 0.8 and widths.max() > 1.7
    assert all(3.0 <= lay.length <= 6.0 and not lay.bends and set(lay.kinds()) <= {"crawl"} for lay in layouts)
    roofs = [lay.roof for lay in layouts]
    assert any(r is None for r in roofs) and all(0.4 <= r <= 1.0 for r in roofs if r is not None)
    crawls = [f for lay in layouts for f in lay.features]
    assert 0 < len(crawls) < len(layouts)
    assert all(0.5 <= f.end - f.begin <= 1.5 and 0.30 <= f.value <= 0.40 for f in crawls)
    for seed, lay in zip(SEEDS, layouts):
        w = _world(seed, 1)
        assert np.all(w.floor[_free(w)] == 0.0)
        i, j = w.cell_of(w.start)
        across = (np.count_nonzero(_free(w)[i]) - 1) * w.resolution  # from the first to the last free sample
        assert lay.width - 2 * w.resolution < across <= lay.width + 1e-9
        sky = CFG.open_sky if lay.roof is None else lay.roof
        assert np.isclose(w.ceiling.max(), sky)
        gap = w.min_clearance
        assert np.isclose(gap, lay.features[0].value if lay.features else sky, atol=1e-6)


def test_level2_obstacles():
    layouts = [_layout(s, 2) for s in SEEDS]
    kinds = {k for lay in layouts for k in lay.kinds()}
    assert {"bar", "block", "pillars"} <= kinds <= {"bar", "block", "pillars", "crawl"}
    for seed, lay in zip(SEEDS, layouts):
        w = _world(seed, 2)
        obstacles = [f for f in lay.features if f.kind != "crawl"]
        assert 1 <= len(obstacles) <= 4
        for f in obstacles:
            mid = lay.point((f.begin + f.end) / 2)
            if f.kind == "bar":
                assert 0.05 - 1e-9 <= f.end - f.begin <= 0.2 and 0.36 <= f.value <= 0.45
                assert np.isclose(_cell_value(w, w.ceiling, mid), f.value)  # the roof drops across the corridor
            elif f.kind == "block":
                assert lay.width >= 0.9 and f.value >= 0.45
                (s, v, _, half_v, _), = f.solids
                assert abs(v) + half_v >= lay.width / 2 + CFG.wall_thickness - 1e-9  # it starts at a wall
                assert lay.width / 2 - (abs(v) - half_v) >= 0.45 - 1e-9  # and leaves the gap to the other one
                i, j = w.cell_of(mid)
                assert (np.count_nonzero(_free(w)[i]) - 1) * w.resolution >= f.value - 2 * w.resolution
                assert np.count_nonzero(~_free(w)[i]) > np.count_nonzero(~_free(w)[w.cell_of(w.start)[0]])
            else:
                assert lay.width >= 1.2 and 2 <= len(f.solids) <= 5
                for k, (s, v, half, _, rnd) in enumerate(f.solids):
                    assert 0.1 <= 2 * half <= 0.25 and abs(v) + half <= lay.width / 2 - 0.45 + 1e-9
                    assert _cell_value(w, w.ceiling, lay.point(s) + v * np.array([0.0, 1.0])) == w.ceiling.max()
                    for s2, v2, half2, _, rnd2 in f.solids[k + 1:]:
                        reach = (half if rnd else half * math.sqrt(2)) + (half2 if rnd2 else half2 * math.sqrt(2))
                        assert math.hypot(s - s2, v - v2) - reach >= 0.45 - 1e-9


SLALOM = LevelConfig(block_group=(2, 3))


def test_block_groups_are_slaloms_from_alternate_walls():
    groups = [f for seed in range(200) for f in level_layout(seed, 2, SLALOM).features if f.kind == "block"]
    assert {len(f.solids) for f in groups} == {1, 2, 3}  # blocks that find no room are left out
    for seed in range(40):
        lay = level_layout(seed, 2, SLALOM)
        world = generate_level(seed, 2, SLALOM)
        for f in (f for f in lay.features if f.kind == "block"):
            sides = [math.copysign(1.0, v) for _, v, _, _, _ in f.solids]
            assert all(a == -b for a, b in zip(sides, sides[1:]))  # each from the wall opposite the one before
            gaps = [lay.width / 2 + abs(v) - hv for _, v, _, hv, _ in f.solids]
            assert min(gaps) >= 0.45 - 1e-9 and np.isclose(f.value, min(gaps))
            assert all(abs(v) + hv >= lay.width / 2 + CFG.wall_thickness - 1e-9 for _, v, _, hv, _ in f.solids)
            centres = [sc for sc, _, _, _, _ in f.solids]
            assert all(1.0 - 1e-9 <= b - a <= 1.6 + 1e-9 for a, b in zip(centres, centres[1:]))
            assert np.isclose(f.begin, centres[0] - f.solids[0][2]) and np.isclose(f.end, centres[-1] + f.solids[-1][2])
            for sc, v, _, _, _ in f.solids:  # each block is solid in the maps, its gap free
                side = math.copysign(1.0, v)
                block = lay.point(sc) + side * (lay.width / 2 - 0.1) * _left(lay, sc)
                gap = lay.point(sc) - side * (lay.width / 2 - 0.1) * _left(lay, sc)
                assert _cell_value(world, world.floor, block) == _cell_value(world, world.ceiling, block)
                assert _cell_value(world, world.ceiling, gap) > _cell_value(world, world.floor, gap)
    single = [level_layout(seed, 2) for seed in range(40)]  # the default: one block, the worlds of older runs
    assert all(len(f.solids) == 1 for lay in single for f in lay.features if f.kind == "block")
    with pytest.raises(WorldError, match="block_pitch"):
        LevelConfig(block_group=(1, 3), block_pitch=(0.5, 1.0)).validate()


BEND_BLOCKS = LevelConfig(bend_blocks=1.0)


def test_bend_blocks_sit_against_the_bends():
    """With bend_blocks 1, a corridor wide enough for blocks gets one ending where a bend's zone begins and one
    beginning where it ends (where they fit), solid in the maps; 0 draws the worlds of older runs, bit for bit."""
    against = 0
    for seed in range(60):
        lay = level_layout(seed, 3, BEND_BLOCKS)
        if not lay.bends or lay.width < CFG.block_corridor_width:
            continue
        blocks = [f for f in lay.features if f.kind == "block"]
        corners = np.cumsum(np.linalg.norm(np.diff(lay.centre_line, axis=0), axis=1))[:-1] - lay.end_margin
        for s_bend, angle in zip(corners, lay.bends):
            zone = lay.width / 2 * math.tan(math.radians(abs(angle)) / 2) + 0.1
            against += sum(np.isclose(f.end, s_bend - zone) or np.isclose(f.begin, s_bend + zone) for f in blocks)
        if seed < 20:
            world = generate_level(seed, 3, BEND_BLOCKS)
            for sc, v, _, _, _ in (solid for f in blocks for solid in f.solids):
                cell = lay.point(sc) + math.copysign(1.0, v) * (lay.width / 2 - 0.1) * _left(lay, sc)
                assert _cell_value(world, world.floor, cell) == _cell_value(world, world.ceiling, cell)
    assert against >= 20
    digest = hashlib.sha256()
    for seed in range(8):  # the default (0): the level 3 and 4 maps of the generator before bend_blocks
        for level in (3, 4):
            w = generate_level(seed, level)
            digest.update(np.ascontiguousarray(w.floor).tobytes() + np.ascontiguousarray(w.ceiling).tobytes())
    assert digest.hexdigest()[:16] == "85f52ca3e30ff725"
    with pytest.raises(WorldError, match="bend_blocks"):
        LevelConfig(bend_blocks=1.5).validate()


def _left(layout, s):
    """Unit vector to the left of the route at arc length s."""
    d = _heading(layout, s)
    return np.array([-d[1], d[0]]) / np.linalg.norm(d)


def test_level3_steps_ramps_and_turns():
    layouts = [_layout(s, 3) for s in SEEDS]
    kinds = {k for lay in layouts for k in lay.kinds()}
    assert {"step", "ramp"} <= kinds and {len(lay.bends) for lay in layouts} == {0, 1, 2}
    for seed, lay in zip(SEEDS, layouts):
        w = _world(seed, 3)
        assert all(30.0 <= abs(b) <= 90.0 for b in lay.bends)
        if len(lay.bends) == 2:
            assert lay.bends[0] * lay.bends[1] < 0  # an S: opposite bends
        for f in lay.features:
            if f.kind == "step":
                assert 0.03 <= abs(f.value) <= 0.10
                before, after = lay.point(f.begin - 0.1), lay.point(f.begin + 0.1)
                assert np.isclose(_cell_value(w, w.floor, after) - _cell_value(w, w.floor, before), f.value, atol=1e-6)
            elif f.kind == "ramp":
                slope = math.degrees(math.atan2(abs(f.value), f.end - f.begin))
                assert 5.0 - 1e-6 <= slope <= 15.0 + 1e-6 and 0.03 <= abs(f.value) <= 0.10
        assert np.isclose(w.goal[2] - CFG.body_height, lay.floor_level(lay.length))
        assert np.allclose(w.goal[:2], lay.point(lay.length)) and np.allclose(w.start[:2], 0.0)


def test_level4_voids():
    layouts = [_layout(s, 4) for s in SEEDS]
    for seed, lay in zip(SEEDS, layouts):
        w = _world(seed, 4)
        voids = [f for f in lay.features if f.kind == "void"]
        assert 1 <= len(voids) <= 2
        for f in voids:
            assert 0.10 <= f.end - f.begin <= 0.25 and 0.1 <= f.value <= 1.0
            level = float(lay.floor_level((f.begin + f.end) / 2))
            assert np.isclose(_cell_value(w, w.floor, lay.point((f.begin + f.end) / 2)), level - f.value, atol=1e-6)
            for s in (f.begin - 0.06, f.end + 0.06):
                assert np.isclose(_cell_value(w, w.floor, lay.point(s)), level, atol=1e-6)
            # the gap spans the corridor: every free sample across the void's centre row is lowered
            i, j = w.cell_of(lay.point((f.begin + f.end) / 2))
            if abs(_heading(lay, f.begin)[1]) < 1e-9:  # rows lie across a leg along x
                assert np.all(w.floor[i][_free(w)[i]] < level - 0.1 + 1e-6)
    depths = [f.value for lay in layouts for f in lay.features if f.kind == "void"]
    assert min(depths) < 0.3 and max(depths) > 0.7


@pytest.mark.parametrize("level", [1, 2, 3, 4])
def test_clearance_walls_spacing_and_compact_maps(level):
    for seed in SEEDS:
        w, lay = _world(seed, level), _layout(seed, level)
        free = _free(w)
        top = float(w.ceiling.max())
        assert w.clearance[free].min() >= CFG.min_clearance - 1e-6
        assert np.all(w.floor[~free] == top) and np.all(w.ceiling[~free] == top)
        assert not free[0].any() and not free[-1].any() and not free[:, 0].any() and not free[:, -1].any()
        spans = sorted((f.begin, f.end) for f in lay.features)
        assert all(a >= CFG.free_radius and b <= lay.length - CFG.free_radius for a, b in spans)
        assert all(begin - end >= CFG.feature_spacing - 1e-9 for (_, end), (begin, _) in zip(spans, spans[1:]))
        box = np.ptp(lay.centre_line, axis=0) + lay.width + 2 * CFG.wall_thickness + 2 * w.resolution
        assert np.all(np.array(w.size) <= box + 1e-9)
        if not lay.bends:  # straight: the map ends at the walls behind start and goal
            assert w.size[0] <= lay.length + 2 * (CFG.end_margin + CFG.wall_thickness + w.resolution) + 1e-9


@pytest.mark.parametrize("level", [1, 2, 3, 4])
def test_start_and_goal_on_flat_free_ground(level):
    for seed in SEEDS:
        w, lay = _world(seed, level), _layout(seed, level)
        xs = w.origin[0] + w.resolution * np.arange(w.shape[0])
        ys = w.origin[1] + w.resolution * np.arange(w.shape[1])
        for point, s in ((w.start, 0.0), (w.goal, lay.length)):
            floor = float(lay.floor_level(s))
            assert np.isclose(point[2], floor + CFG.body_height)
            dx, dy = xs[:, None] - point[0], ys[None, :] - point[1]
            near = np.hypot(dx, dy) < CFG.free_radius
            assert np.all(w.floor[near & _free(w)] == np.float32(floor))
            assert w.clearance[near & _free(w)].min() >= CFG.roof[0] - 1e-6  # no crawl roof or bar there
            heading = _heading(lay, s) / np.linalg.norm(_heading(lay, s))
            along, across = dx * heading[0] + dy * heading[1], -dx * heading[1] + dy * heading[0]
            body = (np.abs(along) <= 0.21) & (np.abs(across) <= 0.07)
            assert np.all(_free(w)[body])


MJCF_WORLDS = [(4, lambda lay: {"bar", "void"} <= set(lay.kinds())),
               (3, lambda lay: {"step", "block"} <= set(lay.kinds()) and lay.bends),
               (2, lambda lay: "pillars" in lay.kinds() and lay.roof is None)]
"""(level, which world) of the MJCF checks: a bar and a void; a step and a side block on a turning route; pillars
under open sky."""


@pytest.mark.parametrize("case", range(len(MJCF_WORLDS)))
def test_mjcf_agrees_with_maps(case):
    level, predicate = MJCF_WORLDS[case]
    seed = _first(level, predicate)
    world, lay = _world(seed, level), _layout(seed, level)
    terrain = Terrain.from_worlds([world])
    model = compile_scene(terrain, GO1)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)

    def sample(xy):  # the nearest map sample: inside every void and under every bar
        return terrain.origin + terrain.resolution * np.array(world.cell_of(xy))

    probes = [sample(lay.point((f.begin + f.end) / 2)) for f in lay.features]
    rng = np.random.default_rng(seed)
    points = probes + [lay.point(f.begin + 0.02) for f in lay.features]
    points += list(rng.uniform(terrain.origin, terrain.upper, (300, 2)))
    rays = {}
    for k, xy in enumerate(points):
        floor, ceiling = float(terrain.floor_at(xy)), float(terrain.ceiling_at(xy))
        if ceiling - floor < 0.02:
            continue  # inside a wall or a column
        rays[k] = ray_heights(model, data, xy, (floor + ceiling) / 2)
        assert abs(rays[k][0] - floor) < 1e-4 and abs(rays[k][1] - ceiling) < 1e-4, xy
    assert len(rays) >= 40
    for k, f in enumerate(lay.features):
        level_z = float(lay.floor_level((f.begin + f.end) / 2))
        if f.kind == "void":
            assert rays[k][0] < level_z - f.value + 1e-4
        elif f.kind == "bar":
            assert rays[k][1] < level_z + f.value + 1e-4


PLANNED = [(1, lambda lay: "crawl" in lay.kinds() and lay.width < 0.8), (1, lambda lay: lay.roof is None),
           (2, lambda lay: "pillars" in lay.kinds()), (2, lambda lay: "block" in lay.kinds()),
           (3, lambda lay: len(lay.bends) == 2 and lay.width < 1.0),
           (3, lambda lay: len(lay.bends) == 1 and "step" in lay.kinds())]
"""(level, which world) of the planning checks: a narrow crawl and open sky, pillars and a side block, a narrow S
and an L with a step (level 0: seeds 0 and 1)."""


@pytest.mark.parametrize("case", [(0, 0), (0, 1)] + [(level, k) for k, (level, _) in enumerate(PLANNED)])
def test_planner_finds_paths_at_levels_0_to_3(case, tmp_path):
    from planners.batch import plan_world
    from planners.body_planner import Plan

    level, k = case
    seed = k if level == 0 else _first(level, PLANNED[k][1])
    result, _ = plan_world(generate_level(seed, level), cache_dir=tmp_path)
    assert isinstance(result, Plan), f"level {level} seed {seed}: {result}"
