"""Waypoint headings that face the way the body travels, where the body fits that way.

The search spaces cost a turn of the body in metres of path (`PlannerConfig.angle_weight`) and nothing ties the
body's heading to its direction of travel, so the cheapest path keeps one heading throughout: through a 90-degree
turn the body walks half the path sideways, and a path that runs diagonally to the start-goal line is walked
crabwise. A legged robot walks forward best. `face_travel` gives each waypoint the heading of the path around it
(`travel_headings`: the chord of the path over a window of a few body lengths centred on the waypoint) wherever
that pose has a feasible body height, roll and pitch and the motions to its neighbours pass the same check as the
search's; elsewhere the searched heading stays. The window keeps short jogs from swinging the body: the heading of
the single segment through a waypoint turned the body 45 degrees for a 0.45 m sidestep back to the centre line
just before the goal, which the follower walked worse than the sidestep itself.
"""

from __future__ import annotations

import numpy as np

from planners.lattice import _line

MIN_MOVE = 1e-3
"""Horizontal travel (m) below which a waypoint has no direction of travel and keeps its searched heading."""


def travel_headings(waypoints: np.ndarray, window: float) -> np.ndarray:
    """Heading of the path around each waypoint (n, 6), radians: the direction of the chord between the points of the
    path `window` / 2 metres of path before and after it; beyond the start and the goal the path is taken to go on
    straight along the start-goal direction. A waypoint whose chord is shorter than MIN_MOVE keeps its own heading."""
    w = np.asarray(waypoints, float)
    xy = w[:, :2]
    if len(xy) < 2:
        return w[:, 5].copy()
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
    overall = xy[-1] - xy[0]
    length = np.linalg.norm(overall)
    direction = overall / length if length > MIN_MOVE else np.zeros(2)

    def at(q: np.ndarray) -> np.ndarray:
        inside = np.clip(q, 0.0, s[-1])
        points = np.column_stack([np.interp(inside, s, xy[:, 0]), np.interp(inside, s, xy[:, 1])])
        return points + (np.minimum(q, 0.0) + np.maximum(q - s[-1], 0.0))[:, None] * direction

    chord = at(s + window / 2) - at(s - window / 2)
    moving = np.linalg.norm(chord, axis=1) > MIN_MOVE
    return np.where(moving, np.arctan2(chord[:, 1], chord[:, 0]), w[:, 5])


def _segments_ok(space, vectors: np.ndarray, check_step: float) -> np.ndarray:
    """Whether the straight motion between each pair of consecutive states passes the space's check (n - 1,)."""
    lines = [_line(a, b, check_step) for a, b in zip(vectors[:-1], vectors[1:])]
    ok = space.valid(np.concatenate(lines))
    bounds = np.cumsum([0] + [len(line) for line in lines])
    return np.array([ok[s:e].all() for s, e in zip(bounds[:-1], bounds[1:])])


def face_travel(waypoints: np.ndarray, space, checker, check_step: float, keep_goal: bool,
                window: float) -> np.ndarray:
    """`waypoints` (n, 6), a planned path whose consecutive motions are valid, with each waypoint after the start
    turned to `travel_headings` over `window` metres where that pose and its motions to the neighbours are valid
    (height, roll and pitch from `space`, a ProjectedSpace or the full space). The start keeps its pose, the goal
    too if `keep_goal`."""
    out = np.array(waypoints, float)
    n = len(out)
    if n < 2:
        return out
    turned = out.copy()
    turned[:, 5] = travel_headings(out, window)
    vectors = np.stack([space.to_vector(p) for p in out])
    turned_vectors = np.stack([space.to_vector(p) for p in turned])
    if turned_vectors.shape[1] == 3:  # projected space: height, roll and pitch follow from x, y and heading
        turned = space.to_poses(turned_vectors)  # (the full space keeps the planned height and tilt)
    use = np.ones(n, bool)
    use[0] = False
    use[-1] &= not keep_goal
    with np.errstate(invalid="ignore"):
        use &= ~np.isnan(turned).any(axis=1)
    use[use] = checker.valid(turned[use])
    while use.any():  # a motion that fails gives its turned ends back their searched heading; the original path's pass
        current = np.where(use[:, None], turned_vectors, vectors)
        bad = np.flatnonzero(~_segments_ok(space, current, check_step))
        if not use[bad].any() and not use[bad + 1].any():  # none left to give back
            break
        use[bad] = False
        use[bad + 1] = False
    out[use] = turned[use]
    return out
