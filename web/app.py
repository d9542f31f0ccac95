"""The dashboard server: a viser scene of the model, playback of a trajectory, overlays and panels.

    dashboard = Dashboard(DashboardConfig(port=8080), source=RolloutSource(env, task))
    print(dashboard.start())   # the address; rollouts are recorded in the background
    dashboard.wait()           # until Ctrl-C
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import threading
import time
import traceback
from pathlib import Path

import numpy as np
import viser

from policies.run_dir import RunDir
from web.camera import DepthCamera, DepthCameraConfig
from web.kinematics import Kinematics
from web.overlays import OVERLAYS, Overlays
from web.panels import CheckpointPicker, ImagePanel, RolloutPlots, TrainingCurves
from web.player import Player
from web.scene import GROUP_NAMES, SceneConfig, SceneView
from web.source import RolloutSource, check_port
from web.trajectory import Trajectory

CAMERA_OFFSET = np.array([-1.2, -1.2, 0.9])
"""Where the viewer's camera sits relative to the robot it looks at, metres."""
TUNNEL_CAMERA_OFFSET = np.array([-0.7, -0.3, 0.12])
"""The same in confined worlds (trajectories with planned paths): behind the robot inside the tunnel, under
its ceiling, so that a first view shows the robot in the tunnel rather than the roof from above."""


@dataclasses.dataclass(frozen=True)
class DashboardConfig:
    """Server address and playback settings."""

    host: str = "127.0.0.1"
    """Address to bind (127.0.0.1: this machine only; reach it over SSH with a port forward)."""
    port: int = 8080
    """Port to bind (0: any free port)."""
    steps: int = 500
    """Control steps per recorded rollout."""
    seed: int = 0
    """Seed of the first rollout."""
    fps: float = 30.0
    """Highest rate at which playback updates the scene, frames per second."""
    poll_seconds: float = 2.0
    """How often the run directory is re-read for new metrics and checkpoints, seconds."""
    scene: SceneConfig = SceneConfig()
    """How the model is drawn."""
    camera: DepthCameraConfig = DepthCameraConfig()
    """Depth view shown in the image panel when the trajectory has no camera images."""
    camera_hz: float = 5.0
    """Highest rate of camera image updates while playing (ray casting is the costliest part of a frame)."""
    label: str = "legged dashboard"
    """Title of the control panel."""


class Dashboard:
    """Serves one model; plays a fixed trajectory or rolls out `source` (re-recordable from the page)."""

    def __init__(self, config: DashboardConfig = DashboardConfig(), source: RolloutSource | None = None,
                 trajectory: Trajectory | None = None, run_dir: str | Path | None = None):
        if (source is None) == (trajectory is None):
            raise ValueError("give the dashboard either a rollout source or a trajectory")
        self.config, self.source = config, source
        self.run_dir = Path(run_dir) if run_dir is not None else (source.run_dir if source else None)
        self.model = source.env.mj_model if source is not None else trajectory.model
        self.traj: Trajectory | None = trajectory
        self.server: viser.ViserServer | None = None
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._recording = threading.Lock()
        self.overlays: Overlays | None = None
        self._camera_time = 0.0
        self.errors: list[str] = []
        """Messages of failed background rollouts or checkpoint loads (also shown on the page)."""

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> str:
        """Start serving; returns the address. Records the first rollout in the background if needed."""
        cfg = self.config
        check_port(cfg.host, cfg.port)
        with contextlib.redirect_stdout(io.StringIO()):  # viser's own address banner; we print ours
            self.server = viser.ViserServer(host=cfg.host, port=cfg.port, label=cfg.label, verbose=False)
        if cfg.port and self.server.get_port() != cfg.port:  # taken between the check and the bind
            self.server.stop()
            raise OSError(f"port {cfg.port} on {cfg.host} is in use; choose another with --port")
        self.kinematics = Kinematics(self.model)
        self.camera = DepthCamera(self.model, cfg.camera)
        offsets = self.traj.offsets if self.traj is not None else self.source.recorder.offsets
        self.view = SceneView(self.server.scene, self.model, offsets, cfg.scene)
        self._build_gui()
        if self.traj is not None:
            self._show(self.traj)
        else:
            self.rerecord(cfg.seed)
        if self.run_dir is not None:
            threading.Thread(target=self._poll, name="dashboard-poll", daemon=True).start()
        return self.url

    @property
    def url(self) -> str:
        """Address of the page."""
        host = self.config.host
        shown = "127.0.0.1" if host in ("0.0.0.0", "") else (f"[{host}]" if ":" in host else host)
        return f"http://{shown}:{self.server.get_port()}"

    def wait(self) -> None:
        """Block until Ctrl-C or `stop()`."""
        try:
            while not self._stop.wait(0.5):
                pass
        except KeyboardInterrupt:
            pass
        finally:
            self.stop()

    def stop(self) -> None:
        """Stop playback, polling and the server (idempotent)."""
        self._stop.set()
        if getattr(self, "player", None) is not None:
            self.player.close()
            self.player = None
        if self.server is not None:
            self.server.stop()
            self.server = None

    # ------------------------------------------------------------------ GUI
    def _build_gui(self) -> None:
        gui = self.server.gui
        self.status = gui.add_markdown("Starting ...")
        self.progress = gui.add_progress_bar(0.0, visible=False)
        self.player = Player(gui, self._render, self.config.fps)
        tabs = gui.add_tab_group()
        with tabs.add_tab("Rollout", viser.Icon.ROBOT):
            self._build_rollout_tab(gui)
        with tabs.add_tab("Overlays", viser.Icon.LAYERS_INTERSECT):
            self._build_overlay_tab(gui)
        with tabs.add_tab("Plots", viser.Icon.CHART_LINE):
            self.plots = RolloutPlots(gui)
        self.curves = self.picker = None
        if self.run_dir is not None:
            with tabs.add_tab("Training", viser.Icon.TRENDING_UP):
                self.curves = TrainingCurves(gui, RunDir(self.run_dir))
                if self.source is not None:
                    self.picker = CheckpointPicker(gui, self.source.checkpoints, self._load_checkpoint,
                                                   self.source.policy.checkpoint if self.source.policy else None)
        with tabs.add_tab("Camera", viser.Icon.CAMERA):
            self.show_camera = gui.add_checkbox("Show camera", True, hint="update the image while playing")
            self.image = ImagePanel(gui, "camera", (self.config.camera.height, self.config.camera.width), scale=5)
            self.image_note = gui.add_markdown("")

    def _build_rollout_tab(self, gui) -> None:
        n = len(self.view.offsets)
        self.env_choice = gui.add_dropdown("Environment", [f"env {e}" for e in range(n)],
                                           hint="environment shown in the plots and the camera")
        self.env_choice.on_update(lambda _: self._env_changed())
        look = gui.add_button("Look at robot", icon=viser.Icon.FOCUS_2)
        look.on_click(lambda event: self._look_at(event.client))
        rollout = self.source is not None
        self.seed = gui.add_number("Seed", self.config.seed, step=1, disabled=not rollout,
                                   hint="reset key: on tiled terrains it also picks the world")
        self.steps = gui.add_number("Steps", self.config.steps, min=1, step=1, disabled=not rollout)
        again = gui.add_button("Reset (this seed)", icon=viser.Icon.REFRESH, disabled=not rollout)
        again.on_click(lambda _: self.rerecord(int(self.seed.value)))
        new = gui.add_button("New world / seed", icon=viser.Icon.ARROWS_SHUFFLE, disabled=not rollout)
        new.on_click(lambda _: self._next_seed())
        save = gui.add_button("Download trajectory", icon=viser.Icon.CLOUD_DOWNLOAD,
                              hint="the shown rollout as .npz; play it with legged view --trajectory FILE")
        save.on_click(lambda event: self._download(event.client))

    def _build_overlay_tab(self, gui) -> None:
        self.overlay_boxes = {}
        for name, label in OVERLAYS.items():
            box = gui.add_checkbox(label, True)
            box.on_update(lambda event, name=name: self._toggle_overlay(name, event.target.value))
            self.overlay_boxes[name] = box
        if self.view.ceiling_nodes():
            ceiling = gui.add_checkbox("ceiling", True, hint="hide the ceiling to look into tunnels from above")
            opacity = gui.add_slider("ceiling opacity", 0.05, 1.0, 0.05, self.view.ceiling_opacity)
            update = lambda _: self.view.set_ceiling(ceiling.value, opacity.value)
            ceiling.on_update(update)
            opacity.on_update(update)
        for group, visible in self.view.groups_visible.items():
            box = gui.add_checkbox(f"geom group {group} ({GROUP_NAMES.get(group, '')})", visible)
            box.on_update(lambda event, group=group: self.view.set_group_visible(group, event.target.value))

    # ------------------------------------------------------------------ actions
    def _set_status(self, text: str) -> None:
        self.status.content = text

    def _next_seed(self) -> None:
        self.seed.value = int(self.seed.value) + 1
        self.rerecord(int(self.seed.value))

    def rerecord(self, seed: int, wait: bool = False) -> None:
        """Record a new rollout with `seed` in the background (`wait`: until it is shown); refused with a
        notice while another is being recorded."""
        if self.source is None:
            return
        if not self._recording.acquire(blocking=False):
            self._notify("a rollout is being recorded; try again when it is shown")
            return
        thread = threading.Thread(target=self._record, args=(seed,), name="dashboard-record", daemon=True)
        thread.start()
        if wait:
            thread.join()

    def _record(self, seed: int) -> None:
        try:
            first = self.traj is None
            note = " (the first one compiles the environment: about a minute on a CPU)" if first else ""
            self._set_status(f"**{self.source.task}** — recording seed {seed} with "
                             f"{self.source.policy_name}{note} ...")
            self.progress.visible, self.progress.value = True, 0.0

            def progress(done: int, total: int) -> None:
                self.progress.value = 100.0 * done / total

            traj = self.source.record(int(self.steps.value), seed, progress)
            if not self._stop.is_set():
                self._show(traj)
        except Exception as exc:  # a failed rollout must not take the page down
            self._error(f"rollout with seed {seed} failed: {exc}")
            traceback.print_exc()
        finally:
            self.progress.visible = False
            self._recording.release()

    def _load_checkpoint(self, path: Path) -> None:
        try:
            self.source.load_checkpoint(path)
        except Exception as exc:
            self._error(f"checkpoint {path.name} not loaded: {exc}")
            return
        self.rerecord(int(self.seed.value))

    def _download(self, client) -> None:
        with self._lock:
            traj = self.traj
        if traj is not None and client is not None:
            name = f"{traj.info.get('task', 'rollout').split()[0]}-seed{traj.info.get('seed', 0)}.npz"
            client.send_file_download(name, traj.to_bytes())

    def _error(self, message: str) -> None:
        self.errors.append(message)
        self._set_status(f"**Error:** {message}")
        self._notify(message, "red")

    def _notify(self, message: str, color: str = "blue") -> None:
        if self.server is not None:
            for client in self.server.get_clients().values():
                client.add_notification("legged dashboard", message, color=color, auto_close_seconds=8.0)

    def _toggle_overlay(self, name: str, visible: bool) -> None:
        with self._lock:
            if self.overlays is not None:
                self.overlays.set_visible(name, visible)
                if name == "replans" and visible:  # which replans show depends on the frame
                    self._render(self.player.frame)

    def _env_changed(self) -> None:
        with self._lock:
            if self.traj is not None:
                self.plots.show(self.traj, self._env())
                self._render(self.player.frame)

    def _env(self) -> int:
        return int(self.env_choice.value.split()[-1])

    def _look_at(self, client) -> None:
        if self.traj is None:
            return
        base = self._base_position(self.player.frame, self._env())
        clients = [client] if client is not None else list(self.server.get_clients().values())
        for c in clients:
            c.camera.look_at = base
            c.camera.position = base + self._camera_offset()

    def _camera_offset(self) -> np.ndarray:
        """Where the camera sits relative to the robot: inside the tunnel in confined worlds."""
        return TUNNEL_CAMERA_OFFSET if self.traj is not None and self.traj.paths is not None else CAMERA_OFFSET

    def _base_position(self, frame: int, env: int) -> np.ndarray:
        with self._lock:  # the MjData is shared with playback
            self.kinematics.set_qpos(self.traj.qpos[frame, env])
            return self.kinematics.xpos[self.camera.body].astype(np.float64) + self.traj.offsets[env]

    # ------------------------------------------------------------------ showing a trajectory
    def _show(self, traj: Trajectory) -> None:
        with self._lock:
            first = self.overlays is None
            self.traj = traj
            if self.overlays is not None:
                self.overlays.remove()
            shown = {name: box.value for name, box in self.overlay_boxes.items()}
            self.overlays = Overlays(self.server.scene, traj, shown)
            for name, available in self.overlay_boxes.items():
                available.disabled = not self.overlays.available[name]
            self.plots.show(traj, self._env())
            self.image_note.content = ("camera observation recorded by the task" if traj.camera is not None else
                                       "depth view from the front of the robot (MuJoCo rays; near = yellow)")
            self.view.set_robots_visible(True)
        self.player.load(traj.num_frames, traj.dt)  # outside our lock: the player locks itself, then us
        base = self._base_position(0, self._env())  # a new rollout may start in another world: go there
        if first:
            self.server.initial_camera.look_at = base
            self.server.initial_camera.position = base + self._camera_offset()
        self._look_at(None)
        info = traj.info
        worlds = ""
        if self.source is not None and traj.paths is not None:
            worlds = f", {self.source.env.terrain.num_tiles} world(s) in the terrain"
        against = f" against {info['opponent']}" if info.get("opponent") else ""
        against += f", steered from its estimate by {info['pilot']}" if info.get("pilot") else ""
        self._set_status(f"**{info.get('task', '?')}** — {info.get('policy', 'recorded trajectory')}{against}, "
                         f"seed {info.get('seed', '?')}, {traj.num_envs} env(s), {traj.num_frames - 1} steps{worlds}")

    def _render(self, frame: int) -> None:
        """Put every environment at `frame`: body poses, overlays and (at most camera_hz times a second
        while playing) the camera image."""
        with self._lock:
            traj = self.traj
            if traj is None or frame >= traj.num_frames:
                return
            collide = self.overlays is not None and self.overlays.shown["contacts"]
            now = time.perf_counter()
            camera_due = self.show_camera.value and (not self.player.playing or
                                                      now - self._camera_time >= 1.0 / self.config.camera_hz)
            contacts, chosen = [], self._env()
            with self.server.atomic():
                for env in range(traj.num_envs):
                    data = self.kinematics.set_qpos(traj.qpos[frame, env], collide=collide)
                    self.view.set_body_poses(env, data.xpos, data.xquat)
                    if collide:
                        contacts.append(self.kinematics.contact_points() + traj.offsets[env])
                    if env == chosen and camera_due:
                        self._camera_time = now
                        self.image.show(traj.camera[frame, env] if traj.camera is not None
                                        else self.camera.render(data))
                if self.overlays is not None:
                    self.overlays.update(frame, np.concatenate(contacts) if contacts else np.zeros((0, 3)))

    def _poll(self) -> None:
        while not self._stop.wait(self.config.poll_seconds):
            try:
                if self.curves is not None:
                    self.curves.refresh()
                if self.picker is not None:
                    self.picker.refresh()
            except Exception as exc:  # a run directory being rewritten must not stop the polling
                print(f"[view] reading {self.run_dir} failed: {exc}")
