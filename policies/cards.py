"""`legged card RUN`: the figures of a policy's CARD.md written from the evaluation JSONs beside it.

A card declares, in a comment at its top, what the policy does and which JSONs hold its figures:

    <!-- card
    summary: Go1 velocity tracking on flat ground
    figures: [eval_robots_native.json, eval_robots_mjx.json]
    deploy: true
    -->

(`deploy: true`: a policy to deploy, listed in the README; older versions kept for the runs trained through them say
nothing) and holds, between FIGURES_BEGIN and FIGURES_END, one table per JSON in that order: what was measured, the
command that measured it (from the JSON's provenance), and the figures. `legged card RUN` rewrites that section (the
prose around it is the author's); `legged card RUN --check` says whether it is as the JSONs have it. Every JSON must
have been written by an evaluation (policies.provenance: an intact body hash) of this run's checkpoint (the tensors it
measured are the run's) through the walker, get-up and pilot the run's config names, or the command fails in one line
naming the file. The first JSON gives the policy's headline (policies.card_tables.headline), which the README's and
docs/policies.md's tables of shipped policies are made of (policies.card_summary).
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from legged.files import write_atomic
from policies.card_tables import json_tables
from policies.policy_io import load_policy
from policies.provenance import ProvenanceError, frozen_runs, read_sealed, tensor_digest
from policies.run_dir import RunDir, RunDirError

FIGURES_BEGIN = "<!-- figures: written by `legged card` from the JSONs named above; edit those, not this -->"
FIGURES_END = "<!-- end of figures -->"
_HEADER = re.compile(r"<!--\s*card\s*\n(.*?)-->", re.S)


class CardError(ValueError):
    """A card that cannot be written or checked (one line naming the file and the cause)."""


def card_header(card_path: Path) -> dict:
    """The `<!-- card ... -->` header of a CARD.md: summary (str) and figures (JSON file names, at least one)."""
    if not card_path.is_file():
        raise CardError(f"{card_path}: no such card")
    match = _HEADER.search(card_path.read_text())
    if match is None:
        raise CardError(f"{card_path}: no `<!-- card` header naming its summary and figures (see policies/cards.py)")
    try:
        header = yaml.safe_load(match.group(1)) or {}
    except yaml.YAMLError as exc:
        raise CardError(f"{card_path}: its card header is not YAML ({str(exc).splitlines()[0]})") from None
    figures = header.get("figures")
    if not isinstance(header.get("summary"), str) or not isinstance(figures, list) or not figures \
            or not all(isinstance(f, str) and f.endswith(".json") for f in figures):
        raise CardError(f"{card_path}: its card header needs `summary:` (one line) and `figures:` (a list of JSON "
                        f"files beside it)")
    return {"summary": header["summary"].strip(), "figures": figures, "deploy": bool(header.get("deploy", False))}


def checked_reports(run_dir: str | Path) -> tuple[dict, list[tuple[str, dict, dict]]]:
    """(the card's header, [(file name, report, provenance)] of the JSONs it names), each checked: written by an
    evaluation, unedited, of this run's checkpoint; CardError naming the file otherwise."""
    run = Path(run_dir)
    header = card_header(run / "CARD.md")
    try:
        policy, config = load_policy(run)
        frozen = frozen_runs(config)  # the walker, get-up and pilot it plays through today
    except (RunDirError, FileNotFoundError) as exc:
        raise CardError(f"{run}: {exc}") from None
    digest = tensor_digest(policy)
    out = []
    for name in header["figures"]:
        path = run / name
        if not path.is_file():
            raise CardError(f"{path}: named by the card's figures but missing (evaluate and save it there)")
        try:
            report, record = read_sealed(path)
        except ProvenanceError as exc:
            raise CardError(str(exc)) from None
        measured = record.get("policies", {}).get("policy", {})
        if measured.get("tensors_sha256") != digest:
            raise CardError(f"{path}: measured {measured.get('checkpoint', 'another checkpoint')}, whose tensors are "
                            f"not this run's ({policy.checkpoint.name})")
        for role, run_now in frozen.items():
            then = record.get("policies", {}).get(role, {})
            if then.get("tensors_sha256") != run_now["tensors_sha256"]:
                raise CardError(f"{path}: played through another {role} ({then.get('run', 'none')}) than this run's "
                                f"config names ({run_now['run']})")
        out.append((name, report, record))
    return header, out


def figures_section(run_dir: str | Path) -> str:
    """The card's figures section (between FIGURES_BEGIN and FIGURES_END, both included) as its JSONs have it."""
    _, reports = checked_reports(run_dir)
    parts = [FIGURES_BEGIN]
    for name, report, record in reports:
        parts.append(json_tables(name, report, record))
    parts.append(FIGURES_END)
    return "\n\n".join(parts)


def _with_section(text: str, section: str, card: Path) -> str:
    if text.count(FIGURES_BEGIN) > 1 or text.count(FIGURES_END) > 1 or \
            (FIGURES_BEGIN in text) != (FIGURES_END in text):
        raise CardError(f"{card}: its figures section is broken (one `{FIGURES_BEGIN[:20]}...` and one "
                        f"`{FIGURES_END}`)")
    if FIGURES_BEGIN not in text:  # a first section goes after the header
        end = _HEADER.search(text).end()
        return text[:end] + "\n\n" + section + "\n" + text[end:]
    start, stop = text.index(FIGURES_BEGIN), text.index(FIGURES_END) + len(FIGURES_END)
    return text[:start] + section + text[stop:]


def write_card(run_dir: str | Path, check: bool = False) -> dict:
    """Rewrite (or with `check` only compare) the figures section of the run's CARD.md; returns the card, the JSONs
    and whether the card was (`check`: is) as they have it. CardError names the cause."""
    card = Path(run_dir) / "CARD.md"
    text = card.read_text() if card.is_file() else ""
    section = figures_section(run_dir)
    wanted = _with_section(text, section, card)
    current = text == wanted
    if not check and not current:
        write_atomic(card, wanted.encode())
    return {"card": str(card), "figures": card_header(card)["figures"], "up_to_date": current}


def shipped_cards(policies_dir: str | Path = "assets/policies") -> list[Path]:
    """The run directories under `policies_dir` whose CARD.md has a card header (the policies `legged card` writes)."""
    return sorted(p.parent for p in Path(policies_dir).glob("*/CARD.md") if _HEADER.search(p.read_text()))


def run_exists(run_dir: str | Path) -> None:
    """CardError in one line if `run_dir` is not a run directory with a card."""
    run = Path(run_dir)
    if not RunDir(run).config_path.is_file():
        raise CardError(f"{run}: not a run directory (no config.yaml)")
    if not (run / "CARD.md").is_file():
        raise CardError(f"{run}: has no CARD.md")
