"""The ray camera rendered in C: MuJoCo's own ray caster (`mj_multiRay`) on CPU threads, then the same
colouring as the JAX renderer (legged.sensors.raycam.images_from_hits), so that both give the same images.

For the native physics engine: `NativeRayCaster.render` takes the batched geom and camera poses the engine
reads after each step and returns every camera's images. One `mj_multiRay` call casts all pixel rays of one
camera (they share the camera's origin), in C with the GIL released, so the environments are split over a
thread pool, each thread with its own scratch MjData holding only the poses.

MuJoCo's caster intersects each ray with every geom it does not eliminate (the soccer scenes' bodies carry no
bounding volumes for its angular culling), so this caster culls first: per camera, the geoms whose bounding
spheres lie wholly outside the pyramid of its pixel rays are made invisible to that cast (alpha 0 in the
thread's own copy of the model; MuJoCo's caster skips invisible geoms). No pixel changes; on random soccer
states a camera casts against about a tenth of the geoms.

MuJoCo's caster also culls by the bounding volumes of bodies whose geoms have them (meshes: Menagerie's OP3),
placed by the bodies' inertial frames, so `render` takes the body poses too and derives those frames. It casts
meshes, which the JAX caster does not: `render_anywhere` renders a camera that sees meshes with this caster from
jitted code too (a host callback), so a task's observation is the same in every engine.

One difference from the JAX caster: the JAX camera skips surfaces nearer than the near plane (as OpenGL
clips them), which is how a head camera sees out of the head it sits in; `mj_multiRay` has no near plane,
so here the rays ignore the geoms of the camera's own body instead. Agreement with the JAX renderer is
tested (tests/test_native_raycam.py).
"""

from __future__ import annotations

import copy
import functools
import threading
from concurrent.futures import ThreadPoolExecutor

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from legged.envs.math import quat_to_mat
from legged.sensors.raycam import RayCamera, camera_rays, images_from_hits, render


def frustum_planes(camera: RayCamera) -> np.ndarray:
    """Inward unit normals of the four side planes of each camera's pyramid of pixel rays, in the camera
    frame, [n_cam, 4, 3]: a point x (camera frame) is inside where every n . x >= 0."""
    w, h = camera.config.width, camera.config.height
    planes = []
    for dirs in camera.dirs:
        corners = dirs[[0, w - 1, h * w - 1, (h - 1) * w]]  # pixel rows run along the width
        normals = np.cross(corners, np.roll(corners, -1, axis=0))
        normals *= np.sign(normals @ dirs.mean(axis=0))[:, None]  # towards the optical axis
        planes.append(normals / np.linalg.norm(normals, axis=1, keepdims=True))
    return np.stack(planes)


class NativeRayCaster:
    """Renders a RayCamera's images for a batch of poses with MuJoCo's C ray caster on `threads` threads
    (culling the geoms outside each camera's view first unless `camera.config.native_cull` is off)."""

    def __init__(self, model: mujoco.MjModel, camera: RayCamera, threads: int = 1):
        if threads < 1:
            raise ValueError(f"threads must be >= 1, got {threads}")
        cast = set(map(int, camera.geoms.ids))
        groups = set(camera.config.geom_groups)
        visible = {g for g in range(model.ngeom) if model.geom_group[g] in groups and model.geom_rgba[g, 3] > 0}
        own = set(np.flatnonzero(np.isin(model.geom_bodyid, model.cam_bodyid[camera.camera_ids])).tolist())
        if visible - own != cast - own:  # the C caster sees MuJoCo's visible geoms of these groups
            raise ValueError(f"the C ray caster would see geoms {sorted(visible ^ cast)} differently from the "
                             f"camera's geom set (materials with their own alpha?)")
        self.model, self.camera = model, camera
        self.groups = np.zeros(mujoco.mjNGROUP, np.uint8)
        self.groups[list(groups)] = 1
        self.exclude = model.cam_bodyid[camera.camera_ids].astype(int)
        self.index = np.full(model.ngeom, -1, np.int64)
        self.index[camera.geoms.ids] = np.arange(camera.geoms.ids.size)
        self.cutoff = float(camera.config.max_depth / np.min(-camera.dirs[..., 2]))
        self.threads, self.cull = threads, camera.config.native_cull
        self._datas = [mujoco.MjData(model) for _ in range(threads)]
        self._cast_ids = np.asarray(camera.geoms.ids, np.int64)
        self._planes = frustum_planes(camera)
        self._rbound = model.geom_rbound[self._cast_ids] + 1e-6
        self._unbounded = model.geom_type[self._cast_ids] == mujoco.mjtGeom.mjGEOM_PLANE
        self._models = [self._culling_copy(model) for _ in range(threads)] if self.cull else [model] * threads
        self._ipos = model.body_ipos.copy()
        self._irot = np.asarray(quat_to_mat(model.body_iquat), np.float64)  # inertial frame in the body frame
        self._pool = ThreadPoolExecutor(threads) if threads > 1 else None

    def _culling_copy(self, model: mujoco.MjModel) -> mujoco.MjModel:
        """A copy of `model` whose geoms are visible to MuJoCo's caster through their own alpha alone (no
        materials), with every geom outside the camera's geom set hidden."""
        own = copy.deepcopy(model)
        own.geom_matid[:] = -1
        own.geom_rgba[:, 3] = 0.0
        own.geom_rgba[self._cast_ids, 3] = 1.0
        return own

    def _in_view(self, geom_xpos: np.ndarray, cam_pos: np.ndarray, cam_xmat: np.ndarray) -> np.ndarray:
        """Whether each cast geom's bounding sphere reaches into each camera's pyramid of rays, [N, n_cam,
        n_geoms] (planes always), from geom positions [N, ngeom, 3], camera origins [N, n_cam, 3] and the
        cameras' rotations [N, n_cam, 3, 3]."""
        normals = np.einsum("ncij,ckj->ncki", cam_xmat, self._planes)  # world-frame inward normals
        offset = geom_xpos[:, None, self._cast_ids, :] - cam_pos[:, :, None, :]
        inside = np.einsum("ncgi,ncki->ncgk", offset, normals) >= -self._rbound[:, None]
        return inside.all(axis=-1) | self._unbounded

    def render(self, geom_xpos: np.ndarray, geom_xmat: np.ndarray, cam_xpos: np.ndarray, cam_xmat: np.ndarray,
               xpos: np.ndarray, xmat: np.ndarray) -> dict:
        """Images of every camera of the batch: rgb uint8 [N, n_cam, H, W, 3], depth float32, segmentation
        and geom int32 [N, n_cam, H, W] (as raycam.render, batched), from geom, camera and body poses
        [N, ngeom | ncam | nbody, 3 | 9 | 3, 3]. Each thread casts and colours its share of the environments."""
        n = geom_xpos.shape[0]
        geom_rot = np.asarray(geom_xmat).reshape(n, -1, 9)
        body_rot = np.asarray(xmat, np.float64).reshape(n, -1, 3, 3)
        xipos = np.asarray(xpos, np.float64) + np.einsum("nbij,bj->nbi", body_rot, self._ipos)
        ximat = np.einsum("nbij,bjk->nbik", body_rot, self._irot).reshape(n, -1, 9)
        chunks = [c for c in np.array_split(np.arange(n), min(self.threads, n)) if len(c)]

        def work(k: int) -> dict:
            rows = chunks[k]
            cam_pos, dirs = camera_rays(self.camera, np.asarray(cam_xpos[rows], np.float64),
                                        np.asarray(cam_xmat[rows], np.float64), np)
            shape = dirs.shape[:-1]  # (rows, n_cam, pixels)
            dist, geom, normal = np.empty(shape), np.empty(shape, np.int32), np.empty(shape + (3,))
            data, model = self._datas[k], self._models[k]
            if self.cull:
                rotations = np.asarray(cam_xmat[rows], np.float64).reshape(len(rows), -1, 3, 3)
                in_view = self._in_view(np.asarray(geom_xpos[rows]), cam_pos,
                                        rotations[:, self.camera.camera_ids]).astype(np.float32)
            for j, i in enumerate(rows):
                data.geom_xpos[:] = geom_xpos[i]
                data.geom_xmat[:] = geom_rot[i]
                data.xipos[:], data.ximat[:] = xipos[i], ximat[i]  # MuJoCo culls by the bodies' bounding volumes
                for c in range(self.camera.n_cameras):
                    if self.cull:
                        model.geom_rgba[self._cast_ids, 3] = in_view[j, c]
                    mujoco.mj_multiRay(model, data, cam_pos[j, c], dirs[j, c].ravel(), self.groups, 1,
                                       int(self.exclude[c]), geom[j, c], dist[j, c], normal[j, c].reshape(-1),
                                       shape[-1], self.cutoff)
            hit = geom >= 0
            return images_from_hits(self.camera, cam_pos, dirs, np.where(hit, dist, np.inf),
                                    self.index[np.maximum(geom, 0)], normal, np)

        if self._pool is None or len(chunks) == 1:
            parts = [work(k) for k in range(len(chunks))]
        else:
            parts = list(self._pool.map(work, range(len(chunks))))
        return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}

    def close(self) -> None:
        """Stop the thread pool."""
        if self._pool is not None:
            self._pool.shutdown()


_POSE_FIELDS = ("geom_xpos", "geom_xmat", "cam_xpos", "cam_xmat", "xpos", "xmat")


@functools.cache
def _host_caster(camera: RayCamera) -> tuple[NativeRayCaster, threading.Lock]:
    return NativeRayCaster(camera.model, camera), threading.Lock()  # one scratch MjData: one call at a time


def render_anywhere(camera: RayCamera, data) -> dict:
    """`legged.sensors.raycam.render` for jitted and vmapped code whatever the camera sees: the JAX caster, or
    for a camera that sees meshes (which it cannot cast) this module's C caster through a host callback, batched
    under vmap. `data`: an mjx.Data, a PhysicsView or raycam.Poses (with the body poses)."""
    if camera.model is None:
        return render(camera, data)
    cfg = camera.config
    shape = (camera.n_cameras, cfg.height, cfg.width)
    out = {"rgb": jax.ShapeDtypeStruct(shape + (3,), jnp.uint8), "depth": jax.ShapeDtypeStruct(shape, jnp.float32),
           "segmentation": jax.ShapeDtypeStruct(shape, jnp.int32), "geom": jax.ShapeDtypeStruct(shape, jnp.int32)}

    def host(*poses):
        lead = poses[0].shape[:-2]  # batch axes before [ngeom, 3]
        flat = [np.asarray(p).reshape((-1,) + p.shape[len(lead):]) for p in poses]
        caster, lock = _host_caster(camera)
        with lock:
            images = caster.render(*flat)
        return {k: images[k].reshape(lead + images[k].shape[1:]) for k in out}

    return jax.pure_callback(host, out, *(getattr(data, k) for k in _POSE_FIELDS), vmap_method="broadcast_all")
