"""The documentation stays true: docs/cli-reference.md is what the parser says today, and the MkDocs site
(mkdocs.yml, docs/) builds with --strict, without a broken link, a missing anchor or a page left out of the nav.

Fast: it builds the `legged` parser (no environment, no torch) and the site, a few seconds together."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from legged.cli.main import build_parser
from legged.cli.reference import PAGE, reference_markdown

ROOT = Path(__file__).resolve().parents[1]


def test_the_committed_cli_reference_matches_the_parser():
    committed = PAGE.read_text(encoding="utf-8")
    assert reference_markdown() == committed, (
        "docs/cli-reference.md differs from the parser: regenerate it with `.venv/bin/python -m legged.cli.reference`")


def test_the_cli_reference_has_a_section_per_command_and_short_lines():
    text = reference_markdown(build_parser())
    for command in ("world", "navigate", "bench", "train", "distill", "eval", "view"):
        assert f"\n## legged {command}\n" in text
    for sub in ("plan", "navigate", "env", "soak"):
        assert f"\n### legged bench {sub}\n" in text
    assert "`--num-envs NUM_ENVS`" in text and "```text\nusage: legged train" in text
    long = [line for line in text.splitlines() if len(line) > 120]
    assert not long, "lines over 120 characters:\n" + "\n".join(long)


def test_the_site_builds_without_warnings(tmp_path):
    if importlib.util.find_spec("mkdocs") is None:
        pytest.skip("mkdocs is not installed (it comes with pip install -e '.[dev]')")
    site = tmp_path / "site"
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(ROOT / "mkdocs.yml"), "--site-dir", str(site)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    output = done.stdout + done.stderr
    warnings = [line for line in output.splitlines() if line.startswith(("WARNING", "ERROR"))]
    assert done.returncode == 0 and not warnings, "mkdocs build --strict:\n" + ("\n".join(warnings) or output)
    pages = sorted(p.stem for p in (ROOT / "docs").glob("*.md"))
    built = [p for p in pages if p != "index" and not (site / p / "index.html").is_file()]
    assert (site / "index.html").is_file() and not built, f"pages missing from the site: {built}"
