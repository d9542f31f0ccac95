"""Narrow passages: body height, roll and pitch derived from the gap (pose bands), the lattice search for
narrow corridors, and the fixed benchmark scenes, checked against the body checker and MuJoCo collisions."""

import mujoco
import numpy as np
import pytest

from legged.robots import GO1
from legged.worlds import generate_world
from planners import BodyChecker, HeightMaps, PlannerConfig, PlanningError, maps_from_scene, plan_path, reference_between
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


@pytest.mark.parametrize("name", ["bar-1mm", "gap-40cm", "bar-gap-3mm-35cm"])
def test_narrow_scenes_are_solved_collision_free_by_mujoco(name):
    """A 1 mm band of body heights under a bar and a corridor 6 cm wider than the narrowed stance are found;
    MuJoCo's collision check finds no waypoint of the body box inside the scene."""
    scene, maps = _scene(name)
    plan = plan_path(maps, scene.start, scene.goal, GO1, PlannerConfig(spacing=0.1))
    probe = with_probe_box(scene.xml, GO1.body_box_half_extents)
    data = mujoco.MjData(probe)
    assert max(probe_penetration(probe, data, pose) for pose in plan.waypoints) < 1e-4
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
