"""Dashboard panels: per-term reward and task-metric plots of the current rollout, training curves of a
run directory (re-read while it trains), a checkpoint picker and an image panel."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Callable

import numpy as np
import viser

from policies.run_dir import RunDir
from web.trajectory import Trajectory

PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
           "#17becf", "#393b79", "#637939")
"""Line colours of plotted series."""

RETURN = "episode return (cumulative)"
"""Metric choice that plots the running sum of the reward."""


class LinePlot:
    """A uPlot line chart inside a GUI container, redrawn in place (re-created when the series change)."""

    def __init__(self, gui: viser.GuiApi, container, aspect: float = 1.3):
        self.gui, self.container, self.aspect = gui, container, aspect
        self.handle = None
        self._lock = threading.Lock()

    def set(self, title: str, x_label: str, x: np.ndarray, series: dict[str, np.ndarray]) -> None:
        """Show `series` (name -> values) over `x` (numbers, not dates)."""
        specs = tuple([{"label": x_label}] + [{"label": name, "stroke": PALETTE[i % len(PALETTE)], "width": 1.5}
                                              for i, name in enumerate(series)])
        data = (np.asarray(x, np.float64),) + tuple(np.asarray(v, np.float64) for v in series.values())
        with self._lock:
            if self.handle is not None and len(self.handle.series) == len(specs):
                self.handle.title, self.handle.series, self.handle.data = title, specs, data
                return
            if self.handle is not None:
                self.handle.remove()
            with self.container:
                self.handle = self.gui.add_uplot(
                    data, specs, title=title, scales={"x": {"time": False}}, legend={"show": True},
                    aspect=self.aspect)

    def clear(self) -> None:
        """Remove the chart."""
        with self._lock:
            if self.handle is not None:
                self.handle.remove()
                self.handle = None


class RolloutPlots:
    """Per-step reward terms and one chosen task metric of the current rollout, for one environment."""

    def __init__(self, gui: viser.GuiApi):
        self._terms = LinePlot(gui, gui.add_folder("Reward terms"))
        folder = gui.add_folder("Task metric")
        with folder:
            self.metric = gui.add_dropdown("Metric", (RETURN,), initial_value=RETURN)
        self._metric_plot = LinePlot(gui, folder)
        self.metric.on_update(lambda _: self._draw_metric())
        self._traj: Trajectory | None = None
        self._env = 0

    def show(self, traj: Trajectory, env: int) -> None:
        """Plot `traj`'s environment `env` (replaces what was shown)."""
        self._traj, self._env = traj, env
        names = [RETURN] + sorted(k for k in traj.metrics if not k.startswith("reward/"))
        self.metric.options = names
        if self.metric.value not in names:
            self.metric.value = RETURN
        terms = {k[7:]: traj.metrics[k][:, env] for k in sorted(traj.metrics) if k.startswith("reward/")}
        terms = terms or {"reward": traj.reward[:, env]}
        self._terms.set("reward terms per step", "time s", self._time(), terms)
        self._draw_metric()

    def _time(self) -> np.ndarray:
        return np.arange(self._traj.num_frames) * self._traj.dt

    def _draw_metric(self) -> None:
        if self._traj is None:
            return
        name, env = self.metric.value, self._env
        values = self._traj.episode_return()[:, env] if name == RETURN else self._traj.metrics[name][:, env]
        self._metric_plot.set(name, "time s", self._time(), {name: values})


def numeric_keys(records: list[dict]) -> list[str]:
    """Keys other than `step` that hold a number in some record."""
    keys = {k for r in records for k, v in r.items()
            if k != "step" and isinstance(v, (int, float)) and not isinstance(v, bool)}
    return sorted(keys)


LATENT_DIAGNOSTICS = (("KL(q(z|h) || N(0, I)), HIB's I(H; Z) bound", "hib_kl"),
                      ("log K - InfoNCE, HIB's I(Z; S^p) bound", "hib_mi_lower_bound"),
                      ("linear probe R^2: latent -> randomised dynamics", "probe_r2"))
"""The latent's diagnostics (title, metrics.jsonl key), each plotted once the run logs it."""


class LatentDiagnostics:
    """Plots of a student's or teacher's latent diagnostics against environment steps (policies.hib and the
    linear probe of policies.probe), in their own folder; drawn from the records TrainingCurves reads."""

    def __init__(self, gui: viser.GuiApi):
        self.gui, self.folder, self.plots = gui, None, {}

    def draw(self, records: list[dict]) -> list[str]:
        """Plot every diagnostic the records hold; returns the keys shown."""
        shown = []
        for title, key in LATENT_DIAGNOSTICS:
            points = [(r["step"], r[key]) for r in records if isinstance(r.get(key), (int, float))
                      and np.isfinite(r[key])]
            if not points:
                continue
            if self.folder is None:
                self.folder = self.gui.add_folder("Latent diagnostics")
            plot = self.plots.setdefault(key, LinePlot(self.gui, self.folder, aspect=2.0))
            steps, values = np.array(points, np.float64).T
            plot.set(title, "env steps", steps, {key: values})
            shown.append(key)
        return shown


class TrainingCurves:
    """One curve of a run's metrics.jsonl against environment steps; `refresh()` re-reads a changed file. The
    latent's diagnostics, where the run logs them, are plotted below it (LatentDiagnostics)."""

    def __init__(self, gui: viser.GuiApi, run: RunDir, initial: str = "episode_return"):
        self.run, self.path = run, run.metrics_path
        folder = gui.add_folder("Training curves")
        with folder:
            self.key = gui.add_dropdown("Curve", (initial,), initial_value=initial)
            self.status = gui.add_markdown("")
        self._plot = LinePlot(gui, folder)
        self.diagnostics = LatentDiagnostics(gui)
        self.key.on_update(lambda _: self._draw())
        self._records: list[dict] = []
        self._stamp = None
        self.refresh()

    def refresh(self) -> bool:
        """Re-read the metrics file if it changed; True when the plot was redrawn."""
        try:
            stat = self.path.stat()
            stamp = (stat.st_size, stat.st_mtime_ns)
        except FileNotFoundError:
            stamp = None
        if stamp == self._stamp:
            return False
        self._stamp = stamp
        self._records = self.run.metrics()
        keys = numeric_keys(self._records)
        if keys:
            self.key.options = keys if self.key.value in keys else [self.key.value] + keys
        self._draw()
        self.diagnostics.draw(self._records)
        return True

    def _draw(self) -> None:
        name = self.key.value
        points = [(r["step"], r[name]) for r in self._records
                  if isinstance(r.get(name), (int, float)) and np.isfinite(r[name])]
        last = self._records[-1]["step"] if self._records else None
        self.status.content = (f"`{self.path}`: {len(self._records)} records, last at step {last}" if self._records
                               else f"`{self.path}`: no records yet (re-read every few seconds)")
        if points:
            steps, values = np.array(points, np.float64).T
            self._plot.set(f"{name} (training)", "env steps", steps, {name: values})
        else:
            self._plot.clear()


class CheckpointPicker:
    """A dropdown of a run's checkpoints and a button that swaps the policy to the chosen one."""

    def __init__(self, gui: viser.GuiApi, list_checkpoints: Callable[[], list[Path]],
                 on_load: Callable[[Path], None], current: Path | None = None):
        self._list, self._on_load = list_checkpoints, on_load
        self._paths: dict[str, Path] = {}
        self.dropdown = gui.add_dropdown("Checkpoint", ("(none yet)",), hint="newest first")
        self.button = gui.add_button("Load checkpoint", icon=viser.Icon.REFRESH,
                                     hint="roll out the chosen checkpoint's policy (same seed)")
        self.button.on_click(lambda _: self._load())
        self.refresh()
        if current is not None and current.name in self._paths:
            self.dropdown.value = current.name

    def refresh(self) -> bool:
        """Re-list the checkpoints; True when the list changed."""
        paths = {p.name: p for p in reversed(self._list())}
        if list(paths) == list(self._paths):
            return False
        was_newest = not self._paths or self.dropdown.value == next(iter(self._paths))
        self._paths = paths
        self.dropdown.options = list(paths) or ["(none yet)"]
        if paths and was_newest:
            self.dropdown.value = next(iter(paths))  # follow a training run's newest checkpoint
        self.button.disabled = not paths
        return True

    def _load(self) -> None:
        path = self._paths.get(self.dropdown.value)
        if path is not None:
            self._on_load(path)


class ImagePanel:
    """Shows one image (H, W, 3) uint8: a camera observation or the depth view."""

    def __init__(self, gui: viser.GuiApi, label: str, shape: tuple[int, int] = (48, 64), scale: int = 4):
        self.scale = scale
        """Each pixel is shown as scale x scale pixels (small sensor images stay legible)."""
        self.handle = gui.add_image(np.zeros((shape[0] * scale, shape[1] * scale, 3), np.uint8), label=label,
                                    format="png")

    def show(self, image: np.ndarray) -> None:
        """Replace the image."""
        image = np.asarray(image, np.uint8)
        if self.scale > 1:
            image = np.repeat(np.repeat(image, self.scale, axis=0), self.scale, axis=1)
        self.handle.image = np.ascontiguousarray(image)
