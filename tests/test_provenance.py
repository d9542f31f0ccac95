"""Provenance written by the evaluator (policies.provenance): a report names its checkpoint relative to the
repository, the file's and the tensors' digests (the latter unchanged by `legged slim`, changed by any weight), the
robot model file, the commit, command and date, and a hash of its body that catches a number edited afterwards."""

import json
import shutil

import pytest
import torch

from legged.cli import main
from policies.checkpoints import load_rsl_checkpoint
from policies.policy_io import load_policy
from policies.provenance import (ProvenanceError, check_sealed, checkpoint_record, read_sealed, repo_path, sealed,
                                 tensor_digest)
from policies.run_dir import RunDir

RSL_RUN = "tests/fixtures/runs/rough-dagger-cpu2"
BRAX_RUN = "tests/fixtures/runs/go1-flat-brax-cpu2"


@pytest.mark.parametrize("source", [RSL_RUN, BRAX_RUN])
def test_the_tensor_digest_survives_slimming_and_moving_but_not_a_changed_weight(source, tmp_path):
    original = tensor_digest(load_policy(source)[0])
    run = shutil.copytree(source, tmp_path / "run")
    assert main(["slim", str(run)]) == 0
    slimmed = load_policy(run)[0]
    assert tensor_digest(slimmed) == original  # another file (slimmed, elsewhere), the same tensors
    assert checkpoint_record(slimmed)["sha256"] != checkpoint_record(load_policy(source)[0])["sha256"]
    if source == RSL_RUN:
        path = RunDir(run).latest_checkpoint()
        payload = load_rsl_checkpoint(path)
        weights = payload["alg"]["student_state_dict"]
        name = next(k for k, v in weights.items() if v.is_floating_point() and v.numel() > 1)
        weights[name] = weights[name].clone()
        weights[name].view(-1)[0] += 1e-3
        torch.save(payload, path)
        assert tensor_digest(load_policy(run)[0]) != original


def test_a_sealed_report_names_its_sources_and_detects_an_edit(tmp_path):
    policy, _ = load_policy(RSL_RUN)
    report = sealed({"episodes": 8, "falls_per_episode": 0.125, "nested": {"success_rate": 0.9}},
                    {"policy": checkpoint_record(policy)}, {"project": "assets/robots/go1.xml"})
    record = report["provenance"]
    assert record["policies"]["policy"]["checkpoint"].startswith("tests/fixtures/runs/rough-dagger-cpu2/checkpoints/")
    assert len(record["policies"]["policy"]["tensors_sha256"]) == 64
    assert record["robot_models"]["project"]["file"] == "assets/robots/go1.xml"
    assert {"commit", "clean", "command", "date", "body_sha256"} <= set(record)
    path = tmp_path / "eval.json"
    path.write_text(json.dumps(report))
    assert read_sealed(path)[1] == record  # read back from its JSON: intact
    edited = json.loads(path.read_text())
    edited["nested"]["success_rate"] = 0.95
    with pytest.raises(ProvenanceError, match="does not match provenance.body_sha256"):
        check_sealed(edited, "eval.json")
    with pytest.raises(ProvenanceError, match="old.json: no provenance"):
        check_sealed({"episodes": 8}, "old.json")
    resealed = sealed(dict(report, where="added"))  # fields added by a caller are hashed by sealing again
    assert check_sealed(resealed)["policies"] == record["policies"]


def test_paths_inside_the_repository_are_relative_and_outside_absolute(tmp_path):
    assert repo_path("assets/robots/op3.xml") == "assets/robots/op3.xml"
    assert repo_path(tmp_path / "x.pt") == str((tmp_path / "x.pt").resolve())
