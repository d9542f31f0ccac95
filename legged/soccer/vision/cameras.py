"""The soccer robots' egocentric cameras: ray-cast images, MuJoCo's reference images and their agreement."""

from __future__ import annotations

import time
from pathlib import Path

import jax
import mujoco
import numpy as np

from legged.sensors.native_camera import NativeCamera
from legged.sensors.native_raycam import render_anywhere
from legged.sensors.raycam import (
    BALL,
    GOAL,
    GROUND,
    LINE,
    NONE,
    OPPONENT,
    OWN_TEAM,
    RayCamera,
    RayCameraConfig,
    poses_of,
    render,
)
from legged.soccer.layout import SoccerLayout


def soccer_geom_classes(model: mujoco.MjModel, layout: SoccerLayout) -> np.ndarray:
    """Segmentation class of every geom as each agent's camera sees it, [n_agents, ngeom].

    Floor: ground; painted lines: line; ball; goal parts: goal; robots: own team or opponent, relative
    to the agent whose camera looks; anything else (walls): none.
    """
    base = np.full(model.ngeom, NONE, dtype=np.int32)
    base[layout.floor_geom] = GROUND
    base[layout.line_geoms] = LINE
    base[layout.ball_geom] = BALL
    base[layout.goal_geoms.ravel()] = GOAL
    classes = np.tile(base, (layout.n_agents, 1))
    robot = layout.geom_agent >= 0
    geom_team = layout.team[np.maximum(layout.geom_agent, 0)]
    for a in range(layout.n_agents):
        classes[a, robot] = np.where(geom_team[robot] == layout.team[a], OWN_TEAM, OPPONENT)
    return classes


def soccer_camera(model: mujoco.MjModel, config: RayCameraConfig = RayCameraConfig(),
                  layout: SoccerLayout | None = None) -> RayCamera:
    """Ray camera over every agent's head camera, in agent order (home players first)."""
    layout = SoccerLayout.from_model(model) if layout is None else layout
    return RayCamera.build(model, layout.head_camera, config, soccer_geom_classes(model, layout))


def classes_of_geoms(model: mujoco.MjModel, geom_ids: np.ndarray, layout: SoccerLayout | None = None) -> np.ndarray:
    """Segmentation classes of geom-id images from every agent's camera, [n_agents, H, W] (e.g. MuJoCo's
    renderer's), by `soccer_geom_classes`; -1 (nothing) maps to class 0."""
    layout = SoccerLayout.from_model(model) if layout is None else layout
    table = soccer_geom_classes(model, layout)  # [n_agents, ngeom], agent order = camera order
    out = np.empty(geom_ids.shape, dtype=np.int32)
    for c in range(geom_ids.shape[0]):
        ids = geom_ids[c]
        out[c] = np.where(ids >= 0, table[c][np.maximum(ids, 0)], NONE)
    return out


def agreement(ray: dict, native_classes: np.ndarray, native_depth: np.ndarray) -> dict:
    """Per-camera and overall agreement of the ray camera with MuJoCo's renderer.

    segmentation: fraction of pixels with the same class. depth_median_abs_error: median |z-depth
    difference| in metres over the pixels where both hit something; depth_within_5cm: the fraction of
    those pixels whose depths differ by less than 5 cm.
    """
    seg = np.asarray(ray["segmentation"])
    depth = np.asarray(ray["depth"])
    same = seg == native_classes
    both = (seg != NONE) & (native_classes != NONE)
    err = np.abs(depth - native_depth)
    per = []
    for c in range(seg.shape[0]):
        e = err[c][both[c]]
        per.append({"segmentation": float(same[c].mean()),
                    "depth_median_abs_error": float(np.median(e)) if e.size else 0.0,
                    "depth_within_5cm": float((e < 0.05).mean()) if e.size else 1.0})
    e = err[both]
    return {"segmentation": float(same.mean()),
            "depth_median_abs_error": float(np.median(e)) if e.size else 0.0,
            "depth_within_5cm": float((e < 0.05).mean()) if e.size else 1.0,
            "per_camera": per}


def native_images(model: mujoco.MjModel, data: mujoco.MjData, camera: RayCamera,
                  layout: SoccerLayout | None = None) -> dict:
    """MuJoCo's renderer through the same cameras at the same size: rgb, depth, geom, segmentation (classes from
    `layout`, default: the project's scene layout read from `model`)."""
    cfg = camera.config
    with NativeCamera(model, cfg.width, cfg.height) as native:
        shots = [native.render(data, int(c)) for c in camera.camera_ids]
    out = {k: np.stack([s[k] for s in shots]) for k in ("rgb", "depth", "geom")}
    out["segmentation"] = classes_of_geoms(model, out["geom"], layout)
    return out


def _write_png(path: Path, rgb: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(np.asarray(rgb, dtype=np.uint8)).save(path)


def ray_images(model: mujoco.MjModel, data: mujoco.MjData, camera: RayCamera) -> tuple[dict, str]:
    """The ray camera's images of `data` and the caster that made them: the JAX caster ("jax"), or MuJoCo's C
    caster ("c") where the camera sees meshes, which only the C caster casts."""
    images = jax.jit(lambda d: render_anywhere(camera, d))(poses_of(data))
    return {k: np.asarray(v) for k, v in images.items()}, "jax" if camera.model is None else "c"


def write_camera_images(scene_model: mujoco.MjModel, data: mujoco.MjData, out_dir,
                        config: RayCameraConfig = RayCameraConfig(), layout: SoccerLayout | None = None) -> dict:
    """Write DIR/agent<i>_ray.png (the ray camera: `ray_images`) and DIR/agent<i>_native.png (MuJoCo's renderer,
    same camera, same size) for every agent; return the agreement figures (see `agreement`), the caster and the
    paths. `layout`: the scene's (default: read from `scene_model`, the project's robots).

    `data` must be forward-computed (mj_forward) so camera and geom poses are current.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OSError(f"cannot create output directory {out}: {exc.strerror}") from exc
    camera = soccer_camera(scene_model, config, layout)
    ray, caster = ray_images(scene_model, data, camera)
    native = native_images(scene_model, data, camera, layout)
    figures = agreement(ray, native["segmentation"], native["depth"])
    paths = {"ray": [], "native": []}
    for i in range(camera.n_cameras):
        for kind, rgb in (("ray", ray["rgb"][i]), ("native", native["rgb"][i])):
            path = out / f"agent{i}_{kind}.png"
            _write_png(path, rgb)
            paths[kind].append(str(path))
    return {**figures, "caster": caster, "width": config.width, "height": config.height, "files": paths}


def time_render(model: mujoco.MjModel, data: mujoco.MjData, batch_sizes=(1, 8, 64), repeats: int = 5,
                config: RayCameraConfig = RayCameraConfig()) -> dict:
    """Seconds per batched render call (all agents' cameras) after compilation, per batch size (measured,
    for benchmarks and reports; not asserted anywhere)."""
    camera = soccer_camera(model, config)
    fn = jax.jit(jax.vmap(lambda d: render(camera, d)))
    poses = poses_of(data)
    out = {}
    for n in batch_sizes:
        batch = jax.tree_util.tree_map(lambda x, n=n: np.broadcast_to(x, (n,) + x.shape).copy(), poses)
        jax.block_until_ready(fn(batch))  # compile
        start = time.perf_counter()
        for _ in range(repeats):
            jax.block_until_ready(fn(batch))
        per_call = (time.perf_counter() - start) / repeats
        out[n] = {"seconds_per_call": per_call, "seconds_per_image": per_call / (n * camera.n_cameras)}
    return out
