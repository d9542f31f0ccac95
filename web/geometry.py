"""Triangle meshes of every geom of a compiled MjModel, built from the model itself (pure numpy).

Each geom becomes vertices in its own frame (the frame MuJoCo poses with geom_xpos / geom_xmat), so
any scene or robot can be drawn: planes, height fields, spheres, capsules, ellipsoids, cylinders,
boxes and meshes. A geom of any other type (e.g. an SDF without a mesh) is drawn as its bounding box.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from legged.sensors.raycam import drawn_rgba

GEOM_KINDS = {int(mujoco.mjtGeom.mjGEOM_PLANE): "plane", int(mujoco.mjtGeom.mjGEOM_HFIELD): "hfield",
              int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere", int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
              int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid", int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
              int(mujoco.mjtGeom.mjGEOM_BOX): "box", int(mujoco.mjtGeom.mjGEOM_MESH): "mesh"}
"""Geom type number -> name, for the types drawn exactly."""


@dataclasses.dataclass(frozen=True)
class MeshOptions:
    """How finely primitives are tessellated and how large infinite planes are drawn."""

    segments: int = 20
    """Segments around the axis of spheres, capsules and cylinders."""
    rings: int = 10
    """Rings from pole to pole of spheres (half of them per capsule cap)."""
    plane_half_size: float = 10.0
    """Half width of a plane whose size is 0 (infinite in MuJoCo), metres."""


@dataclasses.dataclass(frozen=True)
class GeomMesh:
    """One geom as a triangle mesh in the geom's frame."""

    geom: int
    """Geom id in the model."""
    name: str
    """Geom name, or 'geom<id>' for an unnamed geom."""
    kind: str
    """Geom type name (plane, hfield, sphere, ..., or 'bbox' for a type drawn as its bounding box)."""
    body: int
    """Body the geom belongs to."""
    group: int
    """Geom group (0-5), as in MuJoCo's visualisation groups."""
    rgba: tuple[float, float, float, float]
    """Colour and opacity, from the geom or (when the geom has the default colour) its material."""
    vertices: np.ndarray
    """(V, 3) float32 vertex positions in the geom frame."""
    faces: np.ndarray
    """(F, 3) uint32 vertex indices, counter-clockwise seen from outside."""


def box_mesh(half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box with half extents `half` (3,): 8 corners, 12 triangles."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return signs * np.asarray(half, np.float64), faces


def _revolve(profile: np.ndarray, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """Surface of revolution about z of a (radius, z) profile from bottom pole to top pole."""
    angles = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles)], -1)
    inner = profile[1:-1]
    verts = [np.array([[0.0, 0.0, profile[0, 1]]])]
    verts += [np.column_stack([r * ring, np.full(segments, z)]) for r, z in inner]
    verts.append(np.array([[0.0, 0.0, profile[-1, 1]]]))
    vertices = np.concatenate(verts)
    faces, top = [], len(vertices) - 1
    idx = lambda k, s: 1 + k * segments + s % segments
    for s in range(segments):
        faces.append([0, idx(0, s + 1), idx(0, s)])
        faces.append([top, idx(len(inner) - 1, s), idx(len(inner) - 1, s + 1)])
        for k in range(len(inner) - 1):
            a, b, c, d = idx(k, s), idx(k, s + 1), idx(k + 1, s), idx(k + 1, s + 1)
            faces += [[a, b, d], [a, d, c]]
    return vertices, np.array(faces)


def sphere_mesh(radii, options: MeshOptions = MeshOptions()) -> tuple[np.ndarray, np.ndarray]:
    """An ellipsoid with semi-axes `radii` (3,) (a sphere when they are equal)."""
    polar = np.linspace(np.pi, 0.0, options.rings + 1)
    vertices, faces = _revolve(np.stack([np.sin(polar), np.cos(polar)], -1), options.segments)
    return vertices * np.asarray(radii, np.float64), faces


def capsule_mesh(radius: float, half_length: float, options: MeshOptions = MeshOptions()):
    """A capsule along z: a cylinder of `half_length` with hemispherical caps of `radius`."""
    half = max(options.rings // 2, 2)
    polar = np.linspace(np.pi, np.pi / 2, half + 1)
    bottom = np.stack([radius * np.sin(polar), radius * np.cos(polar) - half_length], -1)
    top = bottom[::-1] * np.array([1.0, -1.0])
    return _revolve(np.concatenate([bottom, top]), options.segments)


def cylinder_mesh(radius: float, half_length: float, options: MeshOptions = MeshOptions()):
    """A closed cylinder along z."""
    profile = np.array([[0.0, -half_length], [radius, -half_length], [radius, half_length], [0.0, half_length]])
    return _revolve(profile, options.segments)


def plane_mesh(half_x: float, half_y: float) -> tuple[np.ndarray, np.ndarray]:
    """A rectangle in the xy plane facing +z."""
    vertices = np.array([[-half_x, -half_y, 0], [half_x, -half_y, 0], [half_x, half_y, 0], [-half_x, half_y, 0]],
                        np.float64)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]])


def hfield_mesh(model: mujoco.MjModel, hfield: int) -> tuple[np.ndarray, np.ndarray]:
    """A height field's surface (MuJoCo's triangulation) closed by side walls and a bottom at -size[3]."""
    nrow, ncol = int(model.hfield_nrow[hfield]), int(model.hfield_ncol[hfield])
    sx, sy, sz, base = model.hfield_size[hfield]
    start = model.hfield_adr[hfield]
    heights = np.asarray(model.hfield_data[start:start + nrow * ncol], np.float64).reshape(nrow, ncol)
    # Row r lies at y = -sy + 2 sy r / (nrow - 1), column c at x = -sx + 2 sx c / (ncol - 1).
    x = np.linspace(-sx, sx, ncol)
    y = np.linspace(-sy, sy, nrow)
    gx, gy = np.meshgrid(x, y)
    top = np.column_stack([gx.ravel(), gy.ravel(), sz * heights.ravel()])
    r, c = np.meshgrid(np.arange(nrow - 1), np.arange(ncol - 1), indexing="ij")
    v00 = (r * ncol + c).ravel()
    v01, v10, v11 = v00 + 1, v00 + ncol, v00 + ncol + 1
    faces = [np.stack([v00, v01, v11], -1), np.stack([v00, v11, v10], -1)]
    # Side walls: the border loop of the surface joined to a copy of it at the bottom.
    loop = np.concatenate([np.arange(ncol), np.arange(1, nrow) * ncol + ncol - 1,
                           (nrow - 1) * ncol + np.arange(ncol - 2, -1, -1), np.arange(nrow - 2, 0, -1) * ncol])
    bottom = top[loop] * np.array([1.0, 1.0, 0.0]) - np.array([0.0, 0.0, base])
    b = len(top) + np.arange(len(loop))
    a, a_next, b_next = loop, np.roll(loop, -1), np.roll(b, -1)
    faces += [np.stack([a, b, b_next], -1), np.stack([a, b_next, a_next], -1)]
    # Bottom: a fan over the bottom loop (the border is convex: a rectangle).
    faces.append(np.stack([np.full(len(b) - 2, b[0]), b[2:], b[1:-1]], -1))
    return np.concatenate([top, bottom]), np.concatenate(faces)


def mesh_asset(model: mujoco.MjModel, mesh: int) -> tuple[np.ndarray, np.ndarray]:
    """A mesh asset's vertices and faces (already in the frame its geoms are posed in)."""
    v0, nv = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    f0, nf = model.mesh_faceadr[mesh], model.mesh_facenum[mesh]
    return np.asarray(model.mesh_vert[v0:v0 + nv], np.float64), np.asarray(model.mesh_face[f0:f0 + nf])


def _texture_mean(model: mujoco.MjModel, texture: int) -> np.ndarray:
    """Mean RGB (0-1) of a texture's texels."""
    start, channels = model.tex_adr[texture], model.tex_nchannel[texture]
    size = model.tex_width[texture] * model.tex_height[texture] * channels
    texels = np.asarray(model.tex_data[start:start + size], np.float64).reshape(-1, channels)
    return texels[:, :3].mean(0) / 255.0 if channels >= 3 else np.repeat(texels.mean() / 255.0, 3)


def geom_rgba(model: mujoco.MjModel, geom: int) -> tuple[float, float, float, float]:
    """A geom's colour: its own rgba, or (when that is the default) its material's, tinted by the mean
    colour of the material's texture when it has one."""
    rgba, mat = drawn_rgba(model, geom)
    rgba = np.asarray(rgba, np.float64)
    if mat >= 0:
        texture = int(model.mat_texid[mat, int(mujoco.mjtTextureRole.mjTEXROLE_RGB)])
        if texture >= 0:
            rgba[:3] *= _texture_mean(model, texture)
    return tuple(float(v) for v in rgba)


def geom_mesh(model: mujoco.MjModel, geom: int, options: MeshOptions = MeshOptions()) -> GeomMesh:
    """The triangle mesh of one geom, in its own frame."""
    gtype, size = int(model.geom_type[geom]), np.asarray(model.geom_size[geom], np.float64)
    kind = GEOM_KINDS.get(gtype, "bbox")
    data = int(model.geom_dataid[geom])
    if kind == "plane":
        half = [s if s > 0 else options.plane_half_size for s in size[:2]]
        vertices, faces = plane_mesh(*half)
    elif kind == "hfield":
        vertices, faces = hfield_mesh(model, data)
    elif kind in ("sphere", "ellipsoid"):
        vertices, faces = sphere_mesh(size[:3] if kind == "ellipsoid" else np.full(3, size[0]), options)
    elif kind == "capsule":
        vertices, faces = capsule_mesh(size[0], size[1], options)
    elif kind == "cylinder":
        vertices, faces = cylinder_mesh(size[0], size[1], options)
    elif kind == "box":
        vertices, faces = box_mesh(size[:3])
    elif kind == "mesh" or (data >= 0 and gtype == int(mujoco.mjtGeom.mjGEOM_SDF)):
        kind = "mesh"
        vertices, faces = mesh_asset(model, data)
    else:
        aabb = np.asarray(model.geom_aabb[geom], np.float64)
        vertices, faces = box_mesh(aabb[3:])
        vertices = vertices + aabb[:3]
    name = model.geom(geom).name or f"geom{geom}"
    return GeomMesh(geom=geom, name=name, kind=kind, body=int(model.geom_bodyid[geom]),
                    group=int(model.geom_group[geom]), rgba=geom_rgba(model, geom),
                    vertices=np.ascontiguousarray(vertices, np.float32),
                    faces=np.ascontiguousarray(faces, np.uint32))


def geom_meshes(model: mujoco.MjModel, options: MeshOptions = MeshOptions()) -> list[GeomMesh]:
    """Meshes of all geoms of the model, in geom id order."""
    return [geom_mesh(model, g, options) for g in range(model.ngeom)]
