"""A vision player's tracker of its own place on the pitch and of the ball: odometry, goal nets and ball sightings.

A RoboCup player keeps its pose on the pitch by dead reckoning (the gyro's yaw rate, the walking command's
velocity) corrected by the landmarks it sees, and keeps the ball where it last saw it; it knows the pitch (where
the goals stand), its kick-off spot and when play restarts from the kick-off (the referee's whistle). This is
that tracker, an extended Kalman filter over the torso's ground pose (x, y, yaw) in the world:

- predict, every control period: yaw advances by the gyro's rate about the vertical, x and y by the walker's
  filtered velocity command (measured over 5 s: 0.15 m of drift with the true yaw, 0.03 rad of yaw);
- correct with each goal net the camera sights (legged.soccer.vision.sightings: the mean of the net's visible points,
  in the heading frame), modelled as the centre of the goal's back net: well placed along the pitch, up to half
  the goal's width off across it; a sighting too far from the prediction (a false one) is ignored;
- lock on: a game starts with the robot near its kick-off spot but turned anyhow (+-90 degrees), so the yaw is
  unknown until the opponent goal's net is first seen; its bearing then sets the yaw;
- a kick-off after a goal puts the robot back on its kick-off spot and the ball on the centre spot: both known;
- the ball: where the camera last saw it (world frame), forgotten after `memory_s` unseen (BALL_MEMORY_S); with
  `ball_motion`, a constant-velocity Kalman filter over its sightings instead (slowed by rolling), so that the
  tracker also knows the ball's velocity and a ball out of view moves on.

The state is one float vector (`TRACKER_SIZE`) per player, jittable and vmappable. `tracked_features` turns it
into the heading-frame features the placo command reads (legged.soccer.observe.game_features: ball, own goal,
opponent goal), leaving the player's own estimate where the tracker knows nothing (before it locks on, a ball
not seen lately).
"""

from __future__ import annotations

import jax.numpy as jnp

from legged.envs.math import yaw_rotate

TRACKER_SIZE = 22
"""x, y, yaw (3), the pose's covariance (9), locked on (1), the ball's world x, y (2), ball known (1), seconds
since the ball was last seen (1), the ball's world velocity (2), the ball filter's covariance (3: position,
position-velocity, velocity; the same along x and y)."""

START_STD = (0.29, 0.29, 0.9)
"""Standard deviation of the pose at a game's start around the kick-off pose (m, m, rad): the spawn's uniform
+-0.5 m and +-90 degrees."""

LOCK_YAW_STD = 0.15
"""Standard deviation of the yaw set by the first sighting of the opponent goal's net (rad): the position's
uncertainty and the net's width seen from about 3.5 m."""

DRIFT_STD_PER_S = (0.19, 0.19, 0.063)
"""Growth of the pose's standard deviation per square root of a second while walking (m, m, rad), from the
odometry's measured drift."""

GETTING_UP_DRIFT = 10.0
"""The drift is this many times larger while the robot falls or gets up (its walking command says nothing then)."""

NET_ALONG_STD = 0.06
"""Standard deviation of a net sighting along the pitch (m): the net's back stands at the goal's depth."""

NET_ACROSS_FRACTION = 0.275
"""Standard deviation of a net sighting across the pitch as a fraction of the goal's width (the camera may see
only a part of the net)."""

GATE = 25.0
"""A sighting whose squared Mahalanobis distance from the prediction exceeds this is ignored (once locked on)."""

BALL_MEMORY_S = 1.0
"""The ball is kept where it was last seen this long by default (seconds; SoccerConfig.vision_ball_memory_s); after
that the player's own estimate is used."""

BALL_SIGHT_STD = 0.03
"""Standard deviation of a ball sighting placed on the pitch (m; the detector's 0.026 m RMS near the player)."""

BALL_ACCEL_STD = 1.0
"""Standard deviation of the ball's unmodelled acceleration between kicks (m/s^2), the filter's process noise."""

BALL_KICK_GATE = 16.0
"""A ball sighting whose squared distance from the prediction exceeds this many times its variance was kicked: the
filter's velocity is then uncertain again (BALL_FIRST_VEL_STD) before the correction."""

BALL_FIRST_VEL_STD = 0.5
"""Standard deviation of the ball's velocity when a track starts (m/s; it is taken to be still)."""

BALL_DECEL = 0.4
"""The rolling ball's deceleration (m/s^2) in the game's physics (tests/test_tracker.py measures it)."""


def tracker_start(kickoff) -> jnp.ndarray:
    """A tracker at a game's start: at the kick-off pose `kickoff` (x, y, yaw), its yaw not yet known."""
    cov = jnp.diag(jnp.square(jnp.asarray(START_STD, jnp.float32)))
    return _pack(jnp.asarray(kickoff, jnp.float32), cov, 0.0, jnp.zeros(2), 0.0, 0.0, jnp.zeros(2), jnp.zeros(3))


def tracker_kickoff(kickoff) -> jnp.ndarray:
    """A tracker after a kick-off restart: on its kick-off pose, known, the ball on the centre spot."""
    still = jnp.array([BALL_SIGHT_STD ** 2, 0.0, 1e-4])  # on the centre spot, still
    return _pack(jnp.asarray(kickoff, jnp.float32), jnp.eye(3) * 1e-4, 1.0, jnp.zeros(2), 1.0, 0.0, jnp.zeros(2), still)


def tracker_step(tracker, velocity, yaw_rate, getting_up, dt: float, ball_motion: bool = False) -> jnp.ndarray:
    """Predict one control period on: `velocity` (vx, vy) the walker's command in the heading frame (m/s),
    `yaw_rate` (rad/s) the gyro's rate about the vertical; with `ball_motion` the ball rolls on."""
    pose, cov, locked, ball, known, age, ball_vel, ball_cov = _unpack(tracker)
    yaw = pose[2]
    move = yaw_rotate(-yaw, velocity) * dt
    jacobian = jnp.eye(3).at[:2, 2].set(yaw_rotate(-yaw, jnp.stack([-velocity[1], velocity[0]])) * dt)
    drift = jnp.square(jnp.asarray(DRIFT_STD_PER_S)) * dt * jnp.where(getting_up, GETTING_UP_DRIFT ** 2, 1.0)
    cov = jacobian @ cov @ jacobian.T + jnp.diag(drift)
    pose = pose + jnp.concatenate([move, yaw_rate[None] * dt])
    if ball_motion:
        ball, ball_vel, ball_cov = _ball_predict(ball, ball_vel, ball_cov, dt)
    return _pack(pose, cov, locked, ball, known, age + dt, ball_vel, ball_cov)


def tracker_sight(tracker, sightings, net_centres, goal_width: float, ball_motion: bool = False) -> jnp.ndarray:
    """Correct with one control period's `sightings` [3, 4] (ball, own goal's net, opponent goal's net: seen, x,
    y, z in the heading frame; legged.soccer.vision.sightings) and the world x, y [2, 2] of the own and opponent goal's
    back-net centres; with `ball_motion` a ball sighting corrects the ball's filter (`BALL_MEMORY_S` after its
    last sighting, it starts a new track, the ball still)."""
    pose, cov, locked, ball, known, age, ball_vel, ball_cov = _unpack(tracker)
    net_centres = jnp.asarray(net_centres, jnp.float32)
    opponent = sightings[2]
    lock = (locked < 0.5) & (opponent[0] > 0.5)
    to_net = net_centres[1] - pose[:2]
    lock_yaw = jnp.arctan2(to_net[1], to_net[0]) - jnp.arctan2(opponent[2], opponent[1])
    locked_cov = cov.at[2, :].set(0.0).at[:, 2].set(0.0).at[2, 2].set(LOCK_YAW_STD ** 2)
    pose = jnp.where(lock, pose.at[2].set(lock_yaw), pose)
    cov = jnp.where(lock, locked_cov, cov)
    locked = jnp.where(lock, 1.0, locked)
    known = jnp.where(lock, 0.0, known)  # a ball placed before the yaw was known is misplaced
    across = (NET_ACROSS_FRACTION * goal_width) ** 2
    for k in (1, 2):
        pose, cov = _net_update(pose, cov, sightings[k], net_centres[k - 1], locked > 0.5, across)
    seen = sightings[0, 0] > 0.5
    sighted = pose[:2] + yaw_rotate(-pose[2], sightings[0, 1:3])
    if ball_motion:
        follow = seen & (known > 0.5) & (age <= BALL_MEMORY_S)
        tracked = _ball_correct(ball, ball_vel, ball_cov, sighted)
        first = (sighted, jnp.zeros(2), jnp.array([BALL_SIGHT_STD ** 2, 0.0, BALL_FIRST_VEL_STD ** 2]))
        ball, ball_vel, ball_cov = (jnp.where(follow, t, jnp.where(seen, f, now))
                                    for t, f, now in zip(tracked, first, (ball, ball_vel, ball_cov)))
    else:
        ball = jnp.where(seen, sighted, ball)
    return _pack(pose, cov, locked, ball, jnp.where(seen, 1.0, known), jnp.where(seen, 0.0, age), ball_vel, ball_cov)


def tracked_features(tracker, estimate, ball: slice, own_goal: slice, opponent_goal: slice, own_xy,
                     opponent_xy, memory_s: float = BALL_MEMORY_S, ball_vel: slice | None = None) -> jnp.ndarray:
    """The game features `estimate` (a player's own estimate, heading frame) with what the tracker knows put in:
    both goals' centres (`own_xy`, `opponent_xy`, world) once locked on, the ball's x, y if seen within
    `memory_s` seconds, and then its velocity's x, y at `ball_vel` if given (a tracker with `ball_motion`)."""
    on, own, opponent, fresh, ball_ego = _known(tracker, own_xy, opponent_xy, memory_s)
    estimate = estimate.at[own_goal].set(jnp.where(on, own, estimate[own_goal]))
    estimate = estimate.at[opponent_goal].set(jnp.where(on, opponent, estimate[opponent_goal]))
    xy = slice(ball.start, ball.start + 2)
    estimate = estimate.at[xy].set(jnp.where(fresh, ball_ego, estimate[xy]))
    if ball_vel is None:
        return estimate
    pose, *_, world_vel, _ = _unpack(tracker)
    xy = slice(ball_vel.start, ball_vel.start + 2)
    return estimate.at[xy].set(jnp.where(fresh, yaw_rotate(pose[2], world_vel), estimate[xy]))


TRACKER_INPUT_SIZE = 8
"""Length of `tracker_inputs`."""


def tracker_inputs(tracker, own_xy, opponent_xy, memory_s: float = BALL_MEMORY_S) -> jnp.ndarray:
    """What the tracker knows as a network's inputs [TRACKER_INPUT_SIZE], in the heading frame: locked on (0/1),
    the own and opponent goals' centres (`own_xy`, `opponent_xy`, world; zeros before it locks on), the ball
    fresh (0/1: seen within `memory_s` seconds, once locked on) and its x, y (zeros unless fresh)."""
    on, own, opponent, fresh, ball_ego = _known(tracker, own_xy, opponent_xy, memory_s)
    on, fresh = on.astype(jnp.float32), fresh.astype(jnp.float32)
    return jnp.concatenate([on[None], on * own, on * opponent, fresh[None], fresh * ball_ego])


def tracked_pose(tracker) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(the tracked pose x, y, yaw, whether the tracker is locked on)."""
    pose, _, locked, *_ = _unpack(tracker)
    return pose, locked > 0.5


def _known(tracker, own_xy, opponent_xy, memory_s: float):
    """(locked on, the own and opponent goals' centres in the heading frame, the ball fresh: seen within
    `memory_s` seconds once locked on, the ball in the heading frame) of a tracker."""
    pose, _, locked, ball_xy, known, age, *_ = _unpack(tracker)
    ego = lambda xy: yaw_rotate(pose[2], jnp.asarray(xy, jnp.float32) - pose[:2])
    on = locked > 0.5
    return on, ego(own_xy), ego(opponent_xy), on & (known > 0.5) & (age <= memory_s), ego(ball_xy)


def _net_update(pose, cov, sight, centre, locked, across: float):
    """One extended-Kalman correction of (pose, cov) by a net sighting [4] of the back net centred at `centre`."""
    rel = centre - pose[:2]
    predicted = yaw_rotate(pose[2], rel)
    c, s = jnp.cos(pose[2]), jnp.sin(pose[2])
    world_to_ego = jnp.array([[c, s], [-s, c]])
    d_yaw = jnp.array([[-s, c], [-c, -s]]) @ rel
    h = jnp.concatenate([-world_to_ego, d_yaw[:, None]], axis=1)
    noise = world_to_ego @ jnp.diag(jnp.array([NET_ALONG_STD ** 2, across])) @ world_to_ego.T
    innovation_cov = h @ cov @ h.T + noise
    residual = sight[1:3] - predicted
    distance = residual @ jnp.linalg.solve(innovation_cov, residual)
    gain = cov @ h.T @ jnp.linalg.inv(innovation_cov)
    use = locked & (sight[0] > 0.5) & (distance < GATE)
    return (jnp.where(use, pose + gain @ residual, pose),
            jnp.where(use, (jnp.eye(3) - gain @ h) @ cov, cov))


def _ball_predict(ball, ball_vel, ball_cov, dt: float):
    """The ball's filter one period on: it rolls at its velocity, slowed by BALL_DECEL; its covariance grows by a
    white acceleration of BALL_ACCEL_STD."""
    speed = jnp.linalg.norm(ball_vel)
    slowed = ball_vel * jnp.maximum(0.0, 1.0 - BALL_DECEL * dt / jnp.maximum(speed, 1e-6))
    pp, pv, vv = ball_cov[0], ball_cov[1], ball_cov[2]
    q = BALL_ACCEL_STD ** 2
    cov = jnp.stack([pp + 2 * dt * pv + dt * dt * vv + q * dt ** 4 / 4, pv + dt * vv + q * dt ** 3 / 2,
                     vv + q * dt * dt])
    return ball + ball_vel * dt, slowed, cov


def _ball_correct(ball, ball_vel, ball_cov, sighted):
    """The ball's filter corrected by a sighting at world x, y `sighted` (after a kick, BALL_KICK_GATE, with its
    velocity uncertain again)."""
    residual = sighted - ball
    pp, pv, vv = ball_cov[0], ball_cov[1], ball_cov[2]
    kicked = jnp.sum(residual ** 2) > BALL_KICK_GATE * (pp + BALL_SIGHT_STD ** 2)
    pp = jnp.where(kicked, pp + jnp.sum(residual ** 2) / 2, pp)
    vv = jnp.where(kicked, vv + BALL_FIRST_VEL_STD ** 2, vv)
    innovation = pp + BALL_SIGHT_STD ** 2
    gain_p, gain_v = pp / innovation, pv / innovation
    cov = jnp.stack([(1 - gain_p) * pp, (1 - gain_p) * pv, vv - gain_v * pv])
    return ball + gain_p * residual, ball_vel + gain_v * residual, cov


def _pack(pose, cov, locked, ball, known, age, ball_vel, ball_cov) -> jnp.ndarray:
    scalars = jnp.stack([jnp.asarray(locked, jnp.float32)])
    return jnp.concatenate([pose, cov.reshape(9), scalars, ball, jnp.stack([jnp.asarray(known, jnp.float32),
                                                                           jnp.asarray(age, jnp.float32)]),
                            jnp.asarray(ball_vel, jnp.float32), jnp.asarray(ball_cov, jnp.float32)])


def _unpack(tracker):
    """(pose, its covariance, locked, ball x, y, ball known, its age, ball velocity, the ball filter's covariance)."""
    return (tracker[:3], tracker[3:12].reshape(3, 3), tracker[12], tracker[13:15], tracker[15], tracker[16],
            tracker[17:19], tracker[19:22])
