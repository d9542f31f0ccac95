"""MuJoCo's own OpenGL renderer through a model camera: the reference the ray camera is checked against.

`NativeCamera` renders RGB, z-depth and geom ids (segmentation) with `mjr_render` in an offscreen
buffer. It opens its own GL context: EGL unless MUJOCO_GL names another backend. (`mujoco.Renderer`
picks its backend when mujoco is first imported, from MUJOCO_GL, and falls back to GLFW, which needs a
display; this class works headless whatever was imported first.) Multisampling is switched off in its
copy of the model, so every pixel holds exactly one geom id and one depth, as a ray-cast pixel does.
"""

from __future__ import annotations

import copy
import os

import mujoco
import numpy as np


def _gl_context(width: int, height: int):
    backend = os.environ.get("MUJOCO_GL", "").strip().lower()
    if backend in ("", "egl"):
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.glfw import GLContext
    return GLContext(width, height)


class NativeCamera:
    """Offscreen MuJoCo renderer for a model's fixed cameras at one image size."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int):
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ValueError(f"image {width} x {height} exceeds the model's offscreen buffer "
                             f"{model.vis.global_.offwidth} x {model.vis.global_.offheight}")
        self.model = copy.copy(model)
        self.model.vis.quality.offsamples = 0  # one geom id and one depth per pixel
        self.width, self.height = width, height
        try:
            self._gl = _gl_context(width, height)
        except Exception as exc:
            raise RuntimeError(f"MuJoCo's OpenGL renderer is unavailable ({type(exc).__name__}: {exc}); "
                               "set MUJOCO_GL=egl (or osmesa) where a GL driver exists") from exc
        self._gl.make_current()
        self._ctx = mujoco.MjrContext(self.model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._ctx)
        self._ctx.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(self.model, maxgeom=10000)
        self._option = mujoco.MjvOption()  # MuJoCo's defaults: geom groups 0, 1, 2 visible
        self._rect = mujoco.MjrRect(0, 0, width, height)

    def render(self, data: mujoco.MjData, camera_id: int) -> dict:
        """rgb uint8 [H, W, 3], depth float32 [H, W] (z-depth, metres) and geom int32 [H, W] (-1: nothing)."""
        if not 0 <= camera_id < self.model.ncam:
            raise ValueError(f"camera_id must be in 0..{self.model.ncam - 1}, got {camera_id}")
        self._gl.make_current()
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        cam.fixedcamid = camera_id
        mujoco.mjv_updateScene(self.model, data, self._option, None, cam, mujoco.mjtCatBit.mjCAT_ALL, self._scene)
        h, w = self.height, self.width
        rgb = np.empty((h, w, 3), np.uint8)
        mujoco.mjr_render(self._rect, self._scene, self._ctx)
        mujoco.mjr_readPixels(rgb, None, self._rect, self._ctx)
        flags = self._scene.flags
        flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        try:
            ids = np.empty((h, w, 3), np.uint8)
            raw = np.empty((h, w), np.float32)
            mujoco.mjr_render(self._rect, self._scene, self._ctx)
            mujoco.mjr_readPixels(ids, raw, self._rect, self._ctx)
        finally:
            flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = False
        return {"rgb": np.flipud(rgb).copy(), "depth": np.flipud(self._metric_depth(raw)).copy(),
                "geom": np.flipud(self._geom_ids(ids)).copy()}

    def _metric_depth(self, raw: np.ndarray) -> np.ndarray:
        """Metres along the optical axis from the depth buffer (MuJoCo's reversed-z perspective projection)."""
        extent = self.model.stat.extent
        near = np.float32(self.model.vis.map.znear * extent)
        far = np.float32(self.model.vis.map.zfar * extent)
        c = -(far + near) / (far - near)
        d = -(np.float32(2) * far * near) / (far - near)
        c, d = np.float32(-0.5) * c - np.float32(0.5), np.float32(-0.5) * d  # reversed z: [near, far] -> [1, 0]
        return (d / (raw.astype(np.float64) + c)).astype(np.float32)

    def _geom_ids(self, ids: np.ndarray) -> np.ndarray:
        """Model geom id of each pixel from the segment colours (-1: background or a non-geom object)."""
        ids = ids.astype(np.int64)
        seg = ids[..., 0] + 256 * ids[..., 1] + 65536 * ids[..., 2]  # segid + 1
        table = np.full(self._scene.ngeom + 1, -1, np.int32)
        for g in self._scene.geoms[: self._scene.ngeom]:
            if g.segid >= 0 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                table[g.segid + 1] = g.objid
        return table[np.clip(seg, 0, self._scene.ngeom)]

    def close(self) -> None:
        """Free the GL resources."""
        if getattr(self, "_ctx", None) is not None:
            self._gl.make_current()
            self._ctx.free()
            self._ctx = None
        if getattr(self, "_gl", None) is not None:
            self._gl.free()
            self._gl = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def native_render(model: mujoco.MjModel, data: mujoco.MjData, camera_id: int, width: int, height: int) -> dict:
    """One image from MuJoCo's renderer (rgb, depth, geom; see NativeCamera.render)."""
    with NativeCamera(model, width, height) as camera:
        return camera.render(data, camera_id)
