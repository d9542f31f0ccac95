"""Switchable overlays of a trajectory: planned path and waypoints, current target, height-scan points
(floor and ceiling), contact points, the goal, a navigation's replanned paths (each shown from the frame
it was made on), a vision player's estimate of the ball, goals and opponent, what its camera sighted and where its
tracker puts it."""

from __future__ import annotations

import numpy as np
import viser
from scipy.spatial.transform import Rotation

from web.trajectory import Trajectory

OVERLAYS = {"path": "planned path and waypoints", "target": "current target waypoint",
            "floor_scan": "floor height scan", "ceiling_scan": "ceiling height scan",
            "contacts": "contact points", "goal": "goal", "replans": "replanned paths (navigation)",
            "estimate": "estimated ball, goals, opponent (vision student)",
            "sightings": "ball and goals the camera sees (vision student's detector)",
            "tracked": "where the vision student's tracker puts itself (torso and heading)"}
"""Overlay name -> what it shows (the dashboard's checkbox labels)."""

COLOURS = {"path": (40, 120, 255), "target": (255, 140, 0), "floor_scan": (30, 190, 90),
           "ceiling_scan": (220, 60, 200), "contacts": (230, 20, 20), "goal": (20, 200, 60),
           "replans": (150, 70, 230), "estimate": (255, 230, 0),
           "sightings": (0, 220, 255), "tracked": (255, 0, 200)}
"""Overlay colours (RGB)."""


def quat_from_rpy(rpy: np.ndarray) -> np.ndarray:
    """Quaternions (w, x, y, z) of roll, pitch, yaw angles (..., 3) (rotation z-y-x, as the planner's poses)."""
    rpy = np.asarray(rpy, np.float64)
    quat = Rotation.from_euler("xyz", rpy.reshape(-1, 3)).as_quat(scalar_first=True)
    return quat.reshape(rpy.shape[:-1] + (4,))


class Overlays:
    """Scene nodes of every overlay of one trajectory; `update(frame)` moves the per-frame ones."""

    def __init__(self, scene: viser.SceneApi, traj: Trajectory, shown: dict[str, bool] | None = None):
        self.scene, self.traj = scene, traj
        self.shown = {name: True for name in OVERLAYS} if shown is None else dict(shown)
        self.nodes: dict[str, list] = {name: [] for name in OVERLAYS}
        self._empty: set = set()
        for env in range(traj.num_envs):
            self._add_static(env)
            self._add_dynamic(env)
        self.nodes["contacts"].append(self._points("/overlays/contacts", np.zeros((1, 3)), "contacts", 0.03))

    @property
    def available(self) -> dict[str, bool]:
        """Which overlays this trajectory has data for."""
        t = self.traj
        return {"path": t.paths is not None, "target": t.waypoint is not None, "floor_scan": t.floor_scan is not None,
                "ceiling_scan": t.ceiling_scan is not None, "contacts": True, "goal": t.goal is not None,
                "replans": t.replans is not None, "estimate": t.estimates is not None,
                "sightings": t.sightings is not None, "tracked": t.tracked is not None}

    def _points(self, name, points, kind, size):
        return self.scene.add_point_cloud(name, np.asarray(points, np.float32), COLOURS[kind], point_size=size,
                                          point_shape="circle", precision="float32", visible=self.shown[kind])

    def _add_static(self, env: int) -> None:
        t, offset, root = self.traj, self.traj.offsets[env], f"/overlays/env{env}"
        if t.paths is not None:
            path = t.paths[env, : max(int(t.path_len[env]), 1)].astype(np.float64)
            xyz = path[:, :3] + offset
            if len(xyz) > 1:
                segments = np.stack([xyz[:-1], xyz[1:]], 1)
                self.nodes["path"].append(self.scene.add_line_segments(
                    f"{root}/path/line", segments, COLOURS["path"], thickness=0.01, visible=self.shown["path"]))
            self.nodes["path"].append(self._points(f"{root}/path/waypoints", xyz, "path", 0.035))
            self.nodes["path"].append(self.scene.add_batched_axes(
                f"{root}/path/poses", quat_from_rpy(path[:, 3:6]), xyz, axes_length=0.12, axes_radius=0.006,
                visible=self.shown["path"]))
        if t.replans is not None and env == 0:
            self._replans = []
            for r, (path, n) in enumerate(zip(t.replans, t.replan_len)):
                xyz = path[:max(int(n), 1), :3].astype(np.float64) + offset
                nodes = [self._points(f"{root}/replans/{r}/waypoints", xyz, "replans", 0.03)]
                if len(xyz) > 1:
                    nodes.append(self.scene.add_line_segments(f"{root}/replans/{r}/line", np.stack([xyz[:-1], xyz[1:]], 1),
                                                              COLOURS["replans"], thickness=0.01, visible=False))
                for node in nodes:
                    node.visible = False  # shown from its frame on (update)
                self._replans.append(nodes)
                self.nodes["replans"].extend(nodes)
        if t.goal is not None:
            self.nodes["goal"].append(self.scene.add_icosphere(
                f"{root}/goal", radius=0.08, color=COLOURS["goal"], opacity=0.8,
                position=t.goal[env].astype(np.float64) + offset, visible=self.shown["goal"]))

    def _add_dynamic(self, env: int) -> None:
        t, root = self.traj, f"/overlays/env{env}"
        if t.waypoint is not None and t.paths is not None:
            self.nodes["target"].append(self.scene.add_icosphere(
                f"{root}/target", radius=0.06, color=COLOURS["target"], visible=self.shown["target"]))
        for kind, points, size in (("floor_scan", t.floor_scan, 0.015), ("ceiling_scan", t.ceiling_scan, 0.015),
                                   ("estimate", t.estimates, 0.09)):
            if points is not None:
                self.nodes[kind].append(self._points(f"{root}/{kind}", points[0, env] + t.offsets[env], kind, size))
        for kind, points, size in (("sightings", t.sightings, 0.12), ("tracked", t.tracked, 0.07)):
            if points is not None:  # placed at each frame (update)
                self.nodes[kind].append(self._points(f"{root}/{kind}", np.zeros((1, 3)), kind, size))

    def _place_finite(self, kind: str, env: int, points: np.ndarray) -> None:
        """Show environment `env`'s `kind` node at the finite rows of `points` (k, 3), hidden when there are none."""
        points = points[np.isfinite(points).all(-1)]
        node, key = self.nodes[kind][env], (kind, env)
        if len(points):
            node.points = points.astype(np.float32)
            self._empty.discard(key)
        else:
            self._empty.add(key)
        node.visible = self.shown[kind] and key not in self._empty

    def update(self, frame: int, contacts: np.ndarray) -> None:
        """Move the per-frame overlays to `frame`; `contacts` are world contact points (k, 3) of all envs."""
        t = self.traj
        active = -1  # the newest replan in force at this frame (environment 0)
        if t.replans is not None:
            active = int(np.searchsorted(t.replan_frame, frame, side="right")) - 1
            for r, nodes in enumerate(self._replans):
                for node in nodes:
                    node.visible = self.shown["replans"] and r <= active
        for env in range(t.num_envs):
            offset = t.offsets[env]
            if self.nodes["target"]:
                path, length = (t.replans[active], t.replan_len[active]) if env == 0 and active >= 0 else \
                    (t.paths[env], t.path_len[env])
                index = min(int(t.waypoint[frame, env]), int(length) - 1)
                self.nodes["target"][env].position = path[index, :3].astype(np.float64) + offset
            for kind, points in (("floor_scan", t.floor_scan), ("ceiling_scan", t.ceiling_scan),
                                 ("estimate", t.estimates)):
                if self.nodes[kind]:
                    self.nodes[kind][env].points = (points[frame, env] + offset).astype(np.float32)
            for kind, points in (("sightings", t.sightings), ("tracked", t.tracked)):
                if self.nodes[kind]:  # only what there is at this frame (in view; locked on)
                    self._place_finite(kind, env, points[frame, env] + offset)
        handle = self.nodes["contacts"][0]
        if len(contacts):
            handle.points = np.asarray(contacts, np.float32)
            self._empty.discard("contacts")
        else:
            self._empty.add("contacts")
        handle.visible = self.shown["contacts"] and "contacts" not in self._empty

    def set_visible(self, name: str, visible: bool) -> None:
        """Switch one overlay on or off (replans then appear from their frames on, at the next update)."""
        self.shown[name] = visible
        if name == "replans":
            if not visible:
                for handle in self.nodes[name]:
                    handle.visible = False
            return
        for env, handle in enumerate(self.nodes[name]):
            handle.visible = visible and name not in self._empty and (name, env) not in self._empty

    def remove(self) -> None:
        """Remove every overlay node (before showing another trajectory)."""
        for handles in self.nodes.values():
            for handle in handles:
                handle.remove()
        self.nodes = {name: [] for name in OVERLAYS}
