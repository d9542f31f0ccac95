"""Training curves as PNG files (pillow only), for run directories and reports: `legged plot RUN [RUN ...]`."""

from __future__ import annotations

import math
from pathlib import Path

from PIL import Image, ImageDraw

COLOURS = ((31, 119, 180), (214, 39, 40), (44, 160, 44), (148, 103, 189), (255, 127, 14), (140, 86, 75),
           (227, 119, 194), (23, 190, 207))
"""Line colours, in series order."""


def _ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """About `count` round tick values covering [lo, hi]."""
    span = max(hi - lo, 1e-12)
    step = 10 ** math.floor(math.log10(span / count))
    step *= min((m for m in (1, 2, 5, 10) if span / (step * m) <= count), default=10)
    first = math.ceil(lo / step) * step
    return [first + k * step for k in range(int((hi - first) / step + 1e-9) + 1)]


def line_plot(series: dict, path: str | Path, xlabel: str, ylabel: str, title: str = "",
              hline: float | None = None, size: tuple[int, int] = (820, 500)) -> Path:
    """Draw `series` ({label: (xs, ys)}) as lines on shared axes into a PNG; `hline` draws a dashed goal."""
    points = [(x, y) for xs, ys in series.values() for x, y in zip(xs, ys) if y is not None and math.isfinite(y)]
    if not points:
        raise ValueError(f"nothing to plot: no finite values of {ylabel}")
    xs, ys = zip(*points)
    ys = ys + ((hline,) if hline is not None else ())
    x0, x1 = min(xs), max(xs) if max(xs) > min(xs) else min(xs) + 1
    y0, y1 = min(ys), max(ys) if max(ys) > min(ys) else min(ys) + 1
    pad = 0.05 * (y1 - y0)
    y0, y1 = y0 - pad, y1 + pad
    w, h = size
    left, right, top, bottom = 80, 20, 40, 60
    img = Image.new("RGB", size, "white")
    draw = ImageDraw.Draw(img)
    px = lambda x: left + (x - x0) / (x1 - x0) * (w - left - right)
    py = lambda y: h - bottom - (y - y0) / (y1 - y0) * (h - top - bottom)
    draw.rectangle([left, top, w - right, h - bottom], outline="black")
    for t in _ticks(x0, x1):
        draw.line([px(t), h - bottom, px(t), h - bottom + 5], fill="black")
        draw.text((px(t) - 15, h - bottom + 8), f"{t:g}", fill="black")
    for t in _ticks(y0, y1):
        draw.line([left - 5, py(t), left, py(t)], fill="black")
        draw.line([left, py(t), w - right, py(t)], fill=(230, 230, 230))
        draw.text((5, py(t) - 6), f"{t:.3g}", fill="black")
    if hline is not None:
        for a in range(left, w - right, 12):
            draw.line([a, py(hline), min(a + 6, w - right), py(hline)], fill=(120, 120, 120))
    for k, (label, (sx, sy)) in enumerate(series.items()):
        colour = COLOURS[k % len(COLOURS)]
        line = [(px(x), py(y)) for x, y in zip(sx, sy) if y is not None and math.isfinite(y)]
        if len(line) > 1:
            draw.line(line, fill=colour, width=2)
        draw.text((left + 10, top + 8 + 14 * k), label, fill=colour)
    draw.text((w / 2 - 6 * len(title) / 2, 12), title, fill="black")
    draw.text((w / 2 - 3 * len(xlabel), h - 25), xlabel, fill="black")
    draw.text((5, top - 25), ylabel, fill="black")
    path = Path(path)
    img.save(path)
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
