"""The figure linter: every figure a page prints must be a value of the evidence it cites.

Figures: decimal numbers, percentages, and integers that count goals, falls or wins. A figure is checked against the
evidence its section cites (from its heading to the next) and the evidence cited before the page's first heading (a
card's header names its JSONs; a card's own config.yaml counts too). A section cites evidence by naming it: a JSON
file (`eval_native.json`, `assets/runs/RUN/eval.json`), or a run, policy or benchmark directory (`assets/runs/RUN`:
its JSONs, its training metrics and its config.yaml; a run record also by its name or the end of it, `raw-cpu2`).
Names are looked up beside the page, from the repository's root, and in the directories the section names.

A printed number matches a value when it is that value rounded to the printed decimals; a percentage is read against
the shares (keys such as `success_rate`, `episodes_with_a_fall`), times 100; `13.27M` and `2.5k` are read as
13,270,000 and 2,500, and minutes or hours also as the seconds the evidence holds. Besides the values themselves the
evidence gives counts (a share or a per-episode figure times the report's episodes: `falls_per_episode` 0.25 of 64
games is 16 falls) and, of training metrics, each field's first, last, lowest, highest, mean and median value.
Numbers in code (indented blocks, fences, `inline`), in HTML comments and in link targets are commands and paths, not
figures; so are dates and version numbers. What is left and matches nothing is either a constant (a value of the
physics or of a design, not a measurement: CONSTANTS for every page, or the page's own, declared in a comment
`<!-- constants: 0.4 (step duration, s); 0.08 (double support, s) -->`) or a finding: a figure typed by hand that
no file holds. A sum or a ratio computed by hand is a finding too: print the values it comes from instead.
"""

from __future__ import annotations

import bisect
import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import yaml

CONSTANTS: dict[float, str] = {
    0.02: "the Go1 tasks' control period, s",
    0.025: "OP3 control period, s; planning grid resolution, m",
    0.002: "a physics step, s",
    0.005: "the longest physics step of another robot model, s",
    1.92: "Menagerie's OP3 physics step, ms",
    1.084: "Menagerie's OP3 joint damping, N m s/rad",
    4.1: "OP3 servo torque limit, N m",
    0.21: "the get-up drill's standing height, m",
    0.245: "OP3 torso height at its default pose, m",
    0.27: "Go1 trunk height at its default pose, m",
    0.96: "the placo gait's stride (two steps), s",
    0.5: "a half (ratios, seconds, metres in prose)",
    1.5: "one and a half (seconds, metres in prose)",
    2.5: "two and a half (prose)",
}
"""Numbers that are no measurement (physics and design values a page explains), each with what it is."""

PERCENT_CONSTANTS: dict[float, str] = {95.0: "the confidence level of the intervals"}
"""Percentages that are no measurement."""

PAGES = ("README.md", "docs/*.md", "assets/policies/*/CARD.md")
"""The pages checked, as globs from the repository's root."""
SKIPPED = ("docs/cli-reference.md",)
"""Pages generated from the parser: their numbers are the options' defaults."""

_PAGE_CONSTANTS = re.compile(r"<!--\s*constants:(.*?)-->", re.S)
_JSON = re.compile(r"(?<![\w/.-])((?:[\w.-]+/)*[\w.-]+\.json)\b")
_RUN_NAME = re.compile(r"(?<![\w/.-])([a-z0-9][a-z0-9-]*-cpu2?)\b")
"""A run named by its record's directory name, or the end of it (`raw-cpu2` for soccer-1v1-vision-raw-cpu2)."""
_DIR = re.compile(r"\b((?:assets/(?:runs|policies|benchmarks)|tests/fixtures/runs)/[\w.-]+)")
_NUMBER = re.compile(r"(?<![\w.\-/:])(-?\d{1,3}(?:,\d{3})+|-?\d+)(\.\d+)?(%|M\b|k\b|x\b)?(?![\w.]*\d)")
_RANGE = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)(?=-\d+(?:\.\d+)?(%|M\b|k\b))")
_LISTED = re.compile(r"(?<![\w.%])(\d+(?:\.\d+)?)(?=(?:\s*/\s*\d+(?:\.\d+)?)*\s*/\s*\d+(?:\.\d+)?%)")
_SCIENTIFIC = re.compile(r"\b\d+(?:\.\d+)?e[-+]?\d+\b")
_DATE = re.compile(r"\b\d{4}-\d{2}-\d{2}\b")
_VERSION = re.compile(r"\b\d+\.\d+\.\d+\b|\bv\d+(?:\.\d+)*\b|(?:[<>=]=|[≥≤]) ?\d+(?:\.\d+)*|"
                      r"\b(?:Python|python|torch|"
                      r"MuJoCo|mujoco(?:-mjx)?|jax(?:lib)?|JAX|brax|Brax|MJX|placo|OMPL|ompl|viser|rsl-rl(?:-lib)?|"
                      r"Chromium|chromium|numpy|scipy|version|versions)[ =]+[\d.]+")


@dataclasses.dataclass(frozen=True)
class Finding:
    """A printed figure no cited file holds."""

    page: str
    """The page, relative to the repository."""
    line: int
    """Its line number."""
    text: str
    """The figure as printed."""
    context: str
    """The line around it."""

    def __str__(self) -> str:
        return f"{self.page}:{self.line}: {self.text} ({self.context.strip()[:100]})"


def prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, text) of a page's prose: without code blocks (fenced or indented by 4), inline code, HTML
    comments, link targets, dates, version numbers and numbers in scientific notation (tolerances and settings); the
    first end of a range takes the unit of the second (`91.91-101.91M`), and the numbers of a list the percent sign
    of its last (`92.7 / 95.3 / 80.0%`)."""
    text = re.sub(r"<!--.*?-->", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    out, fenced, in_code = [], False, False
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    ") and not line.lstrip().startswith(("-", "|", "*")):
            in_code = False
            continue
        if not line.strip():  # inline code ends with its paragraph at the latest
            in_code = False
        line = ("`" if in_code else "") + line
        in_code = line.count("`") % 2 == 1  # inline code that goes on on the next line
        line = re.sub(r"`[^`]*(`|$)", " ", line)
        line = re.sub(r"\+-\s?\d[\d.]*", " ", line)  # +-0.04: a range of a setting, as before the + counted
        line = re.sub(r"\]\([^)]*\)", "]", line)
        line = _SCIENTIFIC.sub(" ", _VERSION.sub(" ", _DATE.sub(" ", line)))
        line = _RANGE.sub(lambda m: m.group(1) + m.group(2), line)  # 91.91-101.91M: both ends in millions
        line = _LISTED.sub(lambda m: m.group(1) + "%", line)  # 92.7 / 95.3 / 80.0%: every one a percentage
        line = re.sub(r"(?<=[\d%Mk])-(?=\d)", " to ", line)  # a range's second end is a figure too
        out.append((number, line))
    return out


_COUNTED = re.compile(r"\s*(goals?|falls?|wins?)\b")
"""A count the evidence holds, after an integer: integers are figures only before these words."""
_DURATION = re.compile(r"\s*(minutes?|min|hours?|h)\b")
"""A duration's unit after a number: the evidence holds seconds."""


def printed_numbers(line: str) -> list[tuple[str, list[tuple[float, float, bool]]]]:
    """(as printed, its readings) of each decimal number and percentage on a line, and of each integer that counts
    goals, falls or wins (other integers are not figures here). A reading is (value, tolerance: half the last printed
    digit, percentage); M and k scale the value, and a number of minutes or hours may also be read as seconds, which
    the evidence holds."""
    found = []
    for m in _NUMBER.finditer(line):
        whole, fraction, suffix = m.group(1), m.group(2) or "", m.group(3) or ""
        if not fraction and suffix != "%" and not _COUNTED.match(line, m.end()):
            continue
        value = float(whole.replace(",", "") + fraction)
        scale = {"M": 1e6, "k": 1e3}.get(suffix, 1.0)
        tolerance = 0.5 * 10.0 ** -max(len(fraction) - 1, 0) * scale + 1e-9
        readings = [(value * scale, tolerance, suffix == "%")]
        unit = _DURATION.match(line, m.end())
        if unit and not suffix:
            seconds = 60.0 if unit.group(1).startswith("m") else 3600.0
            readings.append((value * seconds, tolerance * seconds, False))
        found.append((m.group(0), readings))
    return found


def cited_files(page: Path, text: str, root: Path) -> list[Path]:
    """The evidence files a page names: JSONs, and the JSONs, JSON lines (training metrics) and config.yaml of the
    directories it names (and of their sub-directories)."""
    bases = [page.parent, root]
    dirs = {root / d.rstrip(".") for d in _DIR.findall(text)}  # a path ending a sentence keeps no full stop
    records = sorted(p.name for p in (root / "assets/runs").glob("*") if p.is_dir())
    for name in set(_RUN_NAME.findall(text)):
        dirs.update(root / "assets/runs" / r for r in records if r == name or r.endswith("-" + name))
    bases += sorted(d for d in dirs if d.is_dir())
    files = set()
    for name in _JSON.findall(text):
        for base in bases:
            if (base / name).is_file():
                files.add((base / name).resolve())
    if page.name == "CARD.md" and (page.parent / "config.yaml").is_file():  # a card's own run: its settings
        files.add((page.parent / "config.yaml").resolve())
    for d in dirs:
        if d.is_dir():
            files.update(p.resolve() for p in d.glob("**/*.json"))
            files.update(p.resolve() for p in d.glob("**/*.jsonl"))  # runs kept in a record's sub-directories too
            files.update(p.resolve() for p in d.glob("**/config.yaml"))
    return sorted(files)


SHARE_WORDS = frozenset({"rate", "share", "fraction", "success", "win", "wins", "ci95", "interval", "ratio", "stood",
                         "scored"})
"""Words of a key (split at `_`) that make its values shares: the only values a percentage is read against (times
100): `success_rate`, `episodes_with_a_fall`, `ratio_vs_mjx`; not `iteration` or `learning_rate`."""
NOT_SHARES = frozenset({"learning_rate"})
"""Keys that hold a word of SHARE_WORDS and no share."""


def is_share(key: str) -> bool:
    """Whether a JSON key names a share (SHARE_WORDS)."""
    return key not in NOT_SHARES and ("with_a_fall" in key or not SHARE_WORDS.isdisjoint(key.lower().split("_")))


def _walk(node, out: dict, where: str, key: str = "") -> None:
    """Collect the numbers under `node` into out["all"], the shares (is_share) also into out["shares"], each as
    (value, where it is: `FILE:KEY`)."""
    if isinstance(node, bool):
        return
    if isinstance(node, (int, float)):
        if np.isfinite(node):
            out["all"].append((float(node), f"{where}:{key}"))
            if is_share(key):
                out["shares"].append((float(node), f"{where}:{key}"))
        return
    if isinstance(node, dict):
        episodes = node.get("episodes") or node.get("games")
        for name, value in node.items():
            _walk(value, out, where, str(name))
            if isinstance(episodes, (int, float)) and isinstance(value, (int, float)) and not isinstance(value, bool) \
                    and (str(name).endswith(("_per_episode", "_rate")) or name == "episodes_with_a_fall"):
                out["all"].append((float(value) * episodes, f"{where}:{name} x episodes"))  # the count behind it
    elif isinstance(node, list):
        for value in node:
            _walk(value, out, where, key)


def curve_ends(records: list[dict]) -> dict:
    """What a page may quote of a training run's metrics (one record per line): each field's first, last, lowest,
    highest, mean and median value (not every point of the curve, which would match almost any number)."""
    series: dict[str, list[float]] = {}
    for record in records:
        for key, value in record.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value):
                series.setdefault(key, []).append(float(value))
    return {key: [v[0], v[-1], min(v), max(v), float(np.mean(v)), float(np.median(v))] for key, v in series.items()}


@dataclasses.dataclass(frozen=True)
class Evidence:
    """The values a section may print, sorted, each with where it comes from."""

    values: np.ndarray
    """Every number of the cited files (and the counts behind their shares), sorted."""
    sources: list[str]
    """Where each value is (`FILE:KEY`, `constant: what`)."""
    shares: np.ndarray
    """The shares among them, sorted."""
    share_sources: list[str]
    """Where each share is."""

    @staticmethod
    def of(pairs: list[tuple[float, str]], share_pairs: list[tuple[float, str]]) -> "Evidence":
        pairs, share_pairs = sorted(pairs), sorted(share_pairs)
        return Evidence(np.asarray([v for v, _ in pairs], float), [s for _, s in pairs],
                        np.asarray([v for v, _ in share_pairs], float), [s for _, s in share_pairs])

    def source(self, value: float, tolerance: float, percentage: bool) -> str | None:
        """Where a printed reading is a value of the evidence within `tolerance`, or its magnitude is (a penalty
        printed either way), None if nowhere; a percentage is read against the shares, times 100."""
        if percentage:
            return _near(self.shares, self.share_sources, abs(value) / 100.0, tolerance / 100.0)
        return _near(self.values, self.sources, value, tolerance) or \
            _near(self.values, self.sources, -value, tolerance)


def evidence_values(files: list[Path], root: Path, own: list[float] = ()) -> Evidence:
    """Every number the files hold (JSON, JSON lines of training metrics or YAML), with the counts behind their
    shares, the global constants and the page's own (`own`)."""
    out: dict[str, list] = {"all": [], "shares": []}
    for path in files:
        try:
            text = path.read_text()
            data = json.loads(text) if path.suffix == ".json" else \
                curve_ends([json.loads(line) for line in text.splitlines() if line.strip()]) \
                if path.suffix == ".jsonl" else yaml.safe_load(text)
        except (ValueError, yaml.YAMLError, OSError):
            continue
        _walk(data, out, path.relative_to(root).as_posix() if path.is_relative_to(root) else str(path))
    out["all"] += [(v, f"constant: {what}") for v, what in CONSTANTS.items()] + [(v, "page constant") for v in own]
    out["shares"] += [(p / 100, f"constant: {what}") for p, what in PERCENT_CONSTANTS.items()] + \
        [(v, "page constant") for v in own]
    return Evidence.of(out["all"], out["shares"])


def _near(values: np.ndarray, sources: list[str], target: float, tolerance: float) -> str | None:
    i = bisect.bisect_left(values, target - tolerance)
    return sources[i] if i < len(values) and values[i] <= target + tolerance else None


def page_constants(text: str) -> list[float]:
    """The values a page declares as constants (`<!-- constants: VALUE (what); ... -->`), percentages as shares."""
    out = []
    for block in _PAGE_CONSTANTS.findall(text):
        for item in block.split(";"):
            m = re.match(r"\s*(-?\d+(?:\.\d+)?)(%|M|k)?\s*\(", item)
            if m:
                out.append(float(m.group(1)) * {"%": 0.01, "M": 1e6, "k": 1e3}.get(m.group(2) or "", 1.0))
    return out


def sections(text: str) -> list[tuple[int, str]]:
    """(first line number, text) of a page's sections: the part before its first heading (a card's header, the
    page's introduction), then each part from one heading to the next."""
    starts = [0] + [i for i, line in enumerate(text.splitlines()) if line.startswith("#") and i > 0]
    lines = text.splitlines()
    return [(start, "\n".join(lines[start:end])) for start, end in zip(starts, starts[1:] + [len(lines)])]


def page_figures(page: Path, root: Path) -> list[tuple[Finding, str | None]]:
    """Every figure on `page`, with where the evidence cited in its section (or before the page's first heading)
    holds it (`FILE:KEY`), None where nothing does."""
    text = page.read_text()
    parts = sections(text)
    head = parts[0][1]
    own = page_constants(text)
    out = []
    for start, section in parts:
        evidence = evidence_values(cited_files(page, head + "\n" + section, root), root, own)
        for number, line in prose_lines(section):
            for printed, readings in printed_numbers(line):
                source = next(filter(None, (evidence.source(*reading) for reading in readings)), None)
                out.append((Finding(page.relative_to(root).as_posix(), start + number, printed, line), source))
    return out


def pages(root: Path) -> list[Path]:
    """Every page the linter reads."""
    found = sorted({p for pattern in PAGES for p in root.glob(pattern)})
    return [p for p in found if p.relative_to(root).as_posix() not in SKIPPED]


def explain(root: str | Path = ".", only: list[str] | None = None) -> list[tuple[Finding, str | None]]:
    """Every figure of every page (or of the pages in `only`, relative to `root`) with the evidence it matched
    (None: nothing), for a reader to judge whether the match is the figure's source or a coincidence."""
    root = Path(root).resolve()
    chosen = pages(root) if only is None else [root / p for p in only]
    return [pair for page in chosen for pair in page_figures(page, root)]


def lint(root: str | Path = ".", only: list[str] | None = None) -> list[Finding]:
    """The findings of every page (or of the pages in `only`): the figures no file cited in their section (or
    before the page's first heading) holds."""
    return [figure for figure, source in explain(root, only) if source is None]
