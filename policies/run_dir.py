"""A training run on disk: config.yaml, metrics.jsonl, TensorBoard events and atomic checkpoints.

    RUN/config.yaml            the resolved TrainConfig (every field, env config included)
    RUN/metrics.jsonl          one JSON object per report: step (env steps so far), episode_return, ...
    RUN/tb/                    TensorBoard events of the same numbers
    RUN/checkpoints/*.pt|.pkl  checkpoints named by env step, written to a temporary file and renamed
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import yaml

from legged.files import TEMP_GLOB, write_atomic, writer_pid
from policies.config import ConfigError, TrainConfig, load_config, to_dict

CHECKPOINT = re.compile(r"^step_(\d{12})\.(pt|npz|pkl)$")
"""Checkpoint file names: .pt (rsl-rl, torch tensors), .npz (Brax, arrays); .pkl (old Brax pickles) is listed
so that loading it can say how to convert it."""


def checkpoint_step(path: Path) -> int:
    """The environment step in a checkpoint's file name (step_000010002432.pt: 10002432)."""
    return int(CHECKPOINT.match(Path(path).name).group(1))


class RunDirError(ValueError):
    """The run directory cannot be used (unwritable, not a run, no checkpoint); the message says why."""


class TrainingDiverged(RunDirError):
    """A loss or a network parameter became NaN or infinite: the run stops before saving it."""


def check_compatible(obs_sizes: dict, num_actions: int, env, source) -> None:
    """Refuse a checkpoint (or policy) whose observation or action sizes differ from the environment's."""
    if obs_sizes != env.observation_dims() or num_actions != env.action_size:
        raise RunDirError(f"checkpoint {source} expects observations {obs_sizes} and {num_actions} actions; "
                          f"the environment gives {env.observation_dims()} and {env.action_size}")


def check_policy(policy, env, source=None) -> None:
    """Refuse a policy whose actor reads observations (the groups of `policy.inputs`) or gives actions of other sizes
    than the environment's; the groups only critics read (privileged_state) may differ, as on another robot model
    whose own parameters are not drawn."""
    mine, theirs = env.observation_dims(), policy.obs_sizes
    if any(mine.get(g) != theirs.get(g) for g in policy.inputs) or policy.num_actions != env.action_size:
        read = {g: theirs.get(g) for g in policy.inputs}
        raise RunDirError(f"checkpoint {source or policy.checkpoint} reads observations {read} and gives "
                          f"{policy.num_actions} actions; the environment gives "
                          f"{ {g: mine.get(g) for g in policy.inputs} } and {env.action_size}")


class RunDir:
    """Files of one training run."""

    def __init__(self, path: str | Path):
        self.path = Path(path)

    @property
    def config_path(self) -> Path:
        return self.path / "config.yaml"

    @property
    def metrics_path(self) -> Path:
        return self.path / "metrics.jsonl"

    @property
    def checkpoint_dir(self) -> Path:
        return self.path / "checkpoints"

    def create(self, config: TrainConfig) -> "RunDir":
        """Start a new run here; refuses a directory that already holds one."""
        if self.config_path.exists():
            raise RunDirError(f"{self.path} already holds a run; continue it with `legged train --resume "
                              f"{self.path}` or choose another --run-dir")
        try:
            self.checkpoint_dir.mkdir(parents=True, exist_ok=True)
            probe = self.path / ".write-test"
            probe.write_text("ok")
            probe.unlink()
        except OSError as exc:
            raise RunDirError(f"run directory {self.path} is not writable: {exc.strerror}") from None
        self.save_config(config)
        return self

    def save_config(self, config: TrainConfig) -> None:
        """Write the run's resolved config (atomically)."""
        write_atomic(self.config_path, yaml.safe_dump(to_dict(config), sort_keys=False).encode())

    def discard_unstarted(self) -> bool:
        """Remove a run that `create` made but that failed before its first checkpoint or metrics record (e.g.
        a warm start that did not fit), so that the same command can be run again; True if removed."""
        if self.checkpoints() or self.metrics_path.exists():
            return False
        for leftover in (self.config_path, *self.path.glob(TEMP_GLOB), *self.checkpoint_dir.glob(TEMP_GLOB),
                         *(self.path / "tb").glob("events.out.tfevents.*")):
            leftover.unlink(missing_ok=True)
        for folder in (self.checkpoint_dir, self.path / "tb", self.path):
            try:
                folder.rmdir()
            except OSError:  # not empty (something else lives there) or already gone: leave it
                pass
        return True

    def load_config(self) -> TrainConfig:
        """The run's resolved config."""
        if not self.config_path.is_file():
            raise RunDirError(f"{self.path} is not a run directory (no config.yaml)")
        try:
            return load_config(yaml.safe_load(self.config_path.read_text()))
        except (yaml.YAMLError, ConfigError) as exc:
            raise RunDirError(f"{self.config_path} is unusable: {exc}") from None

    def log(self, record: dict, writer=None) -> None:
        """Append a metrics record (and its numbers to TensorBoard when a writer is given). A non-finite
        number is written as the string "nan", "inf" or "-inf": valid JSON that keeps it visible."""
        clean = {k: (str(v) if isinstance(v, float) and not math.isfinite(v) else v) for k, v in record.items()}
        with open(self.metrics_path, "a") as f:
            f.write(json.dumps(clean) + "\n")
            f.flush()
            os.fsync(f.fileno())
        if writer is not None:
            for k, v in record.items():
                if k != "step" and isinstance(v, (int, float)) and v is not None:
                    writer.add_scalar(k, v, record["step"])
            writer.flush()

    def forget_after(self, step: int) -> int:
        """Drop the metrics records written after env step `step` (a resumed run's checkpoint: a killed run logged
        past its last checkpoint, and the resumed run writes those iterations again); the number dropped."""
        records = self.metrics()
        kept = [r for r in records if r["step"] <= step]
        if len(kept) < len(records):
            write_atomic(self.metrics_path, "".join(json.dumps(r) + "\n" for r in kept))
        return len(records) - len(kept)

    def metrics(self) -> list[dict]:
        """All metrics records so far; a line cut short (a killed run, or one being written) is skipped."""
        try:
            lines = self.metrics_path.read_text().splitlines()
        except FileNotFoundError:
            return []
        records = []
        for line in lines:
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(record, dict) and isinstance(record.get("step"), (int, float)):
                records.append(record)
        return records

    def checkpoint_path(self, step: int, suffix: str) -> Path:
        return self.checkpoint_dir / f"step_{step:012d}.{suffix}"

    def checkpoints(self) -> list[Path]:
        """Checkpoints, oldest first."""
        if not self.checkpoint_dir.is_dir():
            return []
        found = [p for p in self.checkpoint_dir.iterdir() if CHECKPOINT.match(p.name)]
        return sorted(found, key=checkpoint_step)

    def latest_checkpoint(self) -> Path:
        """The newest checkpoint; RunDirError if there is none."""
        found = self.checkpoints()
        if not found:
            raise RunDirError(f"{self.path} has no checkpoint yet (nothing to resume or evaluate)")
        return found[-1]

    def write_checkpoint(self, step: int, suffix: str, payload: bytes) -> Path:
        """Write a checkpoint atomically (a killed run never leaves a half-written file under the real name)."""
        return write_atomic(self.checkpoint_path(step, suffix), payload)

    def clean_stale(self) -> list[Path]:
        """Remove temporary files that killed processes left behind (`.<name>.<random>.<pid>.tmp`, written by
        `legged.files.write_atomic`); returns them. A file whose writer still runs is left alone."""
        removed = []
        for tmp in list(self.path.glob(TEMP_GLOB)) + list(self.checkpoint_dir.glob(TEMP_GLOB)):
            pid = writer_pid(tmp.name)
            if pid is not None:
                try:
                    os.kill(pid, 0)  # still running: its file is being written
                    continue
                except ProcessLookupError:
                    pass
                except PermissionError:  # another user's live process
                    continue
            tmp.unlink(missing_ok=True)
            removed.append(tmp)
        return removed
