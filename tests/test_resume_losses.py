"""The training loop, before and after a change: a shipped run resumed for one PPO iteration gives the same losses.

Each case copies a run of assets/policies/ (its config, its one checkpoint), shrinks it to a few environments and
one more iteration, resumes it with `legged train --resume`'s library call, and compares the iteration's losses
with the figures the loop gave before it was rebuilt around hooks (policies.training_hooks), on this machine's
CPU: a walker (no hooks) and a soccer player (the self-play pool restored from its checkpoint, an opponent drawn
before the rollout, the scripted placo player in the pool's draws).
"""

import shutil
from pathlib import Path

import pytest
import yaml

from policies import training
from policies.checkpoints import load_rsl_checkpoint
from policies.run_dir import RunDir

ROOT = Path(__file__).resolve().parents[1]

BEFORE = {
    "go1-flat-walker-v2": {"loss_value": 139.78486862182618, "loss_surrogate": -0.06354149591643363,
                           "loss_entropy": 0.9453128397464752},
    "op3-soccer-1v1-v1": {"loss_value": 5.357893335819244, "loss_surrogate": -0.016925610974431037,
                          "loss_entropy": 2.5791271686553956},
}
"""The first resumed iteration's losses under the loop before the hooks (policies/rsl_backend.py at commit 70d8522).
The soccer player is op3-soccer-1v1-v1 (shipped as op3-soccer-1v1 until its fine-tune with today's walker). The
walker's (go1-flat-walker-v2, shipped as go1-flat-walker until its last fine-tune) were measured again after
each change of the Go1 environments' action latency (its episodes changed): before the whole-period fix,
184.8875389099121 / -0.0679562397301197 / 0.9464436501264573; after it, with the controls in force held for a
partial latency, 143.31788215637206 / -0.06339863531757146 / 0.9453357100486756 (both
still given by the loop with those versions of LeggedEnv.prepare); now, with one rule (the previous action's targets,
within the motor lines at the joints' state now: legged.envs.randomize.late_controls), the figures below."""

ENVS = {"go1-flat-walker-v2": 8, "op3-soccer-1v1-v1": 4}
"""Environments of each resumed run (a few: the figures are the loop's, not the policy's)."""


def resumed_losses(policy: str, tmp_path: Path) -> dict[str, float]:
    """The losses of one PPO iteration of shipped policy `policy`, resumed in a copy under `tmp_path`."""
    source = ROOT / "assets" / "policies" / policy
    run_dir = tmp_path / policy
    (run_dir / "checkpoints").mkdir(parents=True)
    checkpoint = RunDir(source).latest_checkpoint()
    shutil.copy(checkpoint, run_dir / "checkpoints" / checkpoint.name)
    config = yaml.safe_load((source / "config.yaml").read_text())
    iteration = load_rsl_checkpoint(checkpoint)["iteration"]  # the loop runs to ceil(timesteps / per iteration)
    config.update(num_envs=ENVS[policy], threads=1, physics="native", checkpoint_every=1,
                  timesteps=(iteration + 1) * ENVS[policy] * config["ppo"]["num_steps_per_env"])
    (run_dir / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    record = training.resume_run(str(run_dir), progress=False)
    return {k: v for k, v in record.items() if k.startswith("loss_")}


@pytest.mark.slow
@pytest.mark.parametrize("policy", sorted(BEFORE))
def test_a_resumed_iteration_gives_the_losses_it_gave_before(policy, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # shipped configs name their walker by a path from the repository's root
    losses = resumed_losses(policy, tmp_path)
    assert set(losses) == set(BEFORE[policy])
    for name, before in BEFORE[policy].items():
        assert losses[name] == pytest.approx(before, rel=1e-4, abs=1e-6), name
