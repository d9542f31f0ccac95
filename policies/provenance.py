"""Where a result came from, written into every evaluation's JSON by the code that measured it.

A report's `provenance` names the checkpoint it measured (its path relative to the repository, absolute only
outside it; the file's sha256; and `tensors_sha256`, a digest of the tensors the evaluation reads: the deployed
actor with its observation normaliser and encoder, which `legged slim` leaves unchanged), the frozen runs it
played through (walker, get-up, pilot, opponent), the robot model files' sha256, the code's commit and whether
its tree was clean, the command line and the date, and `body_sha256`: a hash of the whole report without that
field, so a JSON edited afterwards no longer matches it (`check_sealed`).
"""

from __future__ import annotations

import datetime
import functools
import hashlib
import json
import shlex
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np

from policies.policy_io import load_policy

REPO_ROOT = Path(__file__).resolve().parents[1]
"""The repository the code runs from (paths inside it are written relative to it)."""

BODY_HASH = "body_sha256"
"""The field of `provenance` that holds the hash of the rest of the report."""


class ProvenanceError(ValueError):
    """A report without provenance, or whose body no longer matches its hash (one line naming the file)."""


def repo_path(path: str | Path) -> str:
    """`path` relative to the repository when inside it, else absolute."""
    resolved = Path(path).resolve()
    try:
        return resolved.relative_to(REPO_ROOT).as_posix()
    except ValueError:
        return str(resolved)


def file_sha256(path: str | Path) -> str:
    """The sha256 of a file's bytes, hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _update(digest, name: str, array: np.ndarray) -> None:
    array = np.ascontiguousarray(array)
    digest.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
    digest.update(array.tobytes())


def tensor_digest(policy) -> str:
    """sha256 of the tensors `policy` (policies.policy_io.Policy) acts with: the deployed torch actor's state (its
    layers, normaliser and encoder) or Brax's normaliser and policy parameters, each with its name, dtype and
    shape, in name order; what an optimiser or a resume needs is not among them."""
    digest = hashlib.sha256()
    if policy.torch_module is not None:
        state = policy.torch_module.state_dict()
        for name in sorted(state):
            _update(digest, name, state[name].detach().cpu().numpy())
    elif policy.brax_params is not None:
        leaves = jax.tree_util.tree_flatten_with_path(policy.brax_params)[0]
        for path, leaf in sorted(leaves, key=lambda item: jax.tree_util.keystr(item[0])):
            _update(digest, jax.tree_util.keystr(path), np.asarray(leaf))
    else:
        raise ProvenanceError(f"{policy.checkpoint}: a policy without tensors has no digest")
    return digest.hexdigest()


def checkpoint_record(policy) -> dict:
    """What names a loaded policy's checkpoint: its path (`repo_path`), the file's sha256, `tensors_sha256` and the
    steps it trained."""
    return {"checkpoint": repo_path(policy.checkpoint), "sha256": file_sha256(policy.checkpoint),
            "tensors_sha256": tensor_digest(policy), "trained_steps": int(policy.step)}


def run_record(run_dir: str | Path) -> dict:
    """`checkpoint_record` of a run's newest checkpoint (a frozen walker, get-up, pilot or opponent)."""
    return dict(checkpoint_record(load_policy(run_dir)[0]), run=repo_path(run_dir))


@functools.lru_cache(maxsize=1)
def code_state() -> dict:
    """The repository's commit and whether its tracked and untracked files (less the ignored ones) are as
    committed; None for both outside a git checkout."""
    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(REPO_ROOT), *args], capture_output=True, text=True, timeout=30)
        except (OSError, subprocess.TimeoutExpired):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    status = git("status", "--porcelain") if commit else None
    return {"commit": commit, "clean": None if status is None else status == ""}


def command_line() -> str:
    """This process's command line as a shell would take it (`legged ...` for the command, however started)."""
    program = Path(sys.argv[0]).name
    return shlex.join(["legged" if program in ("legged", "__main__.py") else program, *sys.argv[1:]])


def canonical(report: dict) -> bytes:
    """The report as canonical JSON (sorted keys, no spaces), without `provenance.body_sha256`: what is hashed."""
    body = json.loads(json.dumps(report))
    if isinstance(body.get("provenance"), dict):
        body["provenance"].pop(BODY_HASH, None)
    return json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=True).encode()


def sealed(report: dict, policies: dict | None = None, robots: dict | None = None) -> dict:
    """`report` with its `provenance`: `policies` (role -> `checkpoint_record` or `run_record`, e.g. {"policy": ...,
    "walker": ...}) and `robots` (name -> model file) added to any it has, then the code state, the command line,
    the date and the body's hash (recomputed over everything, so sealing again after adding fields is sound)."""
    report = json.loads(json.dumps(report))  # plain JSON types, as it will be read back
    record = dict(report.get("provenance") or {})
    if policies:
        record["policies"] = dict(record.get("policies", {}), **policies)
    if robots:
        record["robot_models"] = dict(record.get("robot_models", {}),
                                      **{name: {"file": repo_path(path), "sha256": file_sha256(path)}
                                         for name, path in robots.items()})
    record.update(code_state(), command=command_line(),
                  date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"))
    report["provenance"] = record
    report["provenance"][BODY_HASH] = hashlib.sha256(canonical(report)).hexdigest()
    return report


def check_sealed(report: dict, source: str = "report") -> dict:
    """The report's provenance if its body still matches its hash; ProvenanceError naming `source` otherwise."""
    record = report.get("provenance") if isinstance(report, dict) else None
    if not isinstance(record, dict) or BODY_HASH not in record:
        raise ProvenanceError(f"{source}: no provenance (written before evaluations recorded theirs; evaluate again)")
    if hashlib.sha256(canonical(report)).hexdigest() != record[BODY_HASH]:
        raise ProvenanceError(f"{source}: its body does not match provenance.{BODY_HASH} (edited after it was "
                              f"written)")
    return record


def read_sealed(path: str | Path) -> tuple[dict, dict]:
    """(report, provenance) of a JSON file an evaluation wrote; ProvenanceError naming the file if it is not one or
    was edited."""
    try:
        report = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ProvenanceError(f"{path}: not a readable JSON report ({exc})") from None
    return report, check_sealed(report, str(path))


def policy_digests(record: dict) -> set[str]:
    """Every `tensors_sha256` a provenance names (the policy's and the frozen runs')."""
    return {p["tensors_sha256"] for p in record.get("policies", {}).values() if "tensors_sha256" in p}


def frozen_runs(config, **others) -> dict:
    """`run_record` of every run an evaluation of a run with `config` plays through besides the policy: the soccer
    walker, a learned get-up and the pilot its config names, and `others` (role -> an opponent, teammate or
    teacher); names that are no run directory (placo, scripted, self, script) are skipped."""
    soccer = getattr(config, "soccer", None)
    named = {} if soccer is None else {"walker": soccer.walker, "getup": soccer.getup, "pilot": soccer.pilot}
    named.update(others)
    return {role: run_record(path) for role, path in named.items()
            if path and (Path(path) / "config.yaml").is_file()}
