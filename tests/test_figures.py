"""Figures a reader can check: `legged card` writes a card's figures from the JSONs beside it and refuses JSONs that
are not an evaluation of that run's checkpoint; the shipped cards and tables are as their JSONs have them; soccer
JSONs count the falls their reward paid for; the figure linter finds a number typed by hand."""

import json
import shutil
from pathlib import Path

import pytest
import yaml

from legged.cli import main
from policies.cards import FIGURES_BEGIN, FIGURES_END, checked_reports, shipped_cards
from policies.figure_lint import explain, lint
from policies.policy_io import load_policy
from policies.provenance import checkpoint_record, read_sealed, sealed

ROOT = Path(__file__).resolve().parents[1]
RUN = "tests/fixtures/runs/go1-flat-brax-cpu2"
OTHER = "tests/fixtures/runs/rough-dagger-cpu2"


def _card(run: Path, figures: list[str]) -> None:
    (run / "CARD.md").write_text(f"# {run.name}\n\n<!-- card\nsummary: a test policy\nfigures: {figures}\n-->\n\n"
                                 "Prose the author wrote.\n")


def _report(run_dir, episodes=32, error=0.0512) -> dict:
    policy, _ = load_policy(run_dir)
    report = {"physics": "native", "seed": 7, "task": "go1-flat", "robots": {
        "project": {"episodes": episodes, "tracking_error_mps": error, "falls": 1, "falls_per_episode": 1 / episodes,
                    "episodes_with_a_fall": 1 / episodes, "seconds_down_per_episode": 0.02 / episodes}}}
    return sealed(report, {"policy": checkpoint_record(policy)}, {"project": ROOT / "assets/robots/go1.xml"})


def test_card_writes_the_figures_from_its_jsons_and_check_catches_a_hand_edit(tmp_path, capsys):
    run = Path(shutil.copytree(ROOT / RUN, tmp_path / "run"))
    _card(run, ["eval_robots_native.json"])
    (run / "eval_robots_native.json").write_text(json.dumps(_report(run)))
    assert main(["card", str(run)]) == 0
    text = (run / "CARD.md").read_text()
    assert "Prose the author wrote." in text and FIGURES_BEGIN in text and FIGURES_END in text
    assert "| project | 32 | 0.051 | 1 | 0.031 | 3.1% | 0.00 |" in text
    assert main(["card", str(run), "--check"]) == 0
    capsys.readouterr()
    (run / "CARD.md").write_text(text.replace("| 0.051 |", "| 0.049 |"))  # a figure typed by hand
    assert main(["card", str(run), "--check"]) == 2
    assert "not as the JSONs have them" in capsys.readouterr().err
    report = json.loads((run / "eval_robots_native.json").read_text())
    report["robots"]["project"]["tracking_error_mps"] = 0.049  # the JSON edited instead
    (run / "eval_robots_native.json").write_text(json.dumps(report))
    assert main(["card", str(run)]) == 2
    assert "eval_robots_native.json: its body does not match" in capsys.readouterr().err


def test_card_refuses_a_run_without_evaluations_or_with_another_checkpoints_json(tmp_path, capsys):
    run = Path(shutil.copytree(ROOT / RUN, tmp_path / "run"))
    (run / "CARD.md").write_text("# run\n\nNo header.\n")
    assert main(["card", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "CARD.md: no `<!-- card` header" in err
    _card(run, ["eval_robots_native.json"])
    assert main(["card", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "eval_robots_native.json: named by the card's figures but missing" in err
    (run / "eval_robots_native.json").write_text(json.dumps(_report(ROOT / OTHER)))
    assert main(["card", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "eval_robots_native.json: measured tests/fixtures/runs/rough-dagger-cpu2" in err
    (run / "eval_robots_native.json").write_text(json.dumps({"tracking_error_mps": 0.05}))
    assert main(["card", str(run)]) == 2
    assert "eval_robots_native.json: no provenance" in capsys.readouterr().err
    assert main(["card", str(tmp_path / "nowhere")]) == 2
    assert "not a run directory" in capsys.readouterr().err


def test_every_shipped_card_and_table_is_as_its_jsons_have_them():
    """Each card with a header: every JSON it names was written by an evaluation of its checkpoint (the tensor
    digest), unedited (the body hash), and its figures section and the tables of shipped policies are current."""
    assert shipped_cards(ROOT / "assets/policies"), "no card names its JSONs"
    for run in shipped_cards(ROOT / "assets/policies"):
        _, reports = checked_reports(run)
        assert reports
    assert main(["card", *map(str, shipped_cards(ROOT / "assets/policies")), "--check"]) == 0
    assert main(["card", "--summary", "--check"]) == 0


def test_a_shipped_policy_keeps_only_the_jsons_its_card_checks():
    """Every JSON beside a card with a header is one the card names (and so is checked for its checkpoint): a page
    citing assets/policies/NAME/FILE.json cites a sealed evaluation of that policy."""
    for run in shipped_cards(ROOT / "assets/policies"):
        named = yaml.safe_load((run / "CARD.md").read_text().split("<!-- card")[1].split("-->")[0])["figures"]
        assert sorted(p.name for p in run.glob("*.json")) == sorted(named), run.name


def test_soccer_jsons_count_the_falls_their_reward_paid_for():
    """For every soccer evaluation a card cites: the fall term of the reward over its weight is the falls counted."""
    checked = 0
    for run in shipped_cards(ROOT / "assets/policies"):
        weight = (yaml.safe_load((run / "config.yaml").read_text())["env"].get("rewards") or {}).get("fall")
        for name, report, _ in checked_reports(run)[1]:
            for figures in (report.get("robots") or {"": report}).values():
                if "goals_for_per_episode" in figures and weight:
                    assert figures["reward_terms"]["fall"] / weight == pytest.approx(figures["falls_per_episode"]), \
                        f"{run.name}/{name}"
                    checked += 1
    assert checked > 0


def test_the_linter_finds_figures_no_cited_file_holds(tmp_path):
    (tmp_path / "docs").mkdir()
    evidence = {"episodes": 85, "success_rate": 0.9529, "tracking_error_mps": 0.0481, "falls_per_episode": 0.25,
                "seconds": 85.2}  # 21.25 falls: 0.25 per episode of 85; 1.42 minutes: 85.2 s
    (tmp_path / "docs" / "eval.json").write_text(json.dumps(evidence))
    page = tmp_path / "docs" / "page.md"
    page.write_text("From eval.json: 95.3% success (81 of 85), 0.048 m/s, 21.25 falls in all, a 95% interval, 21 falls\n"
                    "in 1.42 minutes (85.2 s in the JSON); a step of 0.4 s is a constant of this page.\n"
                    "<!-- constants: 0.4 (step, s) -->\n\n"
                    "    legged eval RUN --set ppo.learning_rate=0.0003   # a command, not a figure\n")
    assert lint(tmp_path, ["docs/page.md"]) == []
    page.write_text(page.read_text().replace("95.3%", "68%").replace("0.048", "0.049").replace("21 falls", "23 falls")
                    .replace("0.4 (step", "0.5 (step"))
    assert [f.text for f in lint(tmp_path, ["docs/page.md"])] == ["68%", "0.049", "23", "0.4"]


def test_the_linter_reads_shares_code_spans_paths_and_signed_figures_as_a_reader_would(tmp_path):
    run = tmp_path / "assets" / "runs" / "walk"
    run.mkdir(parents=True)
    (run / "eval.json").write_text(json.dumps({"iteration": 1.0, "learning_rate": 0.5, "goal_rate": 0.25,
                                               "trained_steps": 10_800_000}))
    page = tmp_path / "README.md"
    page.write_text("Run assets/runs/walk. It scores 25% (`goal_rate`), +10.8M steps, vy +-0.04 m/s, `a\n"
                    "command 0.123 that wraps`.\n")
    assert lint(tmp_path, ["README.md"]) == []
    assert [(f.text, source) for f, source in explain(tmp_path, ["README.md"])] == [
        ("25%", "assets/runs/walk/eval.json:goal_rate"), ("10.8M", "assets/runs/walk/eval.json:trained_steps")]
    page.write_text(page.read_text().replace("25%", "100%").replace("+10.8M", "+10.9M") + "And 50%.\n")
    assert [f.text for f in lint(tmp_path, ["README.md"])] == ["100%", "10.9M", "50%"]  # not iteration, learning_rate


def test_every_page_holds_only_figures_its_evidence_has():
    findings = lint(ROOT)
    assert not findings, "figures no cited file holds:\n" + "\n".join(map(str, findings))


def test_the_shipped_json_files_read_back_sealed():
    for run in shipped_cards(ROOT / "assets/policies"):
        for name in yaml.safe_load((run / "CARD.md").read_text().split("<!-- card")[1].split("-->")[0])["figures"]:
            assert read_sealed(run / name)[1]["policies"]["policy"]["checkpoint"].startswith("assets/policies/")
