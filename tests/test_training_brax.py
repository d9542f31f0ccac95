"""Training with the Brax backend: a tiny go1-flat run killed after a checkpoint, resumed with its optimiser
state, then exported (its own file, so that pytest-xdist can run it beside the rsl-rl tests)."""

import numpy as np
import pytest

import policies.training as training
from legged.tasks import make
from policies.export import export_onnx
from policies.policy_io import load_policy
from policies.run_dir import RunDir
from tests.conftest import BATCH, TINY_EPISODE_S, TINY_RUN as TINY


@pytest.fixture(scope="module")
def tiny_env():
    return make("go1-flat", episode_seconds=TINY_EPISODE_S)


def _adam_count(optimizer_leaves) -> int:
    """The update counter of a saved optax optimiser state (its leaves as stored: every integer scalar is
    a step count, and they must agree)."""
    counts = {int(x) for x in optimizer_leaves if np.ndim(x) == 0 and np.issubdtype(np.asarray(x).dtype, np.integer)}
    assert len(counts) == 1, counts
    return counts.pop()


def test_brax_backend_tiny_run_resume_and_export(tiny_env, tmp_path, monkeypatch):
    """Brax PPO: a run killed right after its step-80 checkpoint resumes there, optimiser state included."""
    from policies.brax_backend import fill, load_checkpoint, params_template

    monkeypatch.setattr(training, "build_env", lambda config: tiny_env)
    real_write = RunDir.write_checkpoint

    def killed_after_checkpoint_80(self, step, suffix, payload):
        path = real_write(self, step, suffix, payload)
        if step == 80:
            raise KeyboardInterrupt
        return path

    monkeypatch.setattr(RunDir, "write_checkpoint", killed_after_checkpoint_80)
    run_dir = tmp_path / "brax"
    with pytest.raises(KeyboardInterrupt):
        training.start_run("go1-flat", str(run_dir), backend="brax", num_envs=BATCH, timesteps=120,
                           overrides=TINY, progress=False)
    monkeypatch.setattr(RunDir, "write_checkpoint", real_write)
    run = RunDir(run_dir)
    assert [p.name for p in run.checkpoints()] == ["step_000000000040.npz", "step_000000000080.npz"]
    training.resume_run(str(run_dir), progress=False)
    assert run.checkpoints()[-1].name == "step_000000000120.npz"
    records = run.metrics()
    assert records[0]["step"] <= 80 and records[-1]["step"] == 120  # appended after the resume
    lengths = [r["episode_length"] for r in records if r["episode_length"] is not None]
    assert lengths and set(lengths) == {10.0}  # whole 0.2 s episodes (Brax's own auto-reset made them 1 step)
    saved = [load_checkpoint(run.checkpoint_dir / f"step_{n:012d}.npz")["optimizer_leaves"] for n in (80, 120)]
    updates = 5 * 2  # one iteration: 5 epochs x 2 minibatches
    assert _adam_count(saved[0]) == 2 * updates  # two iterations before the kill
    assert _adam_count(saved[1]) == 3 * updates  # Adam's moments continued, not restarted
    payload = load_checkpoint(run.checkpoints()[-1])
    normalizer = fill(params_template(run.load_config(), payload["obs_sizes"], payload["num_actions"]),
                      payload["params_leaves"], "parameters", "the last checkpoint")[0]
    # Constant features (the nominal dynamics parameters) are divided by the 0.01 floor, not by 1e-6.
    assert float(np.min(normalizer.std["privileged_state"])) >= 0.0099
    policy, _ = load_policy(run_dir)
    assert policy.backend == "brax" and policy.step == 120
    assert export_onnx(policy, tmp_path / "brax.onnx")["max_abs_diff"] <= 1e-4
