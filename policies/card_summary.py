"""The tables of shipped policies in README.md and docs/policies.md, written from the cards (`legged card --summary`):
one row per policy directory under assets/policies, its summary from its card's header and its headline from the first
JSON the card names (policies.cards). A policy whose card has no header yet is listed with its card and no figure."""

from __future__ import annotations

from pathlib import Path

from legged.files import write_atomic
from policies.card_tables import headline
from policies.cards import CardError, checked_reports

SUMMARY_BEGIN = "<!-- shipped policies: written by `legged card --summary` from the cards; edit those, not this -->"
SUMMARY_END = "<!-- end of shipped policies -->"
PAGES = {"README.md": False, "docs/policies.md": True}
"""The pages that hold the table (relative to the repository), and whether it lists every policy there (else those to
deploy)."""


def summary_rows(root: Path, every: bool = True) -> list[str]:
    """The table's lines: every policy, or (`every` False) those
    whose card header says `deploy: true` (not older versions kept for the runs trained through them)."""
    lines = ["| policy | what it does | headline figure (its first JSON) |", "|---|---|---|"]
    for card in sorted((root / "assets/policies").glob("*/CARD.md")):
        run = card.parent
        link = f"`{run.name}`"  # plain text: the site (docs/) cannot link outside its pages
        try:
            header, reports = checked_reports(run)
        except CardError as exc:
            if "no `<!-- card` header" not in str(exc):
                raise
            if every:
                lines.append(f"| {link} | see its card | not measured since evaluations record their provenance |")
            continue
        if not every and not header["deploy"]:
            continue
        name, report, _ = reports[0]
        lines.append(f"| {link} | {header['summary']} | {headline(report)} "
                     f"({run.relative_to(root).as_posix()}/{name}) |")
    return lines


def with_summary(text: str, table: str, page: Path) -> str:
    """`text` with the table between SUMMARY_BEGIN and SUMMARY_END replaced; CardError if the markers are not there."""
    if text.count(SUMMARY_BEGIN) != 1 or text.count(SUMMARY_END) != 1:
        raise CardError(f"{page}: needs one `{SUMMARY_BEGIN[:30]}...` line and one `{SUMMARY_END}` line")
    start, stop = text.index(SUMMARY_BEGIN), text.index(SUMMARY_END) + len(SUMMARY_END)
    return text[:start] + SUMMARY_BEGIN + "\n\n" + table + "\n\n" + SUMMARY_END + text[stop:]


def write_summaries(root: str | Path = ".", check: bool = False) -> dict:
    """Rewrite (with `check` only compare) the shipped-policy tables of PAGES; returns whether each was current."""
    root = Path(root)
    out = {}
    for relative, every in PAGES.items():
        page = root / relative
        text = page.read_text()
        wanted = with_summary(text, "\n".join(summary_rows(root, every)), page)
        out[relative] = text == wanted
        if not check and text != wanted:
            write_atomic(page, wanted)
    return out
