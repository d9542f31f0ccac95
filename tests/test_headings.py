"""Waypoint headings that face the way of travel (planners.headings, `PlannerConfig.face_travel`): where the turned
body fits and its motions pass, it faces the path; elsewhere the searched heading stays."""

import math

import mujoco
import numpy as np
import pytest

from legged.robots import GO1
from planners import BodyChecker, PlannerConfig, PlanningError, maps_from_scene, plan_path
from planners.headings import face_travel, travel_headings
from planners.narrow_scenes import block, tunnel_xml
from tests.planner_support import probe_penetration, with_probe_box


def _wrapped(angle):
    return (np.asarray(angle) + math.pi) % (2 * math.pi) - math.pi


def test_travel_headings_face_the_path_over_a_window():
    """Through an L: along x until half a window before the corner, halfway round at it, along y from half a window
    after it, turning steadily between (within half a window of the start and the goal the path counts as going on
    along the start-goal line); a 0.45 m sidestep back to the centre line before the goal turns the body
    less than half as far as the sidestep's own direction (0.80 rad); a path that does not move keeps its headings."""
    leg = np.arange(0.0, 4.01, 0.25)
    path = np.zeros((2 * len(leg) - 1, 6))
    path[:, :2] = np.concatenate([np.column_stack([leg, 0 * leg]), np.column_stack([4 + 0 * leg[1:], leg[1:]])])
    headings = travel_headings(path, 1.5)
    corner = len(leg) - 1
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1))])
    ends = (s >= 0.75) & (s <= s[-1] - 0.75)
    far_before, far_after = (s <= s[corner] - 0.75) & ends, (s >= s[corner] + 0.75) & ends
    np.testing.assert_allclose(headings[far_before], 0.0, atol=1e-12)
    np.testing.assert_allclose(headings[far_after], math.pi / 2, atol=1e-12)
    assert headings[corner] == pytest.approx(math.pi / 4) and np.all(np.diff(headings[ends]) >= -1e-12)
    assert np.count_nonzero(ends & ~far_before & ~far_after) == 5  # the turn spreads over the window
    hook = np.zeros((11, 6))
    hook[:, :2] = [(0, 0), (0.21, 0.23), (0.40, 0.45), (0.84, 0.45), (1.29, 0.45), (1.73, 0.45), (2.17, 0.45),
                   (2.61, 0.45), (3.50, 0.45), (3.72, 0.23), (3.96, 0.0)]
    assert np.abs(travel_headings(hook, 1.5)).max() < 0.4
    still = np.zeros((3, 6))
    still[:, 5] = 0.3
    np.testing.assert_allclose(travel_headings(still, 1.5), 0.3)
    with pytest.raises(PlanningError, match="travel_window must be > 0"):
        PlannerConfig(face_travel=True, travel_window=0.0).validate()


class _Space:
    """A plane where a body fits at any heading except between x = 0.95 and 1.95, where it must face +x (|yaw| <= 0.1)."""

    @staticmethod
    def _fits(x, yaw):
        return ~((x >= 0.95) & (x <= 1.95) & (np.abs(yaw) > 0.1))

    def to_vector(self, pose):
        return np.array([pose[0], pose[1], pose[5]])

    def to_poses(self, vectors):
        v = np.atleast_2d(vectors)
        return np.column_stack([v[:, 0], v[:, 1], np.full(len(v), 0.3), np.zeros(len(v)), np.zeros(len(v)), v[:, 2]])

    def valid(self, vectors):
        v = np.atleast_2d(vectors)
        return self._fits(v[:, 0], v[:, 2])

    def is_valid_pose(self, poses):
        return self._fits(poses[:, 0], poses[:, 5])


def test_a_turned_waypoint_that_does_not_fit_keeps_the_searched_heading():
    """A diagonal path searched facing +x: the waypoints in the strip that needs +x keep it, and so do the ones just
    before and after it (turning between them and the strip would turn inside it); every other waypoint after the start
    faces the way of travel, the goal too unless kept; every motion passes."""
    space = _Space()
    checker = type("Checker", (), {"valid": staticmethod(space.is_valid_pose)})()
    xs = np.arange(0.0, 3.3, 0.4)
    path = space.to_poses(np.column_stack([xs, xs, np.zeros_like(xs)]))
    out = face_travel(path, space, checker, 0.01, keep_goal=False, window=1.5)
    turned = ~np.isclose(out[:, 5], 0.0)
    assert turned.tolist() == [False, True, False, False, False, False, True, True, True]
    np.testing.assert_allclose(out[turned, 5], math.pi / 4)
    np.testing.assert_array_equal(out[:, :2], path[:, :2])
    vectors = np.stack([space.to_vector(p) for p in out])
    for a, b in zip(vectors[:-1], vectors[1:]):
        assert space.valid(a + np.linspace(0, 1, 101)[:, None] * (b - a)).all()
    kept = face_travel(path, space, checker, 0.01, keep_goal=True, window=1.5)
    assert kept[-1, 5] == 0.0 and kept[-2, 5] == out[-2, 5]


def test_a_zigzag_planned_facing_the_way_of_travel_stays_clear_by_mujoco():
    """Through a tunnel with a block from each wall, the plan facing the way of travel (over a half-metre window, so
    that it turns sharply) keeps the searched positions, faces the path where the search did not, and MuJoCo finds the body box of no waypoint in a block or wall; a goal
    given as a full pose keeps its heading."""
    xml = tunnel_xml([block(GO1, 0.6, -0.6, 1.0), block(GO1, 0.6, 0.6, -1.0)])
    model = mujoco.MjModel.from_xml_string(xml)
    maps = maps_from_scene(model, 0.27, 0.025)
    checker = BodyChecker(maps, GO1)
    start, goal = (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27)
    searched = plan_path(maps, start, goal, GO1, PlannerConfig(planner="lattice", spacing=0.1), checker)
    facing = PlannerConfig(planner="lattice", spacing=0.1, face_travel=True, travel_window=0.5)  # sharp turns
    faced = plan_path(maps, start, goal, GO1, facing, checker)
    np.testing.assert_allclose(faced.waypoints[:, :2], searched.waypoints[:, :2])
    assert checker.valid(faced.waypoints).all()
    off = lambda plan: np.abs(_wrapped(plan.waypoints[1:, 5] - travel_headings(plan.waypoints, 0.5)[1:]))
    assert off(searched).max() > 0.3  # the search sidesteps the blocks facing +x
    assert np.median(off(faced)) < 1e-6 and off(faced).mean() < 0.5 * off(searched).mean()
    probe = with_probe_box(xml, GO1.body_box_half_extents)
    data = mujoco.MjData(probe)
    assert max(probe_penetration(probe, data, pose) for pose in faced.waypoints) < 1e-4
    posed = plan_path(maps, start, (*goal, 0.0, 0.0, 0.0), GO1, facing, checker)
    assert posed.waypoints[-1, 5] == 0.0
