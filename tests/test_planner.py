"""OMPL body-pose planner: paths are collision-free by MuJoCo's own collision detection, errors are clear."""

import json

import mujoco
import numpy as np
import pytest

from legged.cli import main
from legged.envs.math import roll_pitch
from legged.robots import GO1
from legged.sensors.heightscan import surface_height
from legged.worlds import Terrain, generate_world, scene_xml
from legged.worlds.mjcf import CEILING_GEOM, FLOOR_GEOM
from planners import (BodyChecker, HeightMaps, PlannerConfig, PlanningError, maps_from_scene, plan_path,
                      reference_between, replan)
from planners.body_check import quat_rpy, rotation_rpy
from tests.planner_support import BOX_TUNNEL, probe_penetration, with_probe_box

WORLD = (0, 1)
"""(seed, difficulty) of the generated world most tests plan through (RRTConnect solves it in ~0.1 s)."""
TOUCH_M = 1e-4
"""Largest penetration MuJoCo may report for a pose we call collision-free (its contacts start at 0)."""


@pytest.fixture(scope="module")
def world():
    return generate_world(*WORLD)


@pytest.fixture(scope="module")
def world_plan(world):
    return plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, PlannerConfig(spacing=0.25))


def _probe_model(world):
    xml = scene_xml(Terrain.from_worlds([world]), GO1)
    return with_probe_box(xml, GO1.body_box_half_extents, surfaces=[FLOOR_GEOM, CEILING_GEOM])


def test_lookup_and_rotation_conventions_match_the_environments(world):
    maps = HeightMaps.from_world(world)
    xy = np.random.default_rng(0).uniform(maps.origin, maps.upper, (500, 2))
    np.testing.assert_allclose(maps.lookup(xy), surface_height(world.floor, world.origin, world.resolution, xy),
                               atol=1e-6)
    np.testing.assert_allclose(maps.lookup(xy, ceiling=True), surface_height(
        world.ceiling, world.origin, world.resolution, xy, anti_diagonal=True), atol=1e-6)
    assert np.isnan(maps.lookup(np.array([[maps.upper[0] + 0.1, 0.0]])))[0]
    roll, pitch, yaw = 0.2, -0.15, 1.0
    rot = rotation_rpy(roll, pitch, yaw)
    np.testing.assert_allclose(np.array(roll_pitch(rot)), [roll, pitch], atol=1e-6)
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, quat_rpy(roll, pitch, yaw))
    np.testing.assert_allclose(mat.reshape(3, 3), rot, atol=1e-9)


def test_planned_path_is_collision_free_by_mujoco(world, world_plan):
    model = _probe_model(world)
    data = mujoco.MjData(model)
    waypoints = world_plan.waypoints
    assert len(waypoints) >= 2
    np.testing.assert_allclose(waypoints[0, :3], world.start, atol=1e-9)
    np.testing.assert_allclose(waypoints[-1, :3], world.goal, atol=1e-9)
    steps = np.linalg.norm(np.diff(waypoints[:, :3], axis=0), axis=1)
    assert steps.max() <= 0.25 + 1e-6
    assert world_plan.length_m == pytest.approx(steps.sum())
    assert world_plan.length_m >= np.linalg.norm(world.goal - world.start) - 1e-9
    for pose in waypoints:
        assert probe_penetration(model, data, pose) <= TOUCH_M, pose
    heights = BodyChecker(HeightMaps.from_world(world), GO1).stance_heights(waypoints)
    lo, hi = GO1.body_height_range
    assert heights.min() >= lo - 1e-9 and heights.max() <= hi + 1e-9
    # The same check does see a collision: lift a waypoint into the ceiling.
    lifted = waypoints[len(waypoints) // 2] + np.array([0, 0, 0.3, 0, 0, 0])
    assert probe_penetration(model, data, lifted) > 0.01


def test_same_seed_same_path_and_result_fields(world, world_plan):
    again = plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, PlannerConfig(spacing=0.25))
    np.testing.assert_array_equal(again.waypoints, world_plan.waypoints)
    assert world_plan.planner == "rrtconnect" and world_plan.plan_time_s > 0
    raw = [plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1,
                     PlannerConfig(spacing=0.25, seed=seed, simplify=False)).waypoints for seed in (0, 7)]
    assert raw[0].shape != raw[1].shape or not np.allclose(raw[0], raw[1])  # the seed drives the sampling


def test_wall_across_the_tunnel_is_reported_as_no_path(world):
    maps = HeightMaps.from_world(world)
    i = maps.floor.shape[0] // 2
    floor = maps.floor.copy()
    floor[i - 2:i + 2, :] = maps.ceiling[i - 2:i + 2, :]  # solid rock from wall to wall
    blocked = HeightMaps(floor=floor, ceiling=maps.ceiling, resolution=maps.resolution, origin=maps.origin,
                         ceiling_anti_diagonal=True)
    with pytest.raises(PlanningError, match="no collision-free path .* within 0.5 s"):
        plan_path(blocked, world.start, world.goal, GO1, PlannerConfig(planner="rrtconnect", time_limit=0.5))
    with pytest.raises(PlanningError, match="no collision-free path .* the lattice search .* found none"):
        plan_path(blocked, world.start, world.goal, GO1)  # auto: complete, so "blocked" is certain


def test_bad_start_and_goal_say_which(world):
    maps = HeightMaps.from_world(world)
    with pytest.raises(PlanningError, match="start pose .* hits the ceiling"):
        plan_path(maps, world.start + [0, 0, 0.2], world.goal, GO1)
    with pytest.raises(PlanningError, match="goal .* lies outside the map"):
        plan_path(maps, world.start, world.goal + [10.0, 0, 0], GO1)
    with pytest.raises(PlanningError, match="start pose .* legs cannot hold the body"):
        plan_path(maps, world.start - [0, 0, 0.1], world.goal, GO1)
    with pytest.raises(PlanningError, match="unknown planner 'astar'"):
        plan_path(maps, world.start, world.goal, GO1, PlannerConfig(planner="astar"))
    with pytest.raises(PlanningError, match="max_checks must be >= 0"):
        plan_path(maps, world.start, world.goal, GO1, PlannerConfig(max_checks=-1))


@pytest.mark.parametrize("name", ["RRT*", "BIT*", "AORRTC"])
def test_optimal_planners_by_name(name):
    # An open corridor; the search is bounded by a count of motion checks (the 60 s limit is only a ceiling), so
    # that it is the same search on a slow or busy machine (a 0.5 s limit once failed RRT* on a loaded CI runner).
    floor = np.zeros((61, 21))
    maps = HeightMaps(floor=floor, ceiling=floor + 0.5, resolution=0.05, origin=np.array([-1.5, -0.5]))
    config = PlannerConfig(planner=name, time_limit=60.0, max_checks=400)
    plan = plan_path(maps, [-1.0, 0.0, 0.27], [1.0, 0.0, 0.27], GO1, config)
    assert plan.planner == name.lower().replace("*", "star")
    assert np.all(BodyChecker(maps, GO1).valid(plan.waypoints))
    assert plan.length_m < 2.2


def test_replan_from_a_measured_pose_returns_the_rest(world, world_plan):
    maps = HeightMaps.from_world(world)
    middle = world_plan.waypoints[len(world_plan.waypoints) // 2].copy()
    measured = middle + np.array([0.02, -0.01, -0.03, 0.3, 0.0, 0.2])  # crouched, rolled beyond the limit
    rest = replan(maps, measured, world.goal, GO1, PlannerConfig(spacing=0.25))
    assert np.linalg.norm(rest.waypoints[0, :2] - measured[:2]) <= 0.1 * np.sqrt(2) + 1e-9
    np.testing.assert_allclose(rest.waypoints[-1, :3], world.goal, atol=1e-9)
    assert abs(rest.waypoints[0, 3]) <= PlannerConfig().max_roll + 1e-9
    assert rest.length_m < world_plan.length_m


def test_box_tunnel_scene_sampled_by_rays_is_planned_collision_free():
    model = mujoco.MjModel.from_xml_string(BOX_TUNNEL)
    start, goal = np.array([-2.0, 0.0, 0.27]), np.array([2.0, 0.0, 0.27])
    maps = maps_from_scene(model, reference_between(start, goal), resolution=0.05)
    assert maps.floor.shape == (101, 41)  # the scene's extent, 5 m x 2 m
    assert maps.floor_at(np.array([-0.8, 0.25])) == pytest.approx(0.04)  # the step
    assert maps.ceiling_at(np.array([0.3, 0.0])) == pytest.approx(0.34)  # under the beam
    assert maps.ceiling_at(np.array([1.0, 0.0])) == pytest.approx(0.6)  # the decorative sphere is ignored
    assert maps.ceiling_at(np.array([1.5, 0.0])) == pytest.approx(0.42)  # under the mesh slab
    assert maps.floor_at(np.array([0.0, 0.52])) >= maps.ceiling_at(np.array([0.0, 0.52]))  # a wall: no gap
    plan = plan_path(maps, start, goal, GO1, PlannerConfig(spacing=0.1))
    probe = with_probe_box(BOX_TUNNEL, GO1.body_box_half_extents)
    data = mujoco.MjData(probe)
    for pose in plan.waypoints:
        assert probe_penetration(probe, data, pose) <= TOUCH_M, pose
    assert probe_penetration(probe, data, plan.waypoints[len(plan.waypoints) // 2] + [0, 0, 0.4, 0, 0, 0]) > 0.01  # the roof
    under_beam = plan.waypoints[np.abs(plan.waypoints[:, 0] - 0.3) < 0.15]
    assert len(under_beam) and under_beam[:, 2].max() < 0.265  # it crouches under the 0.34 m beam


def test_generated_world_xml_sampled_by_rays_matches_its_maps(world, tmp_path):
    from legged.worlds import write_world

    files = write_world(world, GO1, tmp_path)
    model = mujoco.MjModel.from_xml_path(files["xml"])
    lo, hi = world.origin, world.origin + world.resolution * (np.array(world.shape) - 1)
    maps = maps_from_scene(model, world.start[2], world.resolution, bounds=(lo, hi), dilate=False)
    free = world.clearance > 0.01
    np.testing.assert_allclose(maps.floor[free], world.floor[free], atol=1e-4)
    np.testing.assert_allclose(maps.ceiling[free], world.ceiling[free], atol=1e-4)


def test_cli_plan_prints_json_and_fails_clearly(capsys, tmp_path):
    assert main(["plan", "--seed", str(WORLD[0]), "--difficulty", str(WORLD[1]), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"waypoints", "length_m", "plan_time_s", "planner"}
    assert len(out["waypoints"][0]) == 6 and out["planner"] == "rrtconnect"
    scene = tmp_path / "tunnel.xml"
    scene.write_text(BOX_TUNNEL)
    assert main(["plan", "--scene", str(scene), "--start", "-2,0,0.27", "--goal", "2,0,0.9", "--json"]) == 2
    assert "goal pose" in capsys.readouterr().err
    assert main(["plan", "--scene", str(tmp_path / "missing.xml"), "--start", "0,0,0.27", "--goal", "1,0,0.27"]) == 2
    assert "scene file not found" in capsys.readouterr().err
