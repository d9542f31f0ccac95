"""Training with the Brax backend: a tiny run killed after a checkpoint, resumed with its optimiser state, then
exported; and the committed Go1 Brax run loads and exports (its own file, so that pytest-xdist can run it beside
the rsl-rl tests).

The run trains a small pure-JAX environment with the task interface Brax training reads (`SlidingBlock`): the
backend's start, resume, optimiser state, full resets and checkpoints do not depend on the task, and compiling
Brax's PPO program around an MJX Go1 twice (start and resume) took 19 minutes of the suite on a slow 2-core
machine. The Go1 MJX environment itself is checked in tests/test_envs.py and against native MuJoCo in
tests/test_mjx_vs_native.py; tests/fixtures/runs/go1-flat-brax-cpu2 is the Brax backend's Go1 run."""

import dataclasses
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from brax.envs.base import Env, State

import policies.training as training
from legged.envs.api import MjxEnv
from legged.tasks import make
from policies.export import export_onnx
from policies.policy_io import load_policy
from policies.run_dir import RunDir
from tests.conftest import BATCH, TINY_RUN as TINY

GO1_BRAX_RUN = Path(__file__).resolve().parents[1] / "tests/fixtures/runs/go1-flat-brax-cpu2"
"""The Brax backend's committed go1-flat run (config, metrics, final checkpoint)."""


@dataclasses.dataclass(frozen=True)
class SlidingBlockConfig:
    """The one config field Brax training reads."""

    episode_steps: int = 10
    """Control steps per episode (the tiny runs' 0.2 s episodes of 10 steps)."""


class SlidingBlock(Env):
    """A block on a line pushed by two actions, rewarded for staying near the origin. Like the tasks here it
    counts its own steps in `info` and ends its episodes itself (at their time limit: `truncation`), hands a new
    episode a carry (none) and its privileged state holds constant features (as Go1's nominal dynamics parameters
    are); legged.envs.vector.VectorEnv's MJX engine runs it too (tests/test_training.py)."""

    config = SlidingBlockConfig()

    def reset(self, rng, carry=None):
        position = jax.random.uniform(rng, (), minval=-1.0, maxval=1.0)
        info = {"step": jnp.int32(0), "position": position, "velocity": jnp.float32(0.0),
                "truncation": jnp.float32(0.0)}
        zero = jnp.float32(0.0)
        return State(None, self._obs(info), zero, zero, {"reward/position": zero}, info)

    def step(self, state, action):
        info = state.info
        velocity = 0.9 * info["velocity"] + 0.1 * jnp.sum(jnp.clip(action, -1.0, 1.0))
        position = info["position"] + 0.1 * velocity
        info = {**info, "step": info["step"] + 1, "position": position, "velocity": velocity}  # wrappers' keys kept
        reward = -jnp.square(position)
        done = (info["step"] >= self.config.episode_steps).astype(jnp.float32)
        info["truncation"] = done  # its episodes end at their time limit only
        return State(None, self._obs(info), reward, done, {"reward/position": reward}, info)

    def carry(self, info) -> dict:
        """What a new episode inherits from the one before: nothing (the tasks' curriculum carry)."""
        return {}

    @staticmethod
    def _obs(info) -> dict:
        state = jnp.stack([info["position"], info["velocity"]])
        constants = jnp.array([1.0, 0.5])
        return {"state": state, "privileged_state": jnp.concatenate([state, constants])}

    @property
    def observation_size(self):
        return {"state": (2,), "privileged_state": (4,)}

    observation_dims = MjxEnv.observation_dims  # the sizes as the tasks report them

    @property
    def action_size(self) -> int:
        return 2

    @property
    def backend(self) -> str:
        return "jax"


def _adam_count(optimizer_leaves) -> int:
    """The update counter of a saved optax optimiser state (its leaves as stored: every integer scalar is
    a step count, and they must agree)."""
    counts = {int(x) for x in optimizer_leaves if np.ndim(x) == 0 and np.issubdtype(np.asarray(x).dtype, np.integer)}
    assert len(counts) == 1, counts
    return counts.pop()


def test_brax_backend_tiny_run_resume_and_export(tmp_path, monkeypatch):
    """Brax PPO: a run killed right after its step-80 checkpoint resumes there, optimiser state included."""
    from policies.brax_backend import fill, load_checkpoint, params_template

    monkeypatch.setattr(training, "build_env", lambda config: SlidingBlock())
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
    with run.metrics_path.open("a") as f:  # a report logged after the last checkpoint, before the kill
        f.write(json.dumps({"step": 100, "episode_return": None, "episode_length": None}) + "\n")
    training.resume_run(str(run_dir), progress=False)
    assert run.checkpoints()[-1].name == "step_000000000120.npz"
    records = run.metrics()
    assert records[0]["step"] <= 80 and records[-1]["step"] == 120  # appended after the resume
    steps = [r["step"] for r in records]
    assert steps == sorted(set(steps)) and 100 not in steps  # the report past the checkpoint was dropped
    lengths = [r["episode_length"] for r in records if r["episode_length"] is not None]
    assert lengths and set(lengths) == {10.0}  # whole episodes (Brax's own auto-reset made them 1 step)
    assert all("episode_reward_position" in r for r in records if r["episode_length"] is not None)
    saved = [load_checkpoint(run.checkpoint_dir / f"step_{n:012d}.npz")["optimizer_leaves"] for n in (80, 120)]
    updates = 5 * 2  # one iteration: 5 epochs x 2 minibatches
    assert _adam_count(saved[0]) == 2 * updates  # two iterations before the kill
    assert _adam_count(saved[1]) == 3 * updates  # Adam's moments continued, not restarted
    payload = load_checkpoint(run.checkpoints()[-1])
    normalizer = fill(params_template(run.load_config(), payload["obs_sizes"], payload["num_actions"]),
                      payload["params_leaves"], "parameters", "the last checkpoint")[0]
    # Constant features are divided by the 0.01 floor, not by 1e-6.
    assert float(np.min(normalizer.std["privileged_state"])) >= 0.0099
    policy, _ = load_policy(run_dir)
    assert policy.backend == "brax" and policy.step == 120
    assert export_onnx(policy, tmp_path / "brax.onnx")["max_abs_diff"] <= 1e-4


def test_the_committed_go1_brax_run_loads_acts_and_exports(tmp_path):
    """The Go1 run trained with this backend fits go1-flat as it trained it (its own saved config), acts, and
    exports with parity, its actions inside the tanh's bound."""
    policy, config = load_policy(GO1_BRAX_RUN)
    assert config.backend == "brax" and policy.backend == "brax"
    env = make("go1-flat", config.env)
    assert policy.obs_sizes == env.observation_dims() and policy.num_actions == env.action_size
    actions = policy.act(np.zeros((3, policy.obs_sizes["state"]), np.float32))
    assert actions.shape == (3, env.action_size) and np.all(np.isfinite(actions))
    check = export_onnx(policy, tmp_path / "go1.onnx")
    assert check["max_abs_diff"] <= 1e-4 and check["action_bound"] == 1.0 and check["max_abs_action"] <= 1.0 + 1e-6
