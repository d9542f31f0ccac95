"""Narrow passages: body height, roll and pitch derived from the gap (pose bands), the lattice search for
narrow corridors, and the fixed benchmark scenes, checked against the body checker and MuJoCo collisions."""

from pathlib import Path

import mujoco
import numpy as np
import pytest

from legged.robots import GO1
from legged.worlds import generate_world
from legged.worlds.scenes import read_scene
from planners import (BodyChecker, HeightMaps, PlannerConfig, PlanningError, maps_from_scene, navigation_maps,
                      plan_path, reference_between)
from planners.body_check import BodyCheckConfig, rotation_rpy
from planners.body_planner import planner_key
from planners.narrow_scenes import block, narrow_scenes, tunnel_xml
from planners.pose_band import PoseBands
from tests.planner_support import probe_penetration, with_probe_box


def _scene(name):
    scene = next(s for s in narrow_scenes(GO1) if s.name == name)
    model = mujoco.MjModel.from_xml_string(scene.xml)
    return scene, maps_from_scene(model, reference_between(np.array(scene.start), np.array(scene.goal)), 0.025)


def test_bands_are_exact_for_the_body_checker():
    """The middle of every band passes the checker, and just beyond either end of it does not."""
    world = generate_world(5, 2)
    checker = BodyChecker(HeightMaps.from_world(world), GO1)
    bands = PoseBands(checker, np.radians(15), np.radians(15))
    rng = np.random.default_rng(0)
    lo, hi = world.origin + 0.05, world.origin + np.array(world.size) - 0.05  # walls included
    xy_yaw = np.column_stack([rng.uniform(lo[0], hi[0], 400), rng.uniform(lo[1], hi[1], 400), rng.uniform(-3, 3, 400)])
    poses, ok = bands.project(xy_yaw)
    assert 20 < ok.sum() < 400  # some fit, some do not (walls)
    assert checker.valid(poses[ok]).all()
    low, high = bands.band(xy_yaw[ok], poses[ok, 3], poses[ok, 4])
    for z in (low - 1e-3, high + 1e-3):
        assert not checker.valid(np.column_stack([poses[ok, :2], z, poses[ok, 3:]])).any()


@pytest.mark.parametrize("name", ["bar-1mm", "gap-45cm", "bar-gap-3mm-43cm"])
def test_narrow_scenes_are_solved_collision_free_by_mujoco(name):
    """A 1 mm band of body heights under a bar and a gap 13 cm wider than the legs' rectangle are found; MuJoCo's
    collision check finds no waypoint of the body box inside the scene."""
    scene, maps = _scene(name)
    plan = plan_path(maps, scene.start, scene.goal, GO1, PlannerConfig(spacing=0.1))
    probe = with_probe_box(scene.xml, GO1.body_box_half_extents)
    data = mujoco.MjData(probe)
    assert max(probe_penetration(probe, data, pose) for pose in plan.waypoints) < 1e-4
    roof = plan.waypoints[len(plan.waypoints) // 2] + [0, 0, 0.4, 0, 0, 0]
    assert probe_penetration(probe, data, roof) > 0.01  # the probe does collide
    if name.startswith("bar"):
        assert plan.waypoints[:, 2].min() < GO1.body_height_range[0] + 0.01  # it crouched to its lowest


def test_a_gap_narrower_than_the_robot_is_reported_as_no_path_by_the_lattice():
    xml = tunnel_xml([block(GO1, 0.25, 0.0)])
    maps = maps_from_scene(mujoco.MjModel.from_xml_string(xml), 0.27, 0.025)
    with pytest.raises(PlanningError, match="lattice search .* found none"):
        plan_path(maps, (-1.5, 0, 0.27), (1.5, 0, 0.27), GO1, PlannerConfig(planner="lattice"))


def test_planner_names_and_spaces():
    assert planner_key("Lattice") == "lattice" and planner_key("AUTO") == "auto"
    with pytest.raises(PlanningError, match="space must be"):
        PlannerConfig(space="polar").validate()
    world = generate_world(0, 0)
    with pytest.raises(PlanningError, match="projected space"):
        plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, PlannerConfig(planner="lattice", space="full"))


def test_replans_with_one_checker_reuse_its_lattice(monkeypatch):
    """The lattice of a checker is built once: a second plan on it (a replan) does not filter the maps again
    and finds the path a fresh checker finds."""
    import planners.lattice as lattice
    scene, maps = _scene(narrow_scenes(GO1)[-1].name)
    config = PlannerConfig(planner="lattice")
    checker = BodyChecker(maps, GO1, config.body)
    built = []
    real = lattice.valid_grid
    monkeypatch.setattr(lattice, "valid_grid", lambda c: built.append(c) or real(c))
    first = plan_path(maps, scene.start, scene.goal, GO1, config, checker)
    again = plan_path(maps, scene.start, scene.goal, GO1, config, checker)
    fresh = plan_path(maps, scene.start, scene.goal, GO1, config, BodyChecker(maps, GO1, config.body))
    assert len(built) == 2  # the first checker's lattice and the fresh one's
    np.testing.assert_array_equal(again.waypoints, first.waypoints)
    np.testing.assert_array_equal(fresh.waypoints, first.waypoints)


def _legs_probe(checker: BodyChecker, pose) -> np.ndarray:
    """The pose of a box covering the legs' rectangle of a body at `pose` (its centre moved to the rectangle's)."""
    x0, y0, x1, y1, depth = checker.leg_rectangle
    rot = rotation_rpy(*pose[3:6])
    centre = np.asarray(pose[:3]) + rot @ np.array([(x0 + x1) / 2, (y0 + y1) / 2, depth])
    return np.concatenate([centre, pose[3:6]])


def test_the_legs_keep_clear_of_a_block_the_trunk_would_pass():
    """Just past a block, a body whose trunk box clears it but whose hind legs would stand in it is refused with
    its own reason (and passes when the legs are not checked)."""
    xml = tunnel_xml([block(GO1, 0.6, -0.6, 1.0)])  # a block 0.4 m across, x -0.75 to -0.45
    maps = maps_from_scene(mujoco.MjModel.from_xml_string(xml), 0.27, 0.025)
    checker, trunk_only = BodyChecker(maps, GO1), BodyChecker(maps, GO1, BodyCheckConfig(leg_margin=None))
    x0, y0, x1, y1, _ = checker.leg_rectangle
    assert x0 < -GO1.body_box_half_extents[0] - 0.05 and y1 > GO1.body_box_half_extents[1] + 0.05
    past = np.array([-0.45 + GO1.body_box_half_extents[0] + 0.05, 0.1, 0.27, 0.0, 0.0, 0.0])  # trunk 3 cm past
    assert trunk_only.violation(past) is None
    assert checker.violation(past) == "the legs hit an obstacle beside the body"


def test_a_slalom_is_planned_with_the_legs_clear_of_its_blocks_by_mujoco():
    """Through the benchmark's slalom of side blocks (an MJCF of boxes), MuJoCo's collision check finds the legs'
    rectangle of no waypoint in a block, where the plan that checks the trunk alone cuts the blocks' corners."""
    path = Path(__file__).parents[1] / "assets" / "scenes" / "side-blocks.xml"
    model, scene = read_scene(path)
    maps = navigation_maps(model, scene.start, scene.goal, 0.025)
    checker = BodyChecker(maps, GO1)
    x0, y0, x1, y1, _ = checker.leg_rectangle
    probe = with_probe_box(path.read_text(), ((x1 - x0) / 2, (y1 - y0) / 2, 0.005))
    data = mujoco.MjData(probe)
    def deepest(config):
        plan = plan_path(maps, scene.start, scene.goal, GO1, PlannerConfig(spacing=0.05, body=config))
        return max(probe_penetration(probe, data, _legs_probe(checker, pose)) for pose in plan.waypoints)
    assert deepest(BodyCheckConfig()) < 1e-4
    assert deepest(BodyCheckConfig(leg_margin=None)) > 0.02


def test_a_corridor_the_legs_fit_only_lengthwise_has_a_lattice_and_a_plan():
    """In a corridor 0.5 m wide the legs' rectangle (0.44 m long) fits at no cell across it: the lattice has no node
    at those headings and is still built, and the path runs along the corridor."""
    import planners.lattice as lattice
    res = 0.05
    xs, ys = np.arange(-2.0, 2.0 + 1e-9, res), np.arange(-0.4, 0.4 + 1e-9, res)
    wall = (np.abs(xs[:, None]) > 1.8) | (np.abs(ys[None, :]) > 0.25 + 1e-9)
    ceiling = np.ones((xs.size, ys.size))
    maps = HeightMaps(floor=np.where(wall, 1.0, 0.0), ceiling=ceiling, resolution=res, origin=np.array([xs[0], ys[0]]))
    checker = BodyChecker(maps, GO1)
    valid = lattice.valid_grid(checker)
    across = lattice.YAW_BINS // 4
    assert valid[0].any() and not valid[across].any()
    plan = plan_path(maps, (-1.4, 0.0, 0.27), (1.4, 0.0, 0.27), GO1, PlannerConfig(planner="lattice"), checker)
    assert np.abs(plan.waypoints[:, 1]).max() < 0.05 and checker.valid(plan.waypoints).all()


def test_waypoints_are_states_the_motion_check_visited():
    """RRTConnect's path through a zigzag of blocks is split into waypoints at states its motion check visited: each
    has a feasible body pose (a split between them found none here once: 'internal: a waypoint between validated
    states ...')."""
    xml = tunnel_xml([block(GO1, 0.6, -0.6, 1.0), block(GO1, 0.6, 0.6, -1.0)])
    maps = maps_from_scene(mujoco.MjModel.from_xml_string(xml), 0.27, 0.025)
    config = PlannerConfig(planner="rrtconnect", spacing=0.05, body=BodyCheckConfig(leg_margin=None))
    plan = plan_path(maps, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27), GO1, config)
    assert BodyChecker(maps, GO1, config.body).valid(plan.waypoints).all()
    assert np.linalg.norm(np.diff(plan.waypoints[:, :3], axis=0), axis=1).max() <= 0.05 + 1e-9
