"""Markdown tables of evaluations side by side: `legged table RUN [RUN ...]` (one row per run, one column per
metric and evaluation file), as the docs' comparison tables are written."""

from __future__ import annotations

import json
from pathlib import Path


def _cell(value) -> str:
    if isinstance(value, bool) or value is None:
        return "-" if value is None else str(value)
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        return f"{value:.3g}" if abs(value) < 1000 else f"{value:,.0f}"
    return str(value)


def eval_table(run_dirs: list, files: list[str], metrics: list[str]) -> str:
    """A markdown table: a row per run (its folder name and trained steps), a column per (file, metric) read
    from each run's evaluation JSON files (`legged eval --json` output saved in the run)."""
    header, rows = ["run", "steps"] + [f"{m} ({Path(f).stem})" for f in files for m in metrics], []
    for run_dir in run_dirs:
        reports = []
        for name in files:
            path = Path(run_dir) / name
            if not path.is_file():
                raise ValueError(f"{path} not found: save `legged eval {run_dir} --json` output there first")
            try:
                reports.append(json.loads(path.read_text()))
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path} is not JSON ({exc.msg} at line {exc.lineno})") from None
        missing = [f"{m} in {f}" for f, r in zip(files, reports) for m in metrics if m not in r]
        if missing:
            raise ValueError(f"{run_dir}: no {', '.join(missing)}")
        steps = reports[0].get("trained_steps")
        rows.append([Path(run_dir).name, _cell(steps)] + [_cell(r[m]) for r in reports for m in metrics])
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])
