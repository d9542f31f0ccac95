"""Steps and gaps in the floor: the planner strides over gaps the feet can cross and treats higher steps and wider
gaps as walls; the exact band of body heights when each foot has several places to stand."""

import itertools

import numpy as np
import pytest

from legged.robots import GO1
from planners import BodyChecker, HeightMaps, PlannerConfig, PlanningError, plan_path
from planners.body_check import BodyCheckConfig, step_walls, widest_band
from planners.body_planner import turn_speeds

RES = 0.05


def _corridor(step: float = 0.0, gap: float = 0.0, depth: float = 0.5) -> HeightMaps:
    """A 1.2 m wide corridor from x = -2 to 2 under a 1 m roof: the floor rises by `step` at x = 0, or a gap
    `gap` wide and `depth` deep crosses it there."""
    xs, ys = np.arange(-2.2, 2.2 + 1e-9, RES), np.arange(-0.7, 0.7 + 1e-9, RES)
    floor = np.zeros((xs.size, ys.size))
    floor[xs >= 0.0] += step
    if gap:
        floor[np.abs(xs) < gap / 2 - 1e-9] = -depth
    ceiling = floor.max() + 1.0 + np.zeros_like(floor)
    wall = (np.abs(xs[:, None]) > 2.0) | (np.abs(ys[None, :]) > 0.6)
    floor, ceiling = np.where(wall, ceiling, floor), ceiling
    return HeightMaps(floor=floor, ceiling=ceiling, resolution=RES, origin=np.array([xs[0], ys[0]]))


def _plan(maps: HeightMaps, step: float = 0.0):
    return plan_path(maps, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27 + step), GO1, PlannerConfig(planner="lattice"))


@pytest.mark.parametrize("step", [0.08, -0.08])
def test_a_step_the_robot_can_take_is_planned(step):
    plan = _plan(_corridor(step=step), step)
    assert plan.waypoints[-1][0] == pytest.approx(1.5)


@pytest.mark.parametrize("step", [0.15, -0.15])
def test_a_higher_step_is_a_wall_with_a_reason(step):
    with pytest.raises(PlanningError, match="floor edges over 0.10 m"):
        _plan(_corridor(step=step), step)


@pytest.mark.parametrize("gap", [0.1, 0.22, 0.3])
def test_a_gap_the_feet_can_stride_over_is_planned_and_no_foot_stands_in_it(gap):
    maps = _corridor(gap=gap)
    plan = _plan(maps)
    checker = BodyChecker(maps, GO1)
    assert checker.walled_cells == 0  # its rims are no walls
    fine = np.concatenate([np.linspace(a, b, 20) for a, b in zip(plan.waypoints[:-1], plan.waypoints[1:])])
    heights = checker.stance_heights(fine)
    lo, hi = GO1.body_height_range
    assert np.all((heights >= lo - 1e-6) & (heights <= hi + 1e-6))  # every foot on the floor, none in the gap


def test_a_gap_wider_than_a_stride_is_refused():
    maps = _corridor(gap=0.45)
    assert BodyChecker(maps, GO1).walled_cells > 0
    with pytest.raises(PlanningError, match="rims of gaps wider than 0.36 m"):
        _plan(maps)
    with pytest.raises(PlanningError):  # without the walls the legs alone cannot cross it either
        plan_path(maps, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27), GO1,
                  PlannerConfig(planner="lattice", body=BodyCheckConfig(step_height=None)))


def test_step_walls_leave_slopes_walls_and_shallow_dips_alone():
    xs = np.arange(0, 2, RES)
    floor = np.tile(0.4 * xs[:, None], (1, 20))  # a 22-degree slope: 2 cm per cell
    floor[:, :2] = floor[:, -2:] = 5.0  # walls either side (floor == ceiling)
    floor[20:24, 8:12] -= 0.08  # a shallow dip
    ceiling = np.where(floor >= 5.0, 5.0, 5.0)
    maps = HeightMaps(floor=floor, ceiling=ceiling, resolution=RES, origin=np.zeros(2))
    assert step_walls(maps, 0.10, 0.36)[1] == 0


def test_the_widest_band_is_that_of_the_best_places_for_the_feet():
    """Against brute force on a fine grid of heights, on random intervals (overlapping ones included, where a foot's
    places together reach farther than any one of them)."""
    rng = np.random.default_rng(0)
    n, feet, choices = 200, 4, 3
    ground = rng.uniform(0.0, 0.25, (n, feet, choices))
    ground[rng.random((n, feet, choices)) < 0.2] = np.inf  # an unavailable place
    low, high = rng.uniform(0.15, 0.3, n), rng.uniform(0.3, 0.6, n)
    z_low, z_high = widest_band(low, high, ground + 0.22, ground + 0.32)
    step = 1e-4
    z = np.arange(0.1, 0.7, step)
    inside = (ground[..., None] + 0.22 <= z) & (z <= ground[..., None] + 0.32)        # (n, feet, choices, z)
    ok = inside.any(2).all(1) & (low[:, None] <= z) & (z <= high[:, None])             # (n, z)
    for i in range(n):
        runs, best, length = ok[i], 0, 0
        for flag in runs:
            length = length + 1 if flag else 0
            best = max(best, length)
        if best == 0:
            assert z_low[i] > z_high[i]
        else:
            assert z_high[i] - z_low[i] == pytest.approx((best - 1) * step, abs=3 * step)
            assert ok[i, int(round((0.5 * (z_low[i] + z_high[i]) - 0.1) / step))]


def test_a_plan_slows_where_the_body_must_crouch():
    maps = _corridor()
    ceiling = maps.ceiling.copy()
    xs = maps.origin[0] + RES * np.arange(ceiling.shape[0])
    ceiling[(np.abs(xs) < 0.4)] = 0.33  # a low roof over 0.8 m: the body crouches under it
    low = HeightMaps(floor=np.minimum(maps.floor, ceiling), ceiling=ceiling, resolution=RES, origin=maps.origin)
    config = PlannerConfig(planner="lattice", spacing=0.2, crouch_speed=0.3)
    plan = plan_path(low, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27), GO1, config)
    x, limited = plan.waypoints[:, 0], ~np.isnan(plan.speeds)
    assert limited[np.abs(x) < 0.4].all() and not limited[np.abs(x) > 0.4 + 0.3].any()  # under the roof, not away
    np.testing.assert_array_equal(plan.speeds[limited], 0.3)
    assert (plan.waypoints[limited & (np.abs(x) < 0.4), 2] < GO1.standing_height - 0.03).all()  # they do crouch
    assert plan.to_json()["speeds"].count(None) == (~limited).sum()
    assert _plan(maps).speeds is None  # no crouch speed, no limits of the plan's own
    with pytest.raises(PlanningError, match="crouch_speed"):
        PlannerConfig(crouch_speed=0.0).validate()


def test_turn_limits_follow_the_curvature_and_hold_through_the_turn():
    # an L: 0.5 m east, then a right angle north; a straight run; a 45-degree kink between 1 m segments
    path = np.array([[0, 0], [0.5, 0], [0.5, 0.5], [0.5, 1.0], [0.5, 1.5], [1.2071, 2.2071]], float)
    path = np.concatenate([path, np.zeros((len(path), 4))], axis=1)
    limits = turn_speeds(path, accel=1.0)
    assert np.isinf(limits[0]) and np.isinf(limits[3])  # the start; a waypoint after straight segments
    assert limits[1] == pytest.approx(np.sqrt(0.5 / (np.pi / 2)))  # 90 degrees over 0.5 m segments
    assert limits[2] == pytest.approx(limits[1])  # the limit holds as the body leaves the turn
    kink = np.sqrt(0.5 * (0.5 + 1.0) / (np.pi / 4))
    assert limits[4] == pytest.approx(kink, rel=1e-3) and limits[5] == pytest.approx(kink, rel=1e-3)
    assert np.all(np.isinf(turn_speeds(path[:2], 1.0)))  # two waypoints: no turn
    assert turn_speeds(path, accel=4.0)[1] == pytest.approx(2 * limits[1])  # four times the grip, twice the speed


def test_a_plan_slows_in_its_turns_and_the_limits_combine():
    maps = _corridor()
    block = maps.floor.copy()
    xs = maps.origin[0] + RES * np.arange(block.shape[0])
    ys = maps.origin[1] + RES * np.arange(block.shape[1])
    block[np.ix_(np.abs(xs) < 0.2, ys > -0.1)] = maps.ceiling.max()  # a side block: the path swerves round it
    swerve = HeightMaps(floor=block, ceiling=maps.ceiling, resolution=RES, origin=maps.origin)
    plan = plan_path(swerve, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27), GO1,
                     PlannerConfig(planner="lattice", spacing=0.2, turn_accel=1.0))
    limited = ~np.isnan(plan.speeds)
    assert limited.any() and np.all(plan.speeds[limited] > 0)
    np.testing.assert_allclose(plan.speeds, np.where(limited, turn_speeds(plan.waypoints, 1.0), np.nan))
    both = plan_path(swerve, (-1.5, 0.0, 0.27), (1.5, 0.0, 0.27), GO1,
                     PlannerConfig(planner="lattice", spacing=0.2, turn_accel=1.0, crouch_speed=0.01))
    assert np.nanmin(both.speeds) <= np.nanmin(plan.speeds)
    with pytest.raises(PlanningError, match="turn_accel"):
        PlannerConfig(turn_accel=-1.0).validate()
