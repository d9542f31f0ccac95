"""What a task family adds to the rsl training loop (policies.rsl_backend.train_rsl), as hooks the loop calls at
its start, around each iteration and when it saves a checkpoint. The loop knows no task family: locomotion and
confined runs take these defaults, the soccer games theirs (policies.soccer.hooks)."""

from __future__ import annotations


class TrainingHooks:
    """The loop's hooks. These defaults add nothing: the task's environment is batched as it is, nothing is done
    between iterations, nothing is added to the metrics or the checkpoints."""

    def played_env(self, env):
        """The environment the loop batches and steps (`env` itself here; a pilot's is its vision student's game)."""
        return env

    def wrap(self, venv):
        """The rsl-rl environment the learner trains in, over the batched one (`venv` itself here)."""
        return venv

    def start(self, venv, payload: dict | None, iteration: int, rank: int) -> None:
        """Once the environments and networks exist: `payload` is the checkpoint being resumed (None for a new
        run), `iteration` the iteration it starts at, `rank` this process's (torchrun)."""

    def before_rollout(self, venv) -> None:
        """Before each iteration's rollout."""

    def after_step(self, dones) -> None:
        """After each environment step of a rollout, with its done flags (a torch tensor)."""

    def after_update(self, alg, iteration: int) -> None:
        """After each update of the networks; `iteration` counts the updates done so far."""

    def record(self, venv) -> dict:
        """Fields this family adds to each iteration's metrics record."""
        return {}

    def saved_state(self) -> dict:
        """Entries this family adds to a checkpoint's payload (given back to `start` on resume)."""
        return {}
