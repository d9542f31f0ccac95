"""Where a head camera sees the ball and the goals: a colour-and-depth detector on the camera's own images.

A RoboCup player finds the ball and the goals in its image by their colours and places them with the camera's
pose; this is that detector, for the images the vision players get. A pixel is an object's when its colour is a
shade of the object's (the renderer scales a surface's colour by its lighting, so its pixels are s * rgb for a
shade s), and its depth places it on the ray through the pixel. The ball's centre lies behind the mean of its
surface points by two thirds of its radius along the line of sight (the mean depth of a sphere's visible cap over
its disc); a goal is seen by its net (tinted by its team's colour), placed at the mean of the net's visible points
(up to the goal's depth behind the goal mouth's centre, and to one side when only part of it is in view).
The camera's pose relative to the torso's heading frame is what the head's joint angles and an IMU's roll and
pitch give (forward kinematics): in simulation it is read from the camera's world pose and the torso's.

`sighting` gives [seen, x, y, z]: seen is 1 when any pixel is the object's, then its place in the torso's heading
frame (x forward, y left, z up, metres, as the state players' `ball` feature), zeros when unseen.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from legged.envs.math import yaw_rotate

SIGHTING_SIZE = 4
"""Length of a sighting: seen (0 or 1), then x, y, z of the object in the heading frame."""

SIGHTED = ("ball", "own_goal", "opponent_goal")
"""What a vision player's state sights (`vision_sightings`), in order."""

COLOUR_TOLERANCE = 0.06
"""Largest distance (RGB in [0, 1]) of an object's pixel from the nearest shade of the object's colour."""

BALL_MIN_SHADE = 0.15
"""Darkest shade of the ball's colour counted (darker pixels carry too little colour to tell)."""

NET_MIN_SHADE = 0.45
"""Darkest shade of a net's colour counted: the nets' colours are near grey, and the robots' dark grey parts are
shades of them up to 0.35 (a net lit by the ambient light alone, at a grazing angle, is missed)."""


def colour_mask(rgb, colour, min_shade: float) -> jnp.ndarray:
    """Which pixels show an object of `colour` ([3] or per camera [n, 3], RGB in [0, 1]), [n, P] bool, from RGB
    [n, P, 3] uint8: a shade s * colour within COLOUR_TOLERANCE, s at least `min_shade`."""
    colour = jnp.broadcast_to(jnp.asarray(colour, jnp.float32), (rgb.shape[0], 3))[:, None, :]
    pixels = rgb.astype(jnp.float32) / 255.0
    shade = jnp.sum(pixels * colour, -1) / jnp.sum(colour * colour, -1)
    off = jnp.linalg.norm(pixels - shade[..., None] * colour, axis=-1)
    return (shade >= min_shade) & (off <= COLOUR_TOLERANCE)


def pixel_points(depth, dirs, max_depth: float) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(every pixel's point in its camera's frame [n, P, 3], whether it lies within `max_depth` [n, P]) from z-depth
    [n, H, W] (metres) and the pixels' unit rays in the camera frame [n, H * W, 3] (RayCamera.dirs): computed once
    per image for every object `sighting` looks for. Jittable."""
    depth = depth.reshape(depth.shape[0], -1)
    dirs = jnp.asarray(dirs)
    return dirs * (depth / -dirs[..., 2])[..., None], depth < max_depth


def sighting(rgb, points, in_range, cam_pos, cam_rot, torso_pos, torso_yaw, colour, min_shade: float,
             behind: float) -> jnp.ndarray:
    """[n, SIGHTING_SIZE] for n cameras: rgb [n, H, W, 3] uint8, the pixels' points and depth range (`pixel_points`),
    cam_pos [n, 3] and cam_rot [n, 3, 3] (world from camera), torso_pos [n, 3] and torso_yaw [n] of each camera's
    robot; the object's `colour` ([3] or [n, 3]), the darkest shade of it counted (`colour_mask`), and how far its
    centre lies behind the mean of its visible points along the line of sight (`behind`, metres: 2/3 of a ball's
    radius). Jittable."""
    n = rgb.shape[0]
    mask = colour_mask(rgb.reshape(n, -1, 3), colour, min_shade) & in_range
    count = jnp.sum(mask, -1)
    seen = count > 0
    surface = jnp.sum(points * mask[..., None], 1) / jnp.maximum(count, 1)[:, None]
    sight = surface / jnp.maximum(jnp.linalg.norm(surface, axis=-1, keepdims=True), 1e-6)
    centre = surface + behind * sight
    world = cam_pos + jnp.einsum("nij,nj->ni", cam_rot, centre)
    rel = world - torso_pos
    local = jnp.concatenate([yaw_rotate(torso_yaw, rel[:, :2]), rel[:, 2:]], -1)
    return jnp.where(seen[:, None], jnp.concatenate([jnp.ones((n, 1)), local], -1), 0.0).astype(jnp.float32)


def camera_agents(camera_ids: np.ndarray, head_cameras: np.ndarray) -> np.ndarray:
    """The agent whose head carries each camera of `camera_ids`, from the layout's head camera of each agent."""
    where = {int(c): a for a, c in enumerate(np.asarray(head_cameras))}
    missing = [int(c) for c in camera_ids if int(c) not in where]
    if missing:
        raise ValueError(f"cameras {missing} are no robot's head camera: sightings need head cameras")
    return np.array([where[int(c)] for c in camera_ids], dtype=np.int32)
