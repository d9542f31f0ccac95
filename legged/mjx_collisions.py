"""Sphere-height-field contacts in MJX that agree with MuJoCo's own.

MJX (3.17) collides a sphere with a height field prism by prism (the triangles of the field, each extruded to the
field's base), and decides each sphere-prism pair with the prisms' face normals alone. Near a steep triangle (the
edge of a void, a step, a wall of the confined worlds, whose maps drop by up to 1.5 m between two samples) no face
normal separates a sphere that floats above the edge, and the closest point it then takes is not the prism's: MJX
reports a contact 1.1-1.3 m deep with a nearly horizontal normal where MuJoCo reports none. A trunk sphere 21 cm
above the floor, passing over the rim of a 1 m void, was thrown sideways: the follower fell in 44% of the held-out
d4 worlds in MJX against 10% in native MuJoCo, at the deep voids.

`install()` puts an exact sphere-prism test in MJX's collision table for (height field, sphere) pairs: the distance
from the sphere's centre to the prism as a solid (the closest point of the faces the centre lies in front of; inside,
the depth below the field's surface), and at most four contacts per sphere, within 1 mm of the deepest, at distinct points. Everything
else about MJX's height field collisions (which prisms are tried, the flip of normals that point into the field)
stays MJX's. The project's MJX models are built through legged.robots.models.mjx_model_of, which installs it.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from mujoco.mjx._src import collision_convex, collision_driver, math
from mujoco.mjx._src.types import GeomType

MAX_CONTACTS = 4
"""Contacts one sphere may have with a height field (MJX's own number for this pair)."""

TIE = 1e-3
"""Contacts whose depth is within this of the deepest one's count (m); the others are the same surface seen from a
neighbouring triangle's edge."""


def _closest_on_polygon(poly: jax.Array, normal: jax.Array, point: jax.Array) -> jax.Array:
    """The point of the planar convex polygon `poly` (vertices in order, a repeated vertex allowed) nearest to
    `point`."""
    on_plane = point - jnp.dot(point - poly[0], normal) * normal
    start, edge = poly, jnp.roll(poly, -1, axis=0) - poly
    real = jnp.sum(edge * edge, axis=1) > 1e-12
    side = jnp.einsum("ij,j->i", jnp.cross(edge, on_plane - start), normal)
    inside = jnp.all(~real | (side >= -1e-9)) | jnp.all(~real | (side <= 1e-9))
    t = jnp.clip(jnp.sum((on_plane - start) * edge, axis=1) / jnp.maximum(jnp.sum(edge * edge, axis=1), 1e-12), 0, 1)
    on_edges = start + t[:, None] * edge
    nearest = on_edges[jnp.argmin(jnp.sum((on_edges - point) ** 2, axis=1))]
    return jnp.where(inside, on_plane, nearest)


TOP = 1
"""Index of the top triangle among a height field prism's faces (mujoco.mjx._src.mesh.hfield_prism: bottom, top,
three sides)."""


def sphere_prism(sphere, prism) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(distance, contact point, normal from the sphere into the prism) of a sphere and a height field prism (MJX's
    GeomInfo and ConvexInfo, faces with outward normals). A centre outside the prism: the exact distance to it, from
    the closest point of the faces the centre lies in front of. A centre inside: its depth below the top triangle
    (the sides and the base are inside the field, shared with the neighbouring prisms or under them)."""
    centre = prism.mat.T @ (sphere.pos - prism.pos)
    radius = sphere.size[0]
    ahead = jnp.einsum("fi,fi->f", centre - prism.face[:, 0], prism.face_normal)  # signed distance to each plane
    nearest = jax.vmap(_closest_on_polygon, in_axes=(0, 0, None))(prism.face, prism.face_normal, centre)
    gaps = jnp.where(ahead > 0, jnp.linalg.norm(nearest - centre, axis=1), jnp.inf)
    k, top = jnp.argmin(gaps), prism.face_normal[TOP]
    outside = jnp.any(ahead > 0)
    # outside: towards the closest point (the top's normal when the centre lies on the surface)
    towards = jnp.where(gaps[k] > 1e-9, (nearest[k] - centre) / jnp.maximum(gaps[k], 1e-9), -top)
    normal = jnp.where(outside, towards, -top)
    point = jnp.where(outside, nearest[k], centre - ahead[TOP] * top)
    dist = jnp.where(outside, gaps[k], ahead[TOP]) - radius
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


def install() -> None:
    """Make MJX collide spheres with height fields through `hfield_sphere` (programs traced from now on)."""
    collision_driver._COLLISION_FUNC[(GeomType.HFIELD, GeomType.SPHERE)] = hfield_sphere


def installed() -> bool:
    """Whether MJX's (height field, sphere) pairs go through `hfield_sphere`."""
    return collision_driver._COLLISION_FUNC.get((GeomType.HFIELD, GeomType.SPHERE)) is hfield_sphere
