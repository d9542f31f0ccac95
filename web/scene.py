"""MjModel geoms -> viser scene nodes, one node per geom (per environment for moving bodies).

Geoms of bodies welded to the world (floor, ceiling, walls, goal markers) are drawn once at their fixed
pose. Every other body becomes a frame per environment, its geoms children at their body-relative pose,
so a playback frame moves only the bodies. The ceiling is drawn translucent and can be hidden.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import viser

from legged.worlds.mjcf import CEILING_GEOM, SceneOptions
from web.geometry import GeomMesh, MeshOptions, geom_meshes

GROUP_NAMES = {0: "terrain/world", 1: "group 1", 2: "visual", 3: "collision", 4: "group 4", 5: "group 5"}
"""Labels of MuJoCo geom groups in the dashboard (the project's MJCF uses 0, 2 and 3 as named)."""


@dataclasses.dataclass(frozen=True)
class SceneConfig:
    """How the model is drawn."""

    mesh: MeshOptions = MeshOptions()
    """Tessellation of primitives and size of infinite planes."""
    visible_groups: tuple[int, ...] = (0, 1, 2)
    """Geom groups shown at start (MuJoCo's viewer shows 0-2); the others can be switched on."""
    ceiling_geoms: tuple[str, ...] = (CEILING_GEOM,)
    """Names of geoms drawn translucent so that a robot inside a tunnel stays visible."""
    ceiling_opacity: float = SceneOptions.ceiling_alpha
    """Largest opacity of the ceiling geoms (lower if the model's own alpha is lower)."""
    plane_grid: bool = True
    """Draw grid lines on planes (a flat floor is otherwise one uniform colour)."""
    environment_map: str | None = None
    """Viser HDRI for image-based lighting ('warehouse', 'studio', ...); None: plain lights only, which
    software renderers (browsers without a GPU, headless tests) draw many times faster."""
    shadows: bool = False
    """Shadows from the default lights (costly without a GPU)."""


def _rgb(rgba) -> tuple[int, int, int]:
    return tuple(round(255 * min(max(c, 0.0), 1.0)) for c in rgba[:3])


def _quat(mat: np.ndarray) -> np.ndarray:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.asarray(mat, np.float64).ravel())
    return quat


def static_bodies(model: mujoco.MjModel) -> np.ndarray:
    """Mask of bodies that never move: welded to the world and not driven by mocap."""
    mocap = np.asarray(model.body_mocapid) >= 0
    moving = mocap.copy()
    for b in range(1, model.nbody):  # parents come before children in MuJoCo's body order
        moving[b] |= moving[model.body_parentid[b]]
    return (np.asarray(model.body_weldid) == 0) & ~moving


class SceneView:
    """The model's geoms in a viser scene, with `num_envs` copies of the moving bodies."""

    def __init__(self, scene: viser.SceneApi, model: mujoco.MjModel, offsets: np.ndarray,
                 config: SceneConfig = SceneConfig()):
        self.model, self.config = model, config
        self.offsets = np.asarray(offsets, np.float64).reshape(-1, 3)
        self.meshes: list[GeomMesh] = geom_meshes(model, config.mesh)
        self.static = static_bodies(model)
        self.groups_visible = {g: g in config.visible_groups for g in sorted({m.group for m in self.meshes})}
        self.ceiling_visible, self.ceiling_opacity = True, config.ceiling_opacity
        self.geom_nodes: list[tuple[int, int, viser.MeshHandle]] = []
        """(environment or -1 for static geoms, geom id, handle), one per drawn geom."""
        self.body_frames: dict[tuple[int, int], viser.FrameHandle] = {}
        """(environment, body id) -> frame of a moving body."""
        scene.configure_environment_map(config.environment_map)
        scene.configure_default_lights(True, cast_shadow=config.shadows)
        scene.add_light_hemisphere("/lights/sky", sky_color=(255, 255, 255), ground_color=(90, 90, 100),
                                   intensity=1.0)
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        for mesh in self.meshes:
            if self.static[mesh.body]:
                self._add_geom(scene, f"/world/geom{mesh.geom:04d}", mesh, -1,
                               data.geom_xpos[mesh.geom], _quat(data.geom_xmat[mesh.geom]))
                if config.plane_grid and mesh.kind == "plane" and mesh.rgba[3] > 0:  # not invisible walls
                    self._add_grid(scene, mesh, data)
        self._moving = np.flatnonzero(~self.static)
        for env in range(len(self.offsets)):
            for body in self._moving:
                self.body_frames[env, body] = scene.add_frame(f"/env{env}/body{body:03d}", show_axes=False,
                                                              visible=False)
            for mesh in self.meshes:
                if not self.static[mesh.body]:
                    self._add_geom(scene, f"/env{env}/body{mesh.body:03d}/geom{mesh.geom:04d}", mesh, env,
                                   model.geom_pos[mesh.geom], model.geom_quat[mesh.geom])

    # ------------------------------------------------------------------ building
    def _is_ceiling(self, mesh: GeomMesh) -> bool:
        return mesh.name in self.config.ceiling_geoms

    def _opacity(self, mesh: GeomMesh) -> float | None:
        alpha = mesh.rgba[3]
        if self._is_ceiling(mesh):
            alpha = min(alpha, self.ceiling_opacity)
        return None if alpha >= 1.0 else float(alpha)

    def _shown(self, mesh: GeomMesh) -> bool:
        if mesh.rgba[3] <= 0.0:
            return False  # MuJoCo does not draw fully transparent geoms either
        return self.groups_visible[mesh.group] and (self.ceiling_visible or not self._is_ceiling(mesh))

    def _add_geom(self, scene, name, mesh: GeomMesh, env: int, position, wxyz) -> None:
        two_sided = mesh.kind in ("plane", "hfield") or self._is_ceiling(mesh)
        handle = scene.add_mesh_simple(
            name, mesh.vertices, mesh.faces, color=_rgb(mesh.rgba), opacity=self._opacity(mesh),
            side="double" if two_sided else "front", flat_shading=mesh.kind == "hfield",
            cast_shadow=self.config.shadows and not self._is_ceiling(mesh),
            receive_shadow=self.config.shadows and not self._is_ceiling(mesh),
            position=np.asarray(position, np.float64), wxyz=np.asarray(wxyz, np.float64), visible=self._shown(mesh))
        self.geom_nodes.append((env, mesh.geom, handle))

    def _add_grid(self, scene, mesh: GeomMesh, data) -> None:
        extent = np.ptp(mesh.vertices[:, :2], axis=0)
        scene.add_grid(f"/world/grid{mesh.geom:04d}", width=float(extent[0]), height=float(extent[1]),
                       cell_size=0.25, section_size=1.0, cell_color=(120, 130, 140), section_color=(80, 90, 100),
                       position=data.geom_xpos[mesh.geom] + data.geom_xmat[mesh.geom].reshape(3, 3)[:, 2] * 1e-3,
                       wxyz=_quat(data.geom_xmat[mesh.geom]))

    # ------------------------------------------------------------------ updates
    def set_body_poses(self, env: int, xpos: np.ndarray, xquat: np.ndarray) -> None:
        """Place environment `env`'s moving bodies (world positions and quaternions from MjData)."""
        offset = self.offsets[env]
        for body in self._moving:
            frame = self.body_frames[env, body]
            frame.position = xpos[body] + offset
            frame.wxyz = xquat[body]

    def set_robots_visible(self, visible: bool) -> None:
        """Show or hide all moving bodies (hidden until a trajectory is loaded)."""
        for frame in self.body_frames.values():
            frame.visible = visible

    def set_group_visible(self, group: int, visible: bool) -> None:
        """Show or hide every geom of a MuJoCo geom group."""
        self.groups_visible[group] = visible
        self._refresh()

    def set_ceiling(self, visible: bool, opacity: float) -> None:
        """Show or hide the ceiling geoms and set their opacity (0-1)."""
        self.ceiling_visible, self.ceiling_opacity = visible, float(opacity)
        for _, geom, handle in self.geom_nodes:
            mesh = self.meshes[geom]
            if self._is_ceiling(mesh):
                handle.opacity = self._opacity(mesh)
        self._refresh()

    def _refresh(self) -> None:
        for _, geom, handle in self.geom_nodes:
            handle.visible = self._shown(self.meshes[geom])

    def ceiling_nodes(self) -> list[viser.MeshHandle]:
        """Handles of the ceiling geoms."""
        return [h for _, g, h in self.geom_nodes if self._is_ceiling(self.meshes[g])]

    @property
    def centre(self) -> np.ndarray:
        """Centre of the static geometry (where the camera looks first)."""
        return np.asarray(self.model.stat.center, np.float64)
