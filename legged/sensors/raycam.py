"""Egocentric camera in JAX: rays from a model camera give RGB, depth and segmentation images.

`render(camera, data)` is pure, jittable and vmappable over a batch of data. It follows MuJoCo's
pinhole model exactly, so that its images line up pixel for pixel with MuJoCo's renderer looking through
the same camera at the same size (legged/sensors/native_camera.py):

- vertical field of view `cam_fovy`, square pixels (horizontal extent from the aspect ratio W / H),
  rays through pixel centres, row 0 at the top; the camera looks along its local -z with +y up;
- near clipping at the model's `vis.map.znear * stat.extent` (a surface nearer than that is skipped);
- depth is z-depth: the distance along the camera's optical axis in metres (what MuJoCo's depth
  rendering returns), not the length of the ray. Pixels that hit nothing within `max_depth` get
  `max_depth`, segmentation class 0 and the sky colour.

Rays are cast (legged/sensors/raycast.py) against the geoms of the chosen groups. Decals, thin flat boxes
of one group lying on a ground plane (a soccer pitch's painted lines), are not cast against: where a ray
hits a world plane its xy point is tested against the decal rectangles analytically, which is both exact
and cheaper than 40-odd more boxes. Shading is Lambert's from two lights, a headlight (MuJoCo's
default headlight sits at the camera too) and one straight overhead (the scene's sun):
colour = rgb * min(1, ambient + headlight |n . ray| + overhead max(n_z, 0)); a surface facing the
camera shows its own colour. No shadows, specular highlights or textures (geom and material rgba only).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import jax.numpy as jnp
import mujoco
import numpy as np

from legged.sensors.raycast import GeomSet, cast

SEGMENTATION_CLASSES = ("none", "ground", "line", "ball", "goal", "own_team", "opponent")
"""Segmentation class names by id: 0 sky or nothing, then the soccer scene's object classes."""
NONE, GROUND, LINE, BALL, GOAL, OWN_TEAM, OPPONENT = range(len(SEGMENTATION_CLASSES))
_DEFAULT_RGBA = np.array([0.5, 0.5, 0.5, 1.0], dtype=np.float32)


@dataclasses.dataclass(frozen=True)
class RayCameraConfig:
    """Image size and appearance of the ray-cast camera."""

    width: int = 40
    """Image width, pixels (Tirumala et al.: about 40 x 30)."""
    height: int = 30
    """Image height, pixels."""
    max_depth: float = 10.0
    """Farthest visible surface, metres (z-depth); farther pixels read as nothing (class 0)."""
    geom_groups: tuple[int, ...] = (0, 2)
    """Geom groups cast against: what MuJoCo's renderer shows by default (groups 0-2) minus decals."""
    decal_group: int = 1
    """Geom group of flat boxes drawn analytically on world planes (the pitch lines)."""
    ambient: float = 0.3
    """Light every surface gets (as a fraction of its colour)."""
    headlight: float = 0.7
    """Light from the camera: times |cos| of the angle between surface normal and ray."""
    overhead: float = 0.5
    """Light from straight above: times the normal's upward component (if positive)."""
    sky_rgb: tuple[float, float, float] = (0.55, 0.7, 0.9)
    """Colour of pixels that hit nothing."""
    native_caster: bool = True
    """With native physics, cast the rays with MuJoCo's C ray caster (legged.sensors.native_raycam; same
    images) instead of in JAX."""
    native_cull: bool = True
    """With the C ray caster, skip the geoms outside each camera's view before casting (the same images,
    cast against fewer geoms)."""

    def __post_init__(self):
        if self.width < 1 or self.height < 1:
            raise ValueError(f"width and height must be positive, got {self.width} x {self.height}")
        if not self.max_depth > 0:
            raise ValueError(f"max_depth must be positive, got {self.max_depth}")
        for name in ("ambient", "headlight", "overhead"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must lie in [0, 1], got {getattr(self, name)}")


def drawn_rgba(model: mujoco.MjModel, g: int) -> tuple[np.ndarray, int]:
    """Colour MuJoCo draws a geom in (its material's unless the geom's own rgba was set) and the id of the
    material that colour came from (-1: the geom's own)."""
    rgba = model.geom_rgba[g].astype(np.float32)
    mat = int(model.geom_matid[g])
    if mat >= 0 and np.allclose(rgba, _DEFAULT_RGBA):
        return model.mat_rgba[mat].astype(np.float32), mat
    return rgba, -1


@dataclasses.dataclass(frozen=True, eq=False)
class RayCamera:
    """Everything `render` needs that does not change between frames (numpy: static under jit)."""

    camera_ids: np.ndarray
    """Model camera ids rendered, [n_cam]; output images come in this order."""
    config: RayCameraConfig
    """Image size and appearance."""
    geoms: GeomSet
    """Geoms cast against."""
    rgb: np.ndarray
    """Colour of each cast geom, [n_geoms, 3]."""
    classes: np.ndarray
    """Segmentation class of each cast geom as seen by each camera, [n_cam, n_geoms]."""
    ground: np.ndarray
    """Whether each cast geom is a world plane that carries decals, [n_geoms]."""
    decals: np.ndarray
    """Decal rectangles: centre x, y, unit axis x, y, half length, half width, [n_decals, 6]."""
    decal_rgb: np.ndarray
    """Decal colours, [n_decals, 3]."""
    decal_class: int
    """Segmentation class of decal pixels."""
    dirs: np.ndarray
    """Unit ray direction of each pixel in each camera's frame, [n_cam, H * W, 3] (row-major from the top left)."""
    znear: float
    """Near clipping distance, metres (the model's, as MuJoCo's renderer uses)."""
    model: mujoco.MjModel | None = None
    """The model, kept when the camera sees meshes: MuJoCo's C caster casts them (legged.sensors.native_raycam)."""

    @classmethod
    def build(cls, model: mujoco.MjModel, camera_ids, config: RayCameraConfig = RayCameraConfig(),
              geom_classes: np.ndarray | None = None, decal_class: int = LINE) -> RayCamera:
        """Camera over `model` for `camera_ids`.

        geom_classes: segmentation class of every model geom, [ngeom] or per camera [n_cam, ngeom]
        (default: every visible geom is class 1). Cast geoms: groups in `config.geom_groups` with
        nonzero alpha; decals: boxes of `config.decal_group` in the world body, lying flat.
        """
        camera_ids = np.atleast_1d(np.asarray(camera_ids, dtype=np.int32))
        if camera_ids.size == 0 or camera_ids.min() < 0 or camera_ids.max() >= model.ncam:
            raise ValueError(f"camera_ids must name cameras of the model (0..{model.ncam - 1}), got {camera_ids}")
        rgba = np.stack([drawn_rgba(model, g)[0] for g in range(model.ngeom)]) if model.ngeom else np.zeros((0, 4))
        groups = np.asarray(config.geom_groups)
        visible = np.isin(model.geom_group, groups) & (rgba[:, 3] > 0)
        geoms = GeomSet.from_model(model, np.nonzero(visible)[0])
        if geom_classes is None:
            geom_classes = np.ones(model.ngeom, dtype=np.int32)
        geom_classes = np.broadcast_to(np.asarray(geom_classes, dtype=np.int32), (camera_ids.size, model.ngeom))
        world_plane = (model.geom_bodyid == 0) & (model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)
        zz = _static_zz(model)
        up = np.abs(zz) > 0.999  # boxes lying flat (either face up)
        decal_ids = np.nonzero((model.geom_group == config.decal_group) & (model.geom_bodyid == 0)
                               & (model.geom_type == mujoco.mjtGeom.mjGEOM_BOX) & up & (rgba[:, 3] > 0))[0]
        decals = []
        for g in decal_ids:
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, model.geom_quat[g])
            axis = mat.reshape(3, 3)[:2, 0]
            decals.append((*model.geom_pos[g, :2], *(axis / np.linalg.norm(axis)), *model.geom_size[g, :2]))
        return cls(
            camera_ids=camera_ids, config=config, geoms=geoms,
            rgb=rgba[geoms.ids, :3].astype(np.float32),
            classes=geom_classes[:, geoms.ids].copy(),
            ground=(world_plane & (zz > 0.999))[geoms.ids],
            decals=np.array(decals, dtype=np.float32).reshape(-1, 6),
            decal_rgb=rgba[decal_ids, :3].astype(np.float32).reshape(-1, 3),
            decal_class=int(decal_class),
            dirs=np.stack([pixel_directions(model.cam_fovy[c], config.width, config.height) for c in camera_ids]),
            znear=float(model.vis.map.znear * model.stat.extent),
            model=model if geoms.meshes else None,
        )

    @property
    def n_cameras(self) -> int:
        """Cameras rendered per frame."""
        return int(self.camera_ids.size)

    def select(self, cameras) -> RayCamera:
        """The same camera rendering only the cameras at positions `cameras` of `camera_ids` (in that order)."""
        rows = np.atleast_1d(np.asarray(cameras, dtype=np.int64))
        return dataclasses.replace(self, camera_ids=self.camera_ids[rows], classes=self.classes[rows],
                                   dirs=self.dirs[rows])


def _static_zz(model: mujoco.MjModel) -> np.ndarray:
    """z component of each geom's local z axis in its body frame (world geoms: in the world)."""
    q = model.geom_quat
    return 1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2)


def pixel_directions(fovy_deg: float, width: int, height: int) -> np.ndarray:
    """Unit ray directions through pixel centres in the camera frame, [H * W, 3], row 0 at the top."""
    tan = np.tan(np.deg2rad(fovy_deg) / 2)
    u = (2 * (np.arange(width) + 0.5) / width - 1) * tan * width / height
    v = (1 - 2 * (np.arange(height) + 0.5) / height) * tan
    x, y = np.meshgrid(u, v)
    d = np.stack([x, y, -np.ones_like(x)], -1).reshape(-1, 3)
    return (d / np.linalg.norm(d, axis=-1, keepdims=True)).astype(np.float32)


def _paint_decals(camera: RayCamera, point, rgb, seg, on_ground, xp):
    """Decal colour and class where a ground hit lies inside a decal rectangle (the first such decal)."""
    if camera.decals.shape[0] == 0:
        return rgb, seg
    if xp is np:
        return _paint_decals_numpy(camera, point, rgb, seg, on_ground)
    dec = xp.asarray(camera.decals)
    rel = point[..., None, :2] - dec[:, :2]  # [C, P, D, 2]
    along = xp.abs(xp.sum(rel * dec[:, 2:4], -1))
    across = xp.abs(rel[..., 0] * dec[:, 3] - rel[..., 1] * dec[:, 2])
    inside = (along <= dec[:, 4]) & (across <= dec[:, 5]) & on_ground[..., None]  # [C, P, D]
    any_in = xp.any(inside, -1)
    which = xp.argmax(inside, -1)
    rgb = xp.where(any_in[..., None], xp.asarray(camera.decal_rgb)[which], rgb)
    seg = xp.where(any_in, camera.decal_class, seg)
    return rgb, seg


DECAL_CELL = 0.1
"""Cell size of the numpy decal painter's lookup grid, metres."""


@functools.lru_cache(maxsize=32)
def _decal_grid(camera: RayCamera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The decals that may contain a point of each DECAL_CELL cell of the decals' bounding box (those within
    the cell's circumscribed circle, smallest index first, -1 padded): (grid origin [2], cells along x and y
    [2], candidates [cells, K])."""
    d = camera.decals.astype(np.float64)
    reach = np.hypot(d[:, 4], d[:, 5])[:, None]
    origin = (d[:, :2] - reach).min(axis=0) - DECAL_CELL
    shape = np.ceil(((d[:, :2] + reach).max(axis=0) + DECAL_CELL - origin) / DECAL_CELL).astype(np.int64)
    ix, iy = np.meshgrid(np.arange(shape[0]), np.arange(shape[1]), indexing="ij")
    centres = origin + (np.stack([ix.ravel(), iy.ravel()], axis=1) + 0.5) * DECAL_CELL
    rel = centres[:, None, :] - d[None, :, :2]
    along = np.abs(rel[..., 0] * d[:, 2] + rel[..., 1] * d[:, 3]) - d[:, 4]
    across = np.abs(rel[..., 0] * d[:, 3] - rel[..., 1] * d[:, 2]) - d[:, 5]
    near = np.hypot(np.maximum(along, 0.0), np.maximum(across, 0.0)) <= DECAL_CELL * np.sqrt(0.5) + 1e-6
    order = np.argsort(~near, axis=1, kind="stable")[:, :max(int(near.sum(axis=1).max()), 1)]
    return origin, shape, np.where(np.take_along_axis(near, order, axis=1), order, -1)


def _paint_decals_numpy(camera: RayCamera, point, rgb, seg, on_ground):
    """`_paint_decals` for numpy arrays: the same tests on the ground hits only, and for each only against the
    few decals near it (a lookup grid, `_decal_grid`; the broadcast over every pixel and decal is what JAX
    wants, and many times slower in numpy)."""
    hits = np.flatnonzero(on_ground)
    xy = point.reshape(-1, point.shape[-1])[hits, :2]
    origin, shape, table = _decal_grid(camera)
    cell = np.floor((xy - origin) / DECAL_CELL).astype(np.int64)
    near = np.all((cell >= 0) & (cell < shape), axis=1)
    near[near] = table[cell[near, 0] * shape[1] + cell[near, 1], 0] >= 0
    hits, xy, cell = hits[near], xy[near], cell[near]
    candidates = table[cell[:, 0] * shape[1] + cell[:, 1]]  # [hits, K]
    cx, cy, ax, ay, half_length, half_width = np.moveaxis(camera.decals[np.maximum(candidates, 0)], -1, 0)
    dx, dy = xy[:, None, 0] - cx, xy[:, None, 1] - cy
    inside = ((candidates >= 0) & (np.abs(dx * ax + dy * ay) <= half_length)
              & (np.abs(dx * ay - dy * ax) <= half_width))
    painted = inside.any(axis=1)
    which = candidates[np.arange(len(hits)), inside.argmax(axis=1)][painted]  # the first decal containing it
    rgb, seg = rgb.copy(), seg.copy()
    rgb.reshape(-1, 3)[hits[painted]] = camera.decal_rgb[which]
    seg.reshape(-1)[hits[painted]] = camera.decal_class
    return rgb, seg


class Poses(NamedTuple):
    """The pose fields `render` reads (a pytree: jit and vmap take it); mjx.Data works in its place."""

    geom_xpos: np.ndarray
    """World positions of all geoms, [ngeom, 3]."""
    geom_xmat: np.ndarray
    """World orientations of all geoms, [ngeom, 9] or [ngeom, 3, 3]."""
    cam_xpos: np.ndarray
    """World positions of all cameras, [ncam, 3]."""
    cam_xmat: np.ndarray
    """World orientations of all cameras, [ncam, 9] or [ncam, 3, 3]."""
    xpos: np.ndarray
    """World positions of all bodies, [nbody, 3] (MuJoCo's C caster culls by the bodies' bounding volumes)."""
    xmat: np.ndarray
    """World orientations of all bodies, [nbody, 9] or [nbody, 3, 3]."""


def poses_of(data) -> Poses:
    """float32 copies of the pose fields of a native MjData (after mj_forward), for jitted `render` calls."""
    return Poses(*(np.array(getattr(data, k), dtype=np.float32) for k in Poses._fields))


def render(camera: RayCamera, data) -> dict:
    """Images of every camera for one state: rgb uint8 [n_cam, H, W, 3], depth float32 (z-depth, metres),
    segmentation int32 (class ids, SEGMENTATION_CLASSES) and geom int32 (model geom id, -1 none), each
    [n_cam, H, W]. `data` is an mjx.Data (or anything with geom_xpos, geom_xmat, cam_xpos, cam_xmat);
    jit with the camera closed over and vmap over a batch of data."""
    cam_pos, dirs = camera_rays(camera, data.cam_xpos, data.cam_xmat, jnp)
    cos = -jnp.asarray(camera.dirs)[..., 2]  # cosine between each ray and the optical axis
    dist, index, normal = cast(camera.geoms, data.geom_xpos, data.geom_xmat, cam_pos, dirs, camera.znear / cos)
    return images_from_hits(camera, cam_pos, dirs, dist, index, normal, jnp)


def camera_rays(camera: RayCamera, cam_xpos, cam_xmat, xp) -> tuple:
    """(origins [..., n_cam, 3], unit world directions [..., n_cam, H * W, 3]) of the pixel rays of every
    camera, from the cameras' poses (leading batch axes allowed); jax.numpy or numpy (`xp`)."""
    ids = camera.camera_ids
    cam_pos = xp.asarray(cam_xpos)[..., ids, :]
    xmat = xp.asarray(cam_xmat)
    if xmat.shape[-1] == 9:
        xmat = xmat.reshape(xmat.shape[:-1] + (3, 3))
    dirs = xp.matmul(xp.asarray(camera.dirs), xp.swapaxes(xmat[..., ids, :, :], -1, -2))  # R d for every pixel
    return cam_pos, dirs


def images_from_hits(camera: RayCamera, cam_pos, dirs, dist, index, normal, xp) -> dict:
    """`render`'s images from the ray hits of every camera: `dist` along each ray [..., n_cam, P] (inf:
    no hit), `index` into camera.geoms, `normal` [..., n_cam, P, 3]; `cam_pos` and `dirs` from
    `camera_rays`. Shared by the JAX renderer (xp=jax.numpy) and the C ray caster (numpy,
    legged.sensors.native_raycam)."""
    cfg = camera.config
    depth = dist * -xp.asarray(camera.dirs)[..., 2]
    hit = xp.isfinite(dist) & (depth <= cfg.max_depth)
    safe = xp.where(hit, index, 0)
    rgb = xp.asarray(camera.rgb)[safe]
    classes = xp.asarray(camera.classes)
    seg = xp.take_along_axis(xp.broadcast_to(classes, safe.shape[:-1] + classes.shape[-1:]), safe, axis=-1)
    point = cam_pos[..., None, :] + xp.where(hit, dist, 0.0)[..., None] * dirs
    rgb, seg = _paint_decals(camera, point, rgb, seg, hit & xp.asarray(camera.ground)[safe], xp)
    shade = xp.minimum(1.0, cfg.ambient + cfg.headlight * xp.abs(xp.sum(normal * dirs, -1))
                       + cfg.overhead * xp.maximum(normal[..., 2], 0.0))
    rgb = xp.where(hit[..., None], rgb * shade[..., None], xp.asarray(cfg.sky_rgb, xp.float32))
    shape = hit.shape[:-1] + (cfg.height, cfg.width)
    return {
        "rgb": xp.round(xp.clip(rgb, 0.0, 1.0) * 255).astype(xp.uint8).reshape(shape + (3,)),
        "depth": xp.where(hit, depth, cfg.max_depth).astype(xp.float32).reshape(shape),
        "segmentation": xp.where(hit, seg, NONE).astype(xp.int32).reshape(shape),
        "geom": xp.where(hit, xp.asarray(camera.geoms.ids)[safe], -1).astype(xp.int32).reshape(shape),
    }
