"""The repository stays small and its pointers stay true: no large file is tracked outside assets/policies/ but the
listed legacy ones (which leave as they are removed), and every assets/ path that a page, a card or a shipped
config names is there."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

MAX_BYTES = 5_000_000
"""A tracked file larger than this belongs in assets/policies/ (a shipped policy) or nowhere."""

LEGACY_LARGE_FILES = (
    # Read by a shipped config (init_from, distill.student_init) or by a test: they go once their readers point at
    # assets/policies/ instead.
    "assets/runs/soccer-1v1-prior-cpu2/checkpoints/step_000008355840.pt",
    "assets/runs/soccer-1v1-prior-games-cpu2/checkpoints/step_000016011264.pt",
    "assets/runs/soccer-1v1-vision-sight-cpu2/checkpoints/step_000001966080.pt",
    "assets/runs/soccer-1v1-vision-tracker-cpu2/checkpoints/step_000001966080.pt",
    # Checkpoints of cited runs that nothing reads, still to be removed.
    "assets/runs/soccer-1v1-vision-heading-cpu2/checkpoints/step_000008011776.pt",
    "assets/runs/soccer-1v1-vision-kl-cpu2/checkpoints/step_000001228800.pt",
    "assets/runs/soccer-1v1-vision-memory-cpu2/checkpoints/step_000002088960.pt",
    "assets/runs/soccer-1v1-vision-raw-cpu2/checkpoints/step_000001966080.pt",
    "assets/runs/soccer-1v1-vision-stagger-cpu2/checkpoints/step_000014008320.pt",
    "assets/runs/soccer-1v1-vision-wide-cpu2/checkpoints/step_000004792320.pt",
)
"""Files over MAX_BYTES outside assets/policies/ that are still tracked, each by its path. Remove a line when its
file goes: the test fails on a listed file that no longer exists."""

ASSET_PATH = re.compile(r"assets/[^\s`'\"()<>|;:,]*")
"""An assets/ path in running text, up to a space, a quote, a bracket or a separator."""

PATTERN_CHARS = set("*?[]{}")
"""A path with one of these is a glob pattern or a brace list (assets/runs/rough-{teacher,dagger}-cpu2), not a file."""

PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9]*$")
"""A path part in capitals alone (NAME, PLAYER, RUN) is a placeholder the reader fills in, not a name."""


def _tracked_files() -> list[str]:
    """The files git tracks (`git ls-files`); skips the test outside a git checkout."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    done = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z"], capture_output=True, text=True)
    if done.returncode != 0 or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    return [f for f in done.stdout.split("\0") if f]


def _named_paths(text: str):
    """The assets/ paths that `text` names as files or folders: glob patterns, brace lists and placeholders skipped."""
    for match in ASSET_PATH.finditer(text):
        path = match.group(0).removesuffix("**").rstrip(".")         # markdown bold, a sentence's full stop
        if PATTERN_CHARS & set(path):
            continue                                                 # a glob pattern or a brace list
        if any(PLACEHOLDER.match(part) for part in re.split(r"[/-]", path)):
            continue                                                 # assets/policies/PLAYER, ...-NAME-cpu2/
        yield path


def test_no_large_file_outside_shipped_policies_but_the_listed_legacy_ones():
    tracked = _tracked_files()
    large = sorted(f for f in tracked if not f.startswith("assets/policies/") and (ROOT / f).is_file()
                   and (ROOT / f).stat().st_size > MAX_BYTES)
    unlisted = [f"{f} ({(ROOT / f).stat().st_size / 1e6:.1f} MB)" for f in large if f not in LEGACY_LARGE_FILES]
    assert not unlisted, ("files over 5 MB outside assets/policies/ (ship them as a policy or leave them out):\n"
                          + "\n".join(unlisted))
    gone = sorted(set(LEGACY_LARGE_FILES) - {f for f in tracked if (ROOT / f).is_file()})
    assert not gone, "listed legacy files no longer in the repository (drop them from the list):\n" + "\n".join(gone)
    assert len(set(LEGACY_LARGE_FILES)) == len(LEGACY_LARGE_FILES), "a legacy file is listed twice"


def test_named_paths_skip_patterns_and_placeholders():
    text = ("see assets/runs/a-cpu2/NOTES.md. and **assets/policies/b** or assets/runs/{a,b}-cpu2, "
            "assets/robots/*.xml, assets/policies/PLAYER and assets/runs/soccer-NAME-cpu2/ (assets/policies/c)")
    assert list(_named_paths(text)) == ["assets/runs/a-cpu2/NOTES.md", "assets/policies/b", "assets/policies/c"]


def test_every_assets_path_a_page_card_or_shipped_config_names_exists():
    _tracked_files()
    sources = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
               *sorted((ROOT / "assets" / "policies").glob("*/CARD.md")),
               *sorted((ROOT / "assets" / "policies").glob("*/config.yaml"))]
    named, missing = 0, []
    for source in sources:
        for path in _named_paths(source.read_text(encoding="utf-8")):
            named += 1
            if not (ROOT / path).exists():
                missing.append(f"{source.relative_to(ROOT)}: {path}")
    assert named >= 50, f"only {named} assets/ paths found: is the pattern still right?"
    assert not missing, "named but missing:\n" + "\n".join(sorted(set(missing)))
