"""Training curves as PNG files (matplotlib, drawn off-screen), for run directories and reports:
`legged plot RUN [RUN ...]`."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

COLOURS = ((31, 119, 180), (214, 39, 40), (44, 160, 44), (148, 103, 189), (255, 127, 14), (140, 86, 75),
           (227, 119, 194), (23, 190, 207))
"""Line colours (RGB, 0-255), in series order."""

DPI = 100
"""Pixels per inch of the written PNG: a figure of `size` pixels is `size / DPI` inches."""


def _rgb(colour: tuple[int, int, int]) -> tuple[float, float, float]:
    """A 0-255 RGB colour as matplotlib's 0-1 floats."""
    return tuple(c / 255.0 for c in colour)


def line_plot(series: dict, path: str | Path, xlabel: str, ylabel: str, title: str = "",
              hline: float | None = None, size: tuple[int, int] = (820, 500)) -> Path:
    """Draw `series` ({label: (xs, ys)}) as lines on shared axes into a PNG of `size` pixels; `hline` draws a
    dashed goal. Points whose y is None or not finite are left out (the line joins its neighbours)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from PIL import Image

    lines = {label: [(x, y) for x, y in zip(xs, ys) if y is not None and math.isfinite(y)]
             for label, (xs, ys) in series.items()}
    if not any(lines.values()):
        raise ValueError(f"nothing to plot: no finite values of {ylabel}")
    fig = Figure(figsize=(size[0] / DPI, size[1] / DPI), dpi=DPI, layout="constrained", facecolor="white")
    canvas = FigureCanvasAgg(fig)                            # Agg: drawn in memory, no display needed
    ax = fig.add_subplot()
    for k, (label, points) in enumerate(lines.items()):
        xs, ys = zip(*points) if points else ((), ())
        ax.plot(xs, ys, color=_rgb(COLOURS[k % len(COLOURS)]), linewidth=1.5, label=label,
                marker="o" if len(points) == 1 else None)   # a lone point still shows
    if hline is not None:
        ax.axhline(hline, color=_rgb((120, 120, 120)), linestyle="--", linewidth=1)
    ax.grid(True, axis="y", color=_rgb((230, 230, 230)))
    ax.set_axisbelow(True)
    ax.ticklabel_format(axis="both", style="sci", scilimits=(-3, 6), useOffset=False)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.legend(loc="best", frameon=False)
    canvas.draw()
    path = Path(path)
    Image.fromarray(np.asarray(canvas.buffer_rgba())).convert("RGB").save(path, format="PNG")  # opaque: RGB
    return path


def plot_runs(run_dirs: list, y: str, x: str = "step", out: str | Path | None = None,
              hline: float | None = None) -> Path:
    """Plot metric `y` of several runs (one line each, labelled by the run's folder name) against `x` into one
    PNG (default: the first run's folder, <metric>.png)."""
    series = dict(_run_series(run_dir, y, x) for run_dir in run_dirs)
    if len(series) < len(run_dirs):
        raise ValueError(f"two of the runs share a folder name: {', '.join(str(r) for r in run_dirs)}")
    xlabel = "wall-clock minutes of training" if x == "wall_s" else x
    title = f"{Path(run_dirs[0]).name}: {y}" if len(run_dirs) == 1 else y
    return line_plot(series, out or Path(run_dirs[0]) / f"{y}.png", xlabel, y, title=title, hline=hline)


def _run_series(run_dir: str | Path, y: str, x: str) -> tuple[str, tuple[list, list]]:
    """(the run's folder name, (xs, ys)) of metric `y` against `x`."""
    from policies.run_dir import RunDir

    run = RunDir(run_dir)
    records = [r for r in run.metrics() if isinstance(r.get("step" if x == "wall_s" else x), (int, float))]
    if not records:
        raise ValueError(f"{run.metrics_path}: no records with {x!r}")
    if not any(y in r for r in records):
        names = sorted({k for r in records for k, v in r.items() if isinstance(v, (int, float))})
        raise ValueError(f"{run.metrics_path} has no metric {y!r}; numeric metrics: {', '.join(names)}")
    if x == "wall_s":
        xs = [t / 60.0 for t in _wall_seconds(run.metrics())]
        records = [r for r in run.metrics() if isinstance(r.get("step"), (int, float))]
    else:
        xs = [r[x] for r in records]
    number = lambda v: float(v) if isinstance(v, (int, float)) or v in ("nan", "inf", "-inf") else None
    return Path(run_dir).name, (xs, [number(r.get(y)) for r in records])


def _wall_seconds(records: list[dict]) -> list[float]:
    """Training seconds at each record: its `wall_s`, or for runs logged without it the training-loop time
    summed from each report's steps and steps_per_s (start-up compilation not included)."""
    out, total, step = [], 0.0, 0
    for r in records:
        if isinstance(r.get("wall_s"), (int, float)):
            total = float(r["wall_s"])
        elif isinstance(r.get("steps_per_s"), (int, float)) and r["steps_per_s"] > 0:
            total += (r["step"] - step) / r["steps_per_s"]
        step = r["step"]
        out.append(total)
    return out
