"""Batched ray casting against MuJoCo primitive geoms in JAX: nearest hit, geom id and surface normal.

Same semantics as `mujoco.mj_ray` / `mjx.ray` (a ray hits the nearest surface of any listed geom, planes
only from their front side and within their size when it is positive), with three differences that a
camera needs:

- cylinders are supported (mjx.ray has no cylinder; the OP3's visual geoms have some);
- every ray has a minimum distance `tmin` (a camera's near clipping plane): a surface nearer than that
  is skipped and the ray goes on to the next one, including the far side of a geom it starts inside,
  as OpenGL's near-plane clipping does;
- the surface normal of the hit comes back (for shading).

Rays are batched per camera: all rays of a camera share an origin. The geoms to cast against are fixed
when the `GeomSet` is built (numpy, static under jit); their poses come from the data at call time.
Work is O(cameras x geoms x rays) with no acceleration structure: fine for tens of geoms and a few
thousand rays, which is what a 40 x 30 camera in a soccer scene needs.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

_T = mujoco.mjtGeom
SUPPORTED_TYPES = (_T.mjGEOM_PLANE, _T.mjGEOM_SPHERE, _T.mjGEOM_CAPSULE, _T.mjGEOM_ELLIPSOID,
                   _T.mjGEOM_CYLINDER, _T.mjGEOM_BOX)
"""Geom types this (JAX) caster intersects."""
SET_TYPES = SUPPORTED_TYPES + (_T.mjGEOM_MESH,)
"""Geom types a GeomSet may hold: meshes too, which only MuJoCo's C caster (legged.sensors.native_raycam) casts."""
_TINY = 1e-20


@dataclasses.dataclass(frozen=True, eq=False)
class GeomSet:
    """The geoms rays are cast against, grouped by type (numpy: static under jit)."""

    ids: np.ndarray
    """Geom ids in the model, [n]; ray results index into this array."""
    types: np.ndarray
    """mjtGeom type of each geom, [n]."""
    size: np.ndarray
    """MuJoCo geom size of each geom, [n, 3]."""
    names: tuple[str, ...] = ()
    """Each geom's name (its id where it has none), for messages."""

    @classmethod
    def from_model(cls, model: mujoco.MjModel, geom_ids) -> GeomSet:
        """Geom set of the listed geom ids (ValueError for height fields and other types; meshes are kept, for
        MuJoCo's C caster: `cast` refuses them)."""
        ids = np.asarray(geom_ids, dtype=np.int32)
        for g in ids:
            if int(model.geom_type[g]) not in [int(t) for t in SET_TYPES]:
                raise ValueError(f"geom {model.geom(g).name or g!r} has type "
                                 f"{mujoco.mjtGeom(model.geom_type[g]).name}; the ray camera handles "
                                 f"{', '.join(t.name for t in SET_TYPES)}")
        order = np.argsort(model.geom_type[ids], kind="stable")  # one block per type
        ids = ids[order]
        return cls(ids=ids, types=model.geom_type[ids].astype(np.int32),
                   size=model.geom_size[ids].astype(np.float32),
                   names=tuple(model.geom(int(g)).name or str(int(g)) for g in ids))

    @property
    def meshes(self) -> tuple[str, ...]:
        """Names (or ids) of the mesh geoms, which the JAX caster cannot cast."""
        return tuple(n for n, t in zip(self.names, self.types) if t == int(_T.mjGEOM_MESH))


def _first(cands: jax.Array, tmin: jax.Array) -> jax.Array:
    """Nearest candidate distance at or beyond tmin (inf if none); cands [..., k], tmin broadcastable to [...]."""
    ok = jnp.isfinite(cands) & (cands >= tmin[..., None])
    return jnp.min(jnp.where(ok, cands, jnp.inf), axis=-1)


def _roots(a, b, c):
    """Both roots of a x^2 + 2 b x + c = 0 (inf where there are none), smaller first."""
    det = b * b - a * c
    ok = (det >= 0) & (a > 0)
    sq = jnp.sqrt(jnp.maximum(det, 0.0))
    a = jnp.where(ok, a, 1.0)
    return jnp.where(ok, (-b - sq) / a, jnp.inf), jnp.where(ok, (-b + sq) / a, jnp.inf)


def _div(a, b):
    return a / jnp.where(b == 0, _TINY, b)


def _plane(size, p, v):
    x = jnp.where(v[..., 2] < 0, -_div(p[..., 2], v[..., 2]), jnp.inf)
    hit = p[..., :2] + x[..., None] * v[..., :2]
    inside = jnp.all((size[..., :2] <= 0) | (jnp.abs(hit) <= size[..., :2]), axis=-1)
    return jnp.where(inside, x, jnp.inf)[..., None]


def _sphere(size, p, v):
    r = size[..., 0]
    return jnp.stack(_roots(jnp.sum(v * v, -1), jnp.sum(v * p, -1), jnp.sum(p * p, -1) - r * r), -1)


def _ellipsoid(size, p, v):
    s = 1.0 / jnp.square(size)
    return jnp.stack(_roots(jnp.sum(s * v * v, -1), jnp.sum(s * v * p, -1), jnp.sum(s * p * p, -1) - 1.0), -1)


def _side(r, h, p, v):
    """Hits on the curved side of a z-axis cylinder of radius r and half-length h."""
    a = v[..., 0] ** 2 + v[..., 1] ** 2
    b = p[..., 0] * v[..., 0] + p[..., 1] * v[..., 1]
    c = p[..., 0] ** 2 + p[..., 1] ** 2 - r * r
    out = []
    for x in _roots(a, b, c):
        z = p[..., 2] + x * v[..., 2]
        out.append(jnp.where(jnp.abs(z) <= h, x, jnp.inf))
    return out


def _capsule(size, p, v):
    r, h = size[..., 0], size[..., 1]
    cands = _side(r, h, p, v)
    for sign in (1.0, -1.0):
        q = p.at[..., 2].add(-sign * h)
        for x in _roots(jnp.sum(v * v, -1), jnp.sum(v * q, -1), jnp.sum(q * q, -1) - r * r):
            z = p[..., 2] + x * v[..., 2]
            cands.append(jnp.where(sign * z >= h, x, jnp.inf))
    return jnp.stack(cands, -1)


def _cylinder(size, p, v):
    r, h = size[..., 0], size[..., 1]
    cands = _side(r, h, p, v)
    for sign in (1.0, -1.0):
        x = _div(sign * h - p[..., 2], v[..., 2])
        hx, hy = p[..., 0] + x * v[..., 0], p[..., 1] + x * v[..., 1]
        cands.append(jnp.where(hx * hx + hy * hy <= r * r, x, jnp.inf))
    return jnp.stack(cands, -1)


def _box(size, p, v):
    v = jnp.where(v == 0, _TINY, v)
    t1, t2 = (-size - p) / v, (size - p) / v
    near = jnp.max(jnp.minimum(t1, t2), -1)
    far = jnp.min(jnp.maximum(t1, t2), -1)
    ok = near <= far
    return jnp.stack([jnp.where(ok, near, jnp.inf), jnp.where(ok, far, jnp.inf)], -1)


_CANDIDATES = {
    int(_T.mjGEOM_PLANE): _plane, int(_T.mjGEOM_SPHERE): _sphere, int(_T.mjGEOM_CAPSULE): _capsule,
    int(_T.mjGEOM_ELLIPSOID): _ellipsoid, int(_T.mjGEOM_CYLINDER): _cylinder, int(_T.mjGEOM_BOX): _box,
}


def _local_normal(gtype, size, p):
    """Outward surface normal at local point p of a geom of (traced) type gtype, normalised."""
    r, h = size[..., 0:1], size[..., 1:2]
    axial = jnp.concatenate([p[..., :2], jnp.zeros_like(p[..., 2:])], -1)
    capsule = p - jnp.concatenate([jnp.zeros_like(p[..., :2]), jnp.clip(p[..., 2:], -h, h)], -1)
    rho = jnp.linalg.norm(p[..., :2], axis=-1, keepdims=True)
    cap = (jnp.abs(p[..., 2:]) - h) > (rho - r)
    cylinder = jnp.where(cap, jnp.concatenate([jnp.zeros_like(p[..., :2]), jnp.sign(p[..., 2:])], -1), axial)
    scaled = jnp.abs(p) / jnp.maximum(size, 1e-9)
    face = jax.nn.one_hot(jnp.argmax(scaled, -1), 3, dtype=p.dtype)
    box = face * jnp.sign(p)
    up = jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0], p.dtype), p.shape)
    t = gtype[..., None]
    n = jnp.select(
        [t == int(_T.mjGEOM_PLANE), t == int(_T.mjGEOM_SPHERE), t == int(_T.mjGEOM_CAPSULE),
         t == int(_T.mjGEOM_ELLIPSOID), t == int(_T.mjGEOM_CYLINDER)],
        [up, p, capsule, p / jnp.square(jnp.maximum(size, 1e-9)), cylinder], box)
    return n / jnp.maximum(jnp.linalg.norm(n, axis=-1, keepdims=True), 1e-12)


def _apply_transpose(rot, vec):
    """rot^T @ vec over broadcast leading axes, written elementwise so XLA fuses it into the ray tests."""
    return jnp.stack([sum(rot[..., j, i] * vec[..., j] for j in range(3)) for i in range(3)], -1)


def cast(geoms: GeomSet, geom_xpos, geom_xmat, origins, dirs, tmin):
    """Nearest hits of rays that share one origin per camera.

    Args:
      geoms: the geoms to cast against.
      geom_xpos: world positions of all model geoms, [ngeom, 3] (mjx.Data or MjData field).
      geom_xmat: world orientations of all model geoms, [ngeom, 3, 3] or [ngeom, 9].
      origins: ray origin of each camera, [C, 3].
      dirs: unit ray directions, [C, P, 3].
      tmin: minimum hit distance along each ray, [C, P].

    Returns:
      dist [C, P] (inf: no hit), index [C, P] into geoms.ids (-1: no hit), world normal [C, P, 3].
    """
    if geoms.meshes:
        raise ValueError(f"the JAX ray camera casts against primitive geoms only, and {len(geoms.meshes)} visible "
                         f"geoms are meshes (e.g. {geoms.meshes[0]}): use native physics, whose camera is MuJoCo's "
                         f"own ray caster")
    xpos = jnp.asarray(geom_xpos)
    xmat = jnp.asarray(geom_xmat).reshape((-1, 3, 3))
    dists = []
    start = 0
    for gtype in np.unique(geoms.types):  # sorted, as the blocks of geoms.ids are
        n = int(np.sum(geoms.types == gtype))
        ids = geoms.ids[start:start + n]
        rot, pos = xmat[ids], xpos[ids]
        lp = _apply_transpose(rot[None], origins[:, None, :] - pos[None])  # [C, G, 3]
        lv = _apply_transpose(rot[None, :, None], dirs[:, None, :, :])  # [C, G, P, 3]
        size = jnp.asarray(geoms.size[start:start + n])[None, :, None, :]
        cands = _CANDIDATES[int(gtype)](size, lp[:, :, None, :], lv)
        dists.append(_first(cands, tmin[:, None, :]))  # [C, G, P]
        start += n
    if not dists:
        shape = dirs.shape[:2]
        return jnp.full(shape, jnp.inf), jnp.full(shape, -1, jnp.int32), jnp.zeros(dirs.shape)
    dist_all = jnp.concatenate(dists, axis=1)
    index = jnp.argmin(dist_all, axis=1).astype(jnp.int32)  # [C, P]
    dist = jnp.min(dist_all, axis=1)
    hit = jnp.isfinite(dist)
    # Normal of the winning geom only (cheap: one geom per ray).
    gid = jnp.asarray(geoms.ids)[index]
    rot, pos = xmat[gid], xpos[gid]  # [C, P, 3, 3], [C, P, 3]
    point = origins[:, None, :] + jnp.where(hit, dist, 0.0)[..., None] * dirs
    local = jnp.einsum("cpji,cpj->cpi", rot, point - pos)
    n_local = _local_normal(jnp.asarray(geoms.types)[index], jnp.asarray(geoms.size)[index], local)
    normal = jnp.einsum("cpij,cpj->cpi", rot, n_local)
    return dist, jnp.where(hit, index, -1), normal
