"""The repository stays small and its pointers stay true: no large file is tracked outside assets/policies/, no
checkpoint under assets/runs/ but a few small ones tests read, shipped checkpoints hold weights only, a clone stays
small, every assets/ path that a page, a card or a shipped config names is there, and every run record under
assets/runs/ is cited by a page or a card."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

MAX_BYTES = 5_000_000
"""A tracked file larger than this belongs in assets/policies/ (a shipped policy) or nowhere."""

MAX_TRACKED_BYTES = 150_000_000
"""All tracked files together (a fresh clone's working tree; a link counts as a link) stay under this: 166 MB with
full training checkpoints shipped, 91 MB once shipped checkpoints held the weights only (`legged slim`)."""

RESUMED_POLICIES = ("go1-flat-walker-v2", "op3-soccer-1v1-v1")
"""The shipped policies whose checkpoints keep their optimiser state (and self-play pool): tests/test_resume_losses.py
resumes them to check the training loop. Every other shipped checkpoint holds the weights only (`legged slim`)."""

RUN_CHECKPOINTS: tuple[str, ...] = ()
"""The only checkpoints allowed under assets/runs/, each with its reason (e.g. a run that goes on training in the next
session); a run there keeps its config, metrics, evaluations and notes, the checkpoints users and configs load live
in assets/policies/, those tests load in tests/fixtures/runs/."""

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


def test_no_large_file_outside_shipped_policies_and_no_stray_run_checkpoint():
    tracked = _tracked_files()
    files = [f for f in tracked if (ROOT / f).is_file() and not (ROOT / f).is_symlink()]
    large = [f"{f} ({(ROOT / f).stat().st_size / 1e6:.1f} MB)" for f in files
             if not f.startswith("assets/policies/") and (ROOT / f).stat().st_size > MAX_BYTES]
    assert not large, ("files over 5 MB outside assets/policies/ (ship them as a policy or leave them out):\n"
                       + "\n".join(large))
    checkpoints = sorted(f for f in tracked if f.startswith("assets/runs/") and "/checkpoints/" in f)
    stray = sorted(set(checkpoints) - set(RUN_CHECKPOINTS))
    assert not stray, ("checkpoints under assets/runs/ (a checkpoint someone loads belongs in assets/policies/):\n"
                       + "\n".join(stray))
    gone = sorted(set(RUN_CHECKPOINTS) - set(checkpoints))
    assert not gone, "listed run checkpoints no longer in the repository (drop them from the list):\n" + "\n".join(gone)


def test_shipped_checkpoints_hold_the_weights_only():
    from policies.run_dir import RunDir
    from policies.slim import load_any

    shipped = sorted(p for p in (ROOT / "assets" / "policies").iterdir() if (p / "config.yaml").is_file())
    full = [p.name for p in shipped if p.name not in RESUMED_POLICIES
            and not all(load_any(c).get("slimmed") for c in RunDir(p).checkpoints())]
    assert not full, f"shipped checkpoints with training state (slim them: legged slim RUN): {full}"
    assert {p.name for p in shipped} >= set(RESUMED_POLICIES)


def test_a_clone_stays_small_and_its_links_stay_inside():
    tracked = _tracked_files()
    total = sum((ROOT / f).lstat().st_size for f in tracked if (ROOT / f).exists() or (ROOT / f).is_symlink())
    assert total < MAX_TRACKED_BYTES, f"tracked files hold {total / 1e6:.0f} MB, over {MAX_TRACKED_BYTES / 1e6:.0f} MB"
    links = [f for f in tracked if (ROOT / f).is_symlink()]
    broken = [f for f in links if not (ROOT / f).exists() or ROOT not in (ROOT / f).resolve().parents]
    assert not broken, "links that lead nowhere or out of the repository:\n" + "\n".join(broken)


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


BRACES = re.compile(r"([\w./-]*)\{([\w,.-]+)\}([\w./-]*)")
"""A brace list in running text (assets/runs/rough-{teacher,dagger}-cpu2), expanded to each name it stands for."""


def _expand_braces(text: str) -> str:
    """`text` with each brace list written out: a{b,c}d -> abd acd."""
    return BRACES.sub(lambda m: " ".join(m.group(1) + part + m.group(3) for part in m.group(2).split(",")), text)


def _cited_as(run: str, runs: list[str]) -> list[str]:
    """The names a page may cite run directory `run` by: its whole name, or its tail after leading words of the task
    (soccer-1v1-vision-kl-cpu2 is 'kl-cpu2' in a table of vision runs) that no other of `runs` ends with; a tail keeps
    two words at least."""
    words = run.split("-")
    tails = ["-".join(words[i:]) for i in range(1, len(words) - 1)]
    return [run] + [t for t in tails if not any(other != run and other.endswith("-" + t) for other in runs)]


def _cites(text: str, name: str) -> bool:
    return re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", text) is not None


def test_cited_as_keeps_two_words_and_braces_expand():
    runs = ["soccer-1v1-vision-kl-cpu2", "rough-dagger-cpu2", "soccer-1v1-vision-dagger-cpu2"]
    assert _cited_as(runs[0], runs) == ["soccer-1v1-vision-kl-cpu2", "1v1-vision-kl-cpu2", "vision-kl-cpu2",
                                        "kl-cpu2"]
    assert _cited_as("rough-dagger-cpu2", runs) == ["rough-dagger-cpu2"]  # 'dagger-cpu2' names two runs
    assert _cited_as(runs[2], runs) == [runs[2], "1v1-vision-dagger-cpu2", "vision-dagger-cpu2"]
    text = _expand_braces("see assets/runs/rough-{teacher,dagger}-cpu2 and soccer-1v1-vision-kl-cpu2s")
    assert _cites(text, "rough-dagger-cpu2") and _cites(text, "rough-teacher-cpu2")
    assert not _cites(text, "soccer-1v1-vision-kl-cpu2") and not _cites(text, "dagger")


def test_every_run_record_is_cited_by_a_page_or_card():
    """assets/runs/ keeps the records a card or a docs page cites (its table's figures come from them), nothing else."""
    _tracked_files()
    sources = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
               *sorted((ROOT / "assets" / "policies").glob("*/CARD.md"))]
    text = _expand_braces("\n".join(s.read_text(encoding="utf-8") for s in sources))
    runs = sorted(p.name for p in (ROOT / "assets" / "runs").iterdir() if p.is_dir())
    assert len(runs) >= 10, f"only {len(runs)} run records found under assets/runs/"
    uncited = [run for run in runs if not any(_cites(text, name) for name in _cited_as(run, runs))]
    assert not uncited, ("run records no page or card cites (cite them where their figures are used, or remove "
                         "them):\n" + "\n".join(uncited))
