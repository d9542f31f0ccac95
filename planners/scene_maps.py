"""Floor and ceiling maps of any MuJoCo scene, sampled with MuJoCo's own ray casting.

For every grid column the solid intervals of every static obstacle geom are found with two vertical
rays (one from above, one from below) against that geom alone, so boxes, meshes, height fields and
planes all work and overlapping geoms do not confuse the result. The free gap that contains the
reference height is the column's gap: the floor is the top of the highest solid below it, the ceiling
the bottom of the lowest solid above it. A column whose reference height lies inside a solid is a wall.

Samples sit on grid points, so a wall edge between two samples would be smoothed into a ramp; the maps
are therefore dilated by one cell (floor: maximum of the 3 x 3 neighbourhood, ceiling: minimum, with
`scipy.ndimage.maximum_filter` / `minimum_filter`), which makes them conservative. Scenes with several
storeys are sampled at the storey of the reference height.
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np
from scipy import ndimage

from legged.worlds.maps import HeightMaps

VOID_DEPTH = 1.0
"""A column with no floor below the reference height gets a floor this far below it (a void)."""
OPEN_HEIGHT = 2.0
"""A column with no ceiling above the reference height gets a ceiling this far above it."""


def obstacle_geoms(model: mujoco.MjModel) -> list[int]:
    """Geoms fixed to the world that take part in collisions (by contype/conaffinity or a contact pair)."""
    in_pair = set(model.pair_geom1.tolist()) | set(model.pair_geom2.tolist())
    out = []
    for g in range(model.ngeom):
        static = model.body_weldid[model.geom_bodyid[g]] == 0
        collides = (model.geom_contype[g] | model.geom_conaffinity[g]) != 0 or g in in_pair
        if static and collides:
            out.append(g)
    return out


def _is_plane(model, g) -> bool:
    return model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE


def _xy_box(model, data, g) -> tuple[np.ndarray, np.ndarray, float, float]:
    """World-aligned bounding box of a geom: xy low, xy high, z low, z high."""
    centre_local, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    rot = data.geom_xmat[g].reshape(3, 3)
    centre = data.geom_xpos[g] + rot @ centre_local
    extent = np.abs(rot) @ half
    return centre[:2] - extent[:2], centre[:2] + extent[:2], centre[2] - extent[2], centre[2] + extent[2]


def _ray(model, data, g, point, direction) -> float:
    """Distance along a ray to geom g alone (-1 on a miss)."""
    kind = model.geom_type[g]
    if kind == mujoco.mjtGeom.mjGEOM_HFIELD:
        return mujoco.mj_rayHfield(model, data, g, point, direction)
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        return mujoco.mj_rayMesh(model, data, g, point, direction)
    return mujoco.mju_rayGeom(data.geom_xpos[g], data.geom_xmat[g], model.geom_size[g], point, direction, kind)


def scene_bounds(model: mujoco.MjModel, data: mujoco.MjData, geoms: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal extent of the bounded obstacle geoms (infinite planes excluded)."""
    boxes = [_xy_box(model, data, g) for g in geoms if not _is_plane(model, g)]
    if not boxes:
        raise ValueError("the scene has no bounded obstacle geoms; give the map bounds explicitly")
    return np.min([b[0] for b in boxes], 0), np.max([b[1] for b in boxes], 0)


def _solid_intervals(model, data, g, xy, z_bottom, z_top) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest z of geom g on each column xy (nan where the column misses it)."""
    lo, hi = np.full(len(xy), np.nan), np.full(len(xy), np.nan)
    if _is_plane(model, g):
        normal_z = data.geom_xmat[g].reshape(3, 3)[2, 2]
        if abs(normal_z) < 1e-6:
            raise ValueError(f"geom {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or g} is a vertical "
                             "plane, which vertical rays cannot sample; model the wall as a box")
    down, up = np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0])
    for k, (x, y) in enumerate(xy):
        d_down = _ray(model, data, g, np.array([x, y, z_top]), down)
        d_up = _ray(model, data, g, np.array([x, y, z_bottom]), up)
        if _is_plane(model, g):  # a plane is a half space: solid below (facing up) or above (facing down)
            if d_down >= 0:
                lo[k], hi[k] = -np.inf, z_top - d_down
            elif d_up >= 0:
                lo[k], hi[k] = z_bottom + d_up, np.inf
        elif d_down >= 0 and d_up >= 0:
            lo[k], hi[k] = z_bottom + d_up, z_top - d_down
    return lo, hi


def maps_from_scene(model: mujoco.MjModel, reference_z: float | Callable[[np.ndarray], np.ndarray],
                    resolution: float = 0.05, bounds=None, dilate: bool = True) -> HeightMaps:
    """Sample the floor and ceiling of a compiled scene on a grid by ray casting (see module docstring).

    `reference_z` is the height of the free space to sample (a number, or a function of world xy (n, 2)),
    for a robot usually its body-centre height. `bounds` = ((x_lo, y_lo), (x_hi, y_hi)); by default the
    extent of the scene's bounded obstacle geoms.
    """
    if resolution <= 0:
        raise ValueError(f"resolution must be > 0, got {resolution}")
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    geoms = obstacle_geoms(model)
    if not geoms:
        raise ValueError("the scene has no static geoms that collide; nothing to plan around")
    lo_xy, hi_xy = (np.asarray(b, float) for b in bounds) if bounds is not None else scene_bounds(model, data, geoms)
    shape = np.floor((hi_xy - lo_xy) / resolution + 1e-9).astype(int) + 1
    if np.any(shape < 2):
        raise ValueError(f"map bounds {lo_xy}..{hi_xy} are smaller than two samples at resolution {resolution}")
    xs, ys = lo_xy[0] + resolution * np.arange(shape[0]), lo_xy[1] + resolution * np.arange(shape[1])
    xy = np.stack(np.meshgrid(xs, ys, indexing="ij"), -1).reshape(-1, 2)
    ref = np.broadcast_to(reference_z(xy) if callable(reference_z) else float(reference_z), len(xy)).astype(float)

    boxes = {g: _xy_box(model, data, g) for g in geoms}
    bounded = [b for g, b in boxes.items() if not _is_plane(model, g)]
    z_top = max([b[3] for b in bounded] + [ref.max()]) + 1.0
    z_bottom = min([b[2] for b in bounded] + [ref.min()]) - 1.0
    floor, ceiling = np.full(len(xy), -np.inf), np.full(len(xy), np.inf)
    wall_top = np.full(len(xy), -np.inf)
    for g in geoms:
        near = np.ones(len(xy), bool) if _is_plane(model, g) else np.all(
            (xy >= boxes[g][0] - 1e-9) & (xy <= boxes[g][1] + 1e-9), axis=1)
        if not near.any():
            continue
        lo, hi = np.full(len(xy), np.nan), np.full(len(xy), np.nan)
        lo[near], hi[near] = _solid_intervals(model, data, g, xy[near], z_bottom, z_top)
        hit = ~np.isnan(lo)
        below, above = hit & (hi < ref), hit & (lo > ref)
        inside = hit & ~below & ~above
        floor[below] = np.maximum(floor[below], hi[below])
        ceiling[above] = np.minimum(ceiling[above], lo[above])
        wall_top[inside] = np.maximum(wall_top[inside], np.minimum(hi[inside], z_top))
    floor = np.where(np.isinf(floor), ref - VOID_DEPTH, floor)
    ceiling = np.where(np.isinf(ceiling), ref + OPEN_HEIGHT, ceiling)
    wall = np.isfinite(wall_top)
    floor, ceiling = np.where(wall, wall_top, floor), np.where(wall, wall_top, ceiling)
    floor, ceiling = floor.reshape(shape), ceiling.reshape(shape)
    if dilate:
        # 3 x 3 neighbourhood maximum / minimum, edges padded with themselves
        floor = ndimage.maximum_filter(floor, size=3, mode="nearest")
        ceiling = ndimage.minimum_filter(ceiling, size=3, mode="nearest")
    return HeightMaps(floor=floor, ceiling=ceiling, resolution=resolution, origin=lo_xy.copy(),
                      ceiling_anti_diagonal=False, source="scene ray casting")


def reference_between(start, goal) -> Callable[[np.ndarray], np.ndarray]:
    """Reference height that varies linearly from the start's z to the goal's z along start -> goal."""
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    axis = goal[:2] - start[:2]
    length2 = max(float(axis @ axis), 1e-12)

    def reference(xy: np.ndarray) -> np.ndarray:
        t = np.clip((xy - start[:2]) @ axis / length2, 0.0, 1.0)
        return start[2] + t * (goal[2] - start[2])

    return reference


def navigation_maps(model: mujoco.MjModel, start, goal, resolution: float = 0.025, margin: float = 1.0) -> HeightMaps:
    """The maps of a scene for a navigation from `start` to `goal` (body centres): sampled at the height between
    them, over the bounded obstacle geoms' extent and the start and goal with `margin` metres around them, so that
    an open scene (a floor plane and nothing else, or a few posts) has a map too."""
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    lo, hi = np.minimum(start[:2], goal[:2]) - margin, np.maximum(start[:2], goal[:2]) + margin
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    geoms = obstacle_geoms(model)
    if not geoms:
        raise ValueError("the scene has no static geoms that collide (not even a floor); nothing to walk on")
    hit = np.zeros(1, np.int32)
    for name, point in (("start", start), ("goal", goal)):
        if mujoco.mj_ray(model, data, point[:3], np.array([0.0, 0.0, -1.0]), None, 1, -1, hit) < 0:
            raise ValueError(f"the {name} ({', '.join(f'{v:g}' for v in point[:3])}) is off the scene: nothing "
                             "below it to stand on")
    boxes = [_xy_box(model, data, g) for g in geoms if not _is_plane(model, g)]
    if boxes:
        lo = np.minimum(lo, np.min([b[0] for b in boxes], 0))
        hi = np.maximum(hi, np.max([b[1] for b in boxes], 0))
    return maps_from_scene(model, reference_between(start, goal), resolution, bounds=(lo, hi))
