"""Markdown tables of evaluation reports (`legged eval`, `drill`, `bench navigate` JSONs), for cards and the tables
of shipped policies: which figures a kind of report has, and how each is printed. Every number printed is a value of
the report, rounded as its column says (the figure linter, policies.figure_lint, reads them back that way)."""

from __future__ import annotations

from typing import Callable

Column = tuple[str, str, Callable]
"""(header, key of a report's figures, how the value is printed)."""


def number(digits: int) -> Callable:
    """A value printed with `digits` decimals (None: -)."""
    return lambda v: "-" if v is None else f"{v:.{digits}f}"


def percent(v) -> str:
    """A share printed as a percentage with one decimal (None: -)."""
    return "-" if v is None else f"{100 * v:.1f}%"


def count(v) -> str:
    """A whole number with thousands separators (None: -)."""
    return "-" if v is None else f"{int(round(v)):,}"


FALLS: list[Column] = [
    ("falls", "falls", count), ("falls per episode", "falls_per_episode", number(3)),
    ("episodes with a fall", "episodes_with_a_fall", percent),
    ("time down per episode, s", "seconds_down_per_episode", number(2)),
]
GETUPS: list[Column] = [
    ("get-ups started per episode", "getups_started_per_episode", number(3)),
    ("get-ups completed per episode", "getups_completed_per_episode", number(3)),
]
SOCCER: list[Column] = [
    ("games", "episodes", count), ("goals for per game", "goals_for_per_episode", number(3)),
    ("goals against per game", "goals_against_per_episode", number(3)), ("wins", "win_rate", percent),
]
TRACKING: list[Column] = [("episodes", "episodes", count), ("tracking error, m/s", "tracking_error_mps", number(3))]
WALK_DRILL: list[Column] = TRACKING + [
    ("smoothed tracking error, m/s", "smoothed_tracking_error_mps", number(3)),
    ("smoothed yaw-rate error, rad/s", "smoothed_yaw_rate_error_radps", number(3)),
    ("speed, m/s", "speed_mps", number(3)),
]
GETUP_DRILL: list[Column] = [("episodes", "episodes", count), ("stood", "success_rate", percent),
                             ("time to stand, s", "time_to_stand_s", number(2))]
GOAL_DRILL: list[Column] = [("episodes", "episodes", count), ("scored", "goal_rate", percent),
                            ("time to goal, s", "time_to_goal_s", number(2))]
CONFINED: list[Column] = [
    ("worlds", "episodes", count), ("success", "success_rate", percent),
    ("time to goal, s", "time_to_goal_s", number(2)), ("collisions per episode", "collisions_per_episode", number(2)),
]
NAVIGATION: list[Column] = [
    ("episodes", "episodes", count), ("successes", "successes", count), ("success", "success_rate", percent),
    ("median time to goal / path at the limit", "time_vs_path_at_speed", number(2)),
    ("p95 speed, m/s", "p95_speed_mps", number(2)), ("collisions per episode", "collisions", number(1)),
    ("falls per episode", "falls_per_episode", number(1)), ("replans per episode", "replans", number(1)),
]
ESTIMATE: list[Column] = [("ball estimate RMS error, m", "estimate_rms_m.ball", number(3))]


def value(figures: dict, key: str):
    """The value at a dotted `key` of `figures` (None where missing)."""
    for part in key.split("."):
        if not isinstance(figures, dict) or part not in figures:
            return None
        figures = figures[part]
    return figures


def columns_of(figures: dict) -> list[Column]:
    """The columns that describe one set of figures (one robot model's, one level's, one drill's)."""
    if "successes" in figures:
        return NAVIGATION
    if "drill" in figures or "speed_mps" in figures or "goal_rate" in figures or "time_to_stand_s" in figures:
        kind = WALK_DRILL if "speed_mps" in figures else GOAL_DRILL if "goal_rate" in figures else GETUP_DRILL
    elif "goals_for_per_episode" in figures:
        kind = SOCCER
    elif "success_rate" in figures:
        kind = CONFINED
    else:
        kind = TRACKING
    extra = GETUPS if "getups_started_per_episode" in figures else []
    estimate = ESTIMATE if value(figures, "estimate_rms_m.ball") is not None else []
    return kind + estimate + (FALLS if "falls" in figures else []) + extra


def labels(columns: list[Column]) -> list[str]:
    """The columns' headers; in soccer games an episode is a game, and is called so."""
    game = any(c[1] == "goals_for_per_episode" for c in columns)
    return [c[0].replace("per episode", "per game").replace("episodes with", "games with") if game else c[0]
            for c in columns]


def _table(first: str, rows: list[tuple[str, dict]]) -> str:
    columns = columns_of(rows[0][1])
    if not any(value(figures, "getups_started_per_episode") for _, figures in rows):  # no get-up skill, or none used
        columns = [c for c in columns if c not in GETUPS]
    named = labels(columns)
    lines = ["| " + " | ".join([first] + named) + " |",
             "|" + "---|" * (len(columns) + 1)]
    for label, figures in rows:
        lines.append("| " + " | ".join([label] + [c[2](value(figures, c[1])) for c in columns]) + " |")
    return "\n".join(lines)


def report_rows(report: dict) -> tuple[str, list[tuple[str, dict]]]:
    """(what the rows are, [(row label, figures)]) of a report: one row per robot model, per difficulty, per
    navigation scene total, or the report itself; a student's teacher or pilot in the same games as rows after it."""
    if "robots" in report:
        return "robot model", list(report["robots"].items())
    if "difficulties" in report:
        return "level", [(f"d{level}", figures) for level, figures in report["difficulties"].items()]
    if "scenes" in report and "total" in report:
        total = report["total"]
        return "scene", [(row["scene"], row) for row in report["scenes"]] + [(
            "**all**", dict(total, time_vs_path_at_speed=total["median_time_vs_path_at_speed"]))]
    rows = [(report.get("robot") or "project", report)]
    for role in ("teacher", "pilot"):
        if isinstance(report.get(role), dict):
            rows.append((f"its {role} ({report[role]['run']}), same games", report[role]))
    return "model", rows


def what_was_measured(report: dict) -> str:
    """One line: the policy's checkpoint steps, the kind of evaluation, the engine, the seed."""
    parts = []
    if "drill" in report:
        parts.append(f"the {report['drill']} drill" + (", randomised" if report.get("randomized") else ""))
    elif "opponent" in report or any("opponent" in f for f in report.get("robots", {}).values()):
        first = report if "opponent" in report else next(iter(report["robots"].values()))
        parts.append(f"games against {first['opponent']}" +
                     (f", teammate {first['teammate']}" if first.get("teammate") else ""))
    elif "scenes" in report:
        parts.append(f"navigation of the scenes in {report['scenes_dir']}")
    elif "difficulties" in report:
        parts.append(f"held-out level worlds (world seed {report['world_seed']})")
    else:
        parts.append("held-out episodes")
    if report.get("nominal"):
        parts.append("nominal models")
    parts.append(f"{report.get('physics', 'native')} physics")
    if "seed" in report:
        parts.append(f"seed {report['seed']}")
    elif "seeds" in report:
        parts.append(f"episode seeds {report['seeds'][0]}-{report['seeds'][-1]}")
    return ", ".join(parts)


def wrapped_command(command: str, width: int = 110) -> str:
    """A command line as an indented code block, continued with backslashes past `width` characters (an option
    stays with its value)."""
    groups: list[str] = []
    for word in command.split(" "):
        if groups and not word.startswith("--") and groups[-1].startswith("--") and " " not in groups[-1]:
            groups[-1] += " " + word
        else:
            groups.append(word)
    lines, line = [], "    "
    for word in groups:
        if len(line) + len(word) + 1 > width and line.strip():
            lines.append(line + " \\")
            line = "      "
        line += ("" if line.endswith(" ") else " ") + word
    return "\n".join(lines + [line])


def json_tables(name: str, report: dict, record: dict) -> str:
    """A card's table of one JSON: its name, what it measured, the command, the table."""
    first, rows = report_rows(report)
    commit = (record.get("commit") or "")[:10]
    state = "" if record.get("clean") in (None, True) else ", uncommitted changes"
    head = (f"**{name}**: {what_was_measured(report)};\nmeasured {record.get('date', '')[:10]} at commit "
            f"{commit or 'unknown'}{state} by\n\n{wrapped_command(record.get('command', ''))}")
    return head + "\n\n" + _table(first, rows)


def headline(report: dict) -> str:
    """A one-line headline of a report: its main figure per row, the rows named."""
    first, rows = report_rows(report)
    columns = columns_of(rows[0][1])
    main = [c for c in columns if c[1] not in ("episodes",)][:1] + [c for c in columns if c[1] == "falls_per_episode"]
    named = dict(zip([c[1] for c in columns], labels(columns)))
    pieces = [f"{named[c[1]]} " + " / ".join(c[2](value(f, c[1])) for _, f in rows) for c in main]
    episodes = rows[0][1].get("episodes")
    unit = "games" if "goals_for_per_episode" in named else "episodes"
    return (f"{'; '.join(pieces)} ({' / '.join(label for label, _ in rows)}; {episodes} {unit} each, "
            f"{report.get('physics', 'native')})")
