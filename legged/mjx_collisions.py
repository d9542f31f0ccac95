"""Sphere-height-field contacts in MJX that agree with MuJoCo's own.

MJX (3.17) collides a sphere with a height field prism by prism (the triangles of the field, each extruded to the
field's base), and decides each sphere-prism pair with the prisms' face normals alone. Near a steep triangle (the
edge of a void, a step, a wall of the confined worlds, whose maps drop by up to 1.5 m between two samples) no face
normal separates a sphere that floats above the edge, and the closest point it then takes is not the prism's: MJX
reports a contact 1.1-1.3 m deep with a nearly horizontal normal where MuJoCo reports none. A trunk sphere 21 cm
above the floor, passing over the rim of a 1 m void, was thrown sideways: the shipped follower fell in 44% of the
held-out d4 worlds in MJX (28% with this module) against 10% in native MuJoCo, most at the deep voids.

`install()` puts an exact test in MJX's collision table for (height field, sphere) pairs: the distance from the
sphere's centre to each prism's top triangle (the field's surface; the sides and base of its prisms lie inside it),
the depth below it for a centre within the prism, and at most four contacts per sphere, within 1 mm of the deepest,
at distinct points. Everything else about MJX's height field collisions (which prisms are tried, the flip of normals
that point into the field) stays MJX's. The project's MJX models are built through
legged.robots.models.mjx_model_of, which installs it.
"""

from __future__ import annotations

import contextlib

import jax
import jax.numpy as jnp
from mujoco.mjx._src import collision_convex, collision_driver, math
from mujoco.mjx._src.types import GeomType

MAX_CONTACTS = 4
"""Contacts one sphere may have with a height field (MJX's own number for this pair)."""

TIE = 1e-3
"""Contacts whose depth is within this of the deepest one's count (m); the others are the same surface seen from a
neighbouring triangle's edge."""

TOP = 1
"""Index of the top triangle among a height field prism's faces (mujoco.mjx._src.mesh.hfield_prism: bottom, top,
three sides)."""


def _inside(corners: jax.Array, point: jax.Array, normal: jax.Array) -> jax.Array:
    """Whether `point` lies inside the triangle `corners` seen along `normal` (either winding)."""
    side = jnp.einsum("ij,j->i", jnp.cross(jnp.roll(corners, -1, axis=0) - corners, point - corners), normal)
    return jnp.all(side >= -1e-12) | jnp.all(side <= 1e-12)


def _closest_on_triangle(corners: jax.Array, point: jax.Array, normal: jax.Array) -> jax.Array:
    """The point of the triangle `corners` (its unit `normal`) nearest to `point`."""
    on_plane = point - jnp.dot(point - corners[0], normal) * normal
    edge = jnp.roll(corners, -1, axis=0) - corners
    t = jnp.clip(jnp.sum((on_plane - corners) * edge, axis=1) / jnp.maximum(jnp.sum(edge * edge, axis=1), 1e-12),
                 0.0, 1.0)
    on_edges = corners + t[:, None] * edge
    nearest = on_edges[jnp.argmin(jnp.sum((on_edges - point) ** 2, axis=1))]
    return jnp.where(_inside(corners, on_plane, normal), on_plane, nearest)


def sphere_prism(sphere, prism) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(distance, contact point, normal from the sphere into the field) of a sphere and one prism of a height field
    (MJX's GeomInfo and ConvexInfo, in the field's frame). The field is the union of its prisms, whose sides and base
    lie inside it: its surface is the prisms' top triangles. A centre in front of this prism's top: the exact
    distance to that triangle. A centre under the top, within the prism: its depth below the top's plane. A centre
    under the top's plane beside the prism: nothing here (the prism it lies in, or the triangle it faces, answers)."""
    centre = prism.mat.T @ (sphere.pos - prism.pos)
    radius = sphere.size[0]
    corners, top = prism.face[TOP, :3], prism.face_normal[TOP]
    ahead = jnp.dot(centre - corners[0], top)  # signed distance to the top's plane
    closest = _closest_on_triangle(corners, centre, top)
    gap = jnp.linalg.norm(closest - centre)
    in_front = ahead >= 0
    within = _inside(corners, centre, jnp.array([0.0, 0.0, 1.0]))  # over or under the triangle, along the field's z
    towards = jnp.where(gap > 1e-9, (closest - centre) / jnp.maximum(gap, 1e-9), -top)
    normal = jnp.where(in_front, towards, -top)
    point = jnp.where(in_front, closest, centre - ahead * top)
    dist = jnp.where(in_front, gap - radius, jnp.where(within, ahead - radius, 1.0))
    pos = (point + centre + normal * radius) / 2
    return dist, prism.mat @ pos + prism.pos, prism.mat @ normal


@collision_convex.collider(ncon=MAX_CONTACTS)
def hfield_sphere(field, sphere, subgrid_size) -> tuple[jax.Array, jax.Array, jax.Array]:
    """MJX's collision function of a (height field, sphere) pair with `sphere_prism` for each prism."""
    dist, pos, normal = collision_convex._hfield_collision(sphere_prism, field, sphere, jnp.max(sphere.size),
                                                           subgrid_size)
    counts = dist < jnp.minimum(0.0, dist.min() + TIE)
    order = jnp.argsort(jnp.where(counts, dist, jnp.inf))[:MAX_CONTACTS]
    dist, pos, normal, counts = dist[order], pos[order], normal[order], counts[order]
    # the same point reached through two neighbouring prisms is one contact
    near = jnp.linalg.norm(pos[:, None] - pos[None], axis=2) < TIE
    repeated = jnp.any(jnp.tril(near, -1) & counts[None, :], axis=1)
    dist = jnp.where(counts & ~repeated, dist, 1.0)
    pos = jax.vmap(lambda p: field.mat @ p + field.pos)(pos)
    normal = jax.vmap(lambda n: field.mat @ n)(normal)
    return dist, pos, jax.vmap(math.make_frame)(normal)


PAIR = (GeomType.HFIELD, GeomType.SPHERE)
"""The key of the replaced function in MJX's collision table."""


def install() -> None:
    """Make MJX collide spheres with height fields through `hfield_sphere` (programs traced from now on)."""
    collision_driver._COLLISION_FUNC[PAIR] = hfield_sphere


def installed() -> bool:
    """Whether MJX's (height field, sphere) pairs go through `hfield_sphere`."""
    return collision_driver._COLLISION_FUNC.get(PAIR) is hfield_sphere


@contextlib.contextmanager
def mjx_own():
    """MJX's own (height field, sphere) function for the programs traced inside (`legged bench env --physics
    mjx-stock` measures what the replacement costs); the function before it afterwards."""
    before = collision_driver._COLLISION_FUNC[PAIR]
    collision_driver._COLLISION_FUNC[PAIR] = collision_convex.hfield_sphere
    try:
        yield
    finally:
        collision_driver._COLLISION_FUNC[PAIR] = before
