"""What the dashboard shows, resolved from `legged view` arguments with every check done before long work.

Checks run cheapest first: numbers, the port, the trajectory file, the run directory and its config,
the task name, the checkpoint; only then is the environment built (and compiled, on the first rollout).
The task registry and policies (torch among them) are imported inside the functions that first need them, so
that a wrong argument is answered before they load.
"""

from __future__ import annotations

import dataclasses
import errno
import socket
from pathlib import Path
from typing import Callable

from web.rollout import Recorder, RecorderConfig
from web.trajectory import Trajectory, load_trajectory

DEFAULT_TASK = "confined-waypoints"
"""Task shown when neither a run directory nor a task is named."""


@dataclasses.dataclass(frozen=True)
class ViewRequest:
    """The arguments of `legged view`."""

    run_dir: str | None = None
    """Training run whose policy, curves and checkpoints are shown."""
    task: str | None = None
    """Task to show (default: the run's task, else confined-waypoints)."""
    checkpoint: str | None = None
    """Checkpoint file (default: the run's newest, if it has one)."""
    trajectory: str | None = None
    """Recorded trajectory (.npz) to play instead of rolling out."""
    num_envs: int = 1
    """Environments side by side."""
    physics: str = "mjx"
    """Physics engine of the rollouts: mjx or native."""
    seed: int = 0
    """Seed of the first rollout."""
    steps: int = 500
    """Control steps per rollout."""
    host: str = "127.0.0.1"
    """Address the server binds to."""
    port: int | None = 8080
    """Port the server binds to (0: any free port; None: no server, e.g. when only recording)."""
    opponent: str | None = None
    """Soccer: what drives the other robots: placo, scripted (the default) or a soccer run directory."""
    drill: str | None = None
    """A soccer drill (walk, empty-goal, getup; legged.soccer.drills) played by the run's policy, or without a
    run by the placo player."""
    robot: str = "project"
    """The robot model the rollouts run (legged.robots.models): project, a reference name or an MJCF path."""


def check_port(host: str, port: int) -> None:
    """OSError naming the address if nothing can listen on host:port now (the same socket options as viser)."""
    if not 0 <= port <= 65535:
        raise ValueError(f"--port must be between 0 and 65535, got {port}")
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host, port))
        except OSError as exc:
            reason = "is in use" if exc.errno == errno.EADDRINUSE else f"cannot be bound ({exc.strerror})"
            raise OSError(f"port {port} on {host} {reason}; choose another with --port") from None


class RolloutSource:
    """An environment, its recorder and the current policy (or the default controller): what is re-recorded."""

    def __init__(self, env, task: str, recorder: RecorderConfig = RecorderConfig(), policy=None,
                 run_dir: Path | None = None, opponent: tuple[str, object] | None = None,
                 builtin: str = "default controller"):
        """opponent: (name, legged.soccer.opponents.Opponent) driving the other robots of a soccer game;
        builtin: what acts without a policy (the environment's default controller, or e.g. the placo player)."""
        self.env, self.task, self.run_dir, self.builtin = env, task, run_dir, builtin
        self.opponent_name = None if opponent is None else opponent[0]
        self.recorder = Recorder(env, task, recorder, () if opponent is None else (opponent[1],))
        self.policy = policy

    @property
    def policy_name(self) -> str:
        """The checkpoint's file name, or what acts without one (`builtin`)."""
        return self.builtin if self.policy is None else self.policy.checkpoint.name

    def checkpoints(self) -> list[Path]:
        """Checkpoints of the run directory, oldest first (none without a run)."""
        if self.run_dir is None:
            return []
        from policies.run_dir import RunDir

        return RunDir(self.run_dir).checkpoints()

    def load_checkpoint(self, path: Path) -> None:
        """Swap the policy for a checkpoint of the run (errors leave the current one in place)."""
        from policies.policy_io import load_policy
        from policies.run_dir import check_policy

        if self.run_dir is None:
            raise ValueError("checkpoints can be loaded only when a run directory is shown")
        policy, _ = load_policy(self.run_dir, path)
        check_policy(policy, self.env, path)
        self.policy = policy

    def record(self, steps: int, seed: int, progress: Callable[[int, int], None] | None = None) -> Trajectory:
        """Roll out the current policy (or the default controller)."""
        act = None if self.policy is None else self.policy.act
        if self.policy is not None:
            self.policy.reset()  # a policy with memory starts the recorded episodes afresh
        info = {"policy": self.policy_name}
        if self.policy is not None:
            info.update(checkpoint=str(self.policy.checkpoint), trained_steps=int(self.policy.step))
        if self.run_dir is not None:
            info["run_dir"] = str(self.run_dir)
        if self.opponent_name is not None:
            info["opponent"] = self.opponent_name
        if getattr(self.env, "state_pilot", None) is not None:  # a vision student steered from its estimate
            info["pilot"] = self.env.pilot_name
        return self.recorder.record(steps, seed, act, info, progress)


@dataclasses.dataclass
class Resolved:
    """What `resolve` found: a trajectory to play or a source to roll out, and the run directory if any."""

    source: RolloutSource | None
    """Rolls out the environment (None when playing a recorded trajectory)."""
    trajectory: Trajectory | None
    """The recorded trajectory (None when rolling out)."""
    run_dir: Path | None
    """Run directory for training curves and the checkpoint picker."""


def _run_dir_of(request: ViewRequest) -> Path | None:
    if request.run_dir is None and request.checkpoint is not None:
        parent = Path(request.checkpoint).resolve().parent.parent  # RUN/checkpoints/step_*.pt
        if not (parent / "config.yaml").is_file():
            raise ValueError(f"--checkpoint {request.checkpoint}: name its run directory too (RUN_DIR holds "
                             "config.yaml and checkpoints/)")
        return parent
    if request.run_dir is None:
        return None
    path = Path(request.run_dir)
    if not path.exists():
        raise FileNotFoundError(f"run directory not found: {path}")
    if not path.is_dir():
        raise NotADirectoryError(f"not a run directory: {path}")
    return path


def resolve(request: ViewRequest, log: Callable[[str], None] = print) -> Resolved:
    """Check the request and build what it asks for (the environment last)."""
    if request.physics not in ("mjx", "native"):
        raise ValueError(f"unknown physics {request.physics!r}; one of mjx, native")
    if not 1 <= request.num_envs <= 16:
        raise ValueError(f"--num-envs must be between 1 and 16, got {request.num_envs}")
    if request.steps < 1:
        raise ValueError(f"--steps must be >= 1, got {request.steps}")
    if request.port is not None:
        check_port(request.host, request.port)
    if request.opponent is not None and request.trajectory is not None:
        raise ValueError("--opponent plays a new rollout; it cannot be combined with --trajectory")
    if request.robot not in ("", "project") and request.trajectory is not None:
        raise ValueError("--robot chooses the robot model of a new rollout; it cannot be combined with --trajectory")
    if request.drill is not None:
        return _resolve_drill(request, log)
    run_dir = _run_dir_of(request)
    config = None
    if run_dir is not None:
        from policies.run_dir import RunDir

        config = RunDir(run_dir).load_config()
    if request.trajectory is not None:
        return Resolved(source=None, trajectory=load_trajectory(request.trajectory), run_dir=run_dir)
    from legged.tasks import default_config

    task = request.task or (config.task if config is not None else DEFAULT_TASK)
    if config is not None and task != config.task:
        raise ValueError(f"--task {task} differs from the task of run {run_dir} ({config.task})")
    default_config(task)  # unknown task -> error naming the known ones
    if request.opponent is not None:
        from legged.tasks import task_entry

        if task_entry(task).kind != "soccer":
            raise ValueError(f"--opponent applies to soccer tasks; {task} has no opponents")
        if config is not None and config.soccer.drill:
            raise ValueError(f"run {run_dir} trained on the {config.soccer.drill} drill, where nobody else plays: "
                             f"drop --opponent")
    if request.robot not in ("", "project"):
        from policies.config import TrainConfig
        from policies.evaluate import on_robot

        config = on_robot(config if config is not None else TrainConfig(task=task).resolved(), request.robot,
                          request.physics)
    policy = None
    if run_dir is not None and (request.checkpoint is not None or _has_checkpoints(run_dir)):
        policy = _load_policy(run_dir, request.checkpoint, log)
    log(f"[view] building the {task} environment ...")
    env = _build_env(task, config)
    if policy is not None:
        from policies.run_dir import check_policy

        check_policy(policy, env)
    opponent = None
    if request.opponent is not None:
        from policies.environments import soccer_opponent

        opponent = (request.opponent, soccer_opponent(request.opponent, env))
    source = RolloutSource(env, task, RecorderConfig(num_envs=request.num_envs, physics=request.physics), policy,
                           run_dir, opponent)
    return Resolved(source=source, trajectory=None, run_dir=run_dir)


def _load_policy(run_dir: Path, checkpoint: str | None, log: Callable[[str], None]):
    """The run's policy (its newest checkpoint, or `checkpoint`), announced."""
    from policies.policy_io import load_policy

    policy, _ = load_policy(run_dir, checkpoint)
    log(f"[view] policy {policy.checkpoint} ({policy.backend}, {policy.step} env steps)")
    return policy


def _resolve_drill(request: ViewRequest, log: Callable[[str], None]) -> Resolved:
    """`legged view [RUN] --drill NAME`: the drill as `legged drill NAME --player RUN|placo` plays it."""
    from legged.soccer.drills import DRILLS, DrillConfig
    from legged.robots import OP3
    from legged.robots.models import checked_model
    from legged.robots.op3 import OP3_CTRL_DT
    from policies.soccer.drill import check_player, drill_env
    from policies.run_dir import RunDir

    if request.drill not in DRILLS:
        raise ValueError(f"unknown drill {request.drill!r}; drills: {', '.join(DRILLS)}")
    if request.trajectory is not None or request.opponent is not None or request.task is not None:
        raise ValueError("--drill plays a new rollout of one player: it cannot be combined with --trajectory, "
                         "--opponent or --task")
    run_dir = _run_dir_of(request)
    drill, player = DrillConfig(name=request.drill), "placo" if run_dir is None else str(run_dir)
    check_player(player, drill)  # the run can do this drill (and is a run), before anything is built
    checked_model(OP3, request.robot, OP3_CTRL_DT, request.physics)  # a bad model: one line, before a policy loads
    policy = None if run_dir is None else _load_policy(run_dir, request.checkpoint, log)
    log(f"[view] building the {request.drill} drill ...")
    env = drill_env(player, drill, randomize=False, robot=request.robot)
    task = "soccer-1v1" if run_dir is None else RunDir(run_dir).load_config().task
    if policy is not None:
        from policies.run_dir import check_policy

        check_policy(policy, env)
    source = RolloutSource(env, f"{task} ({request.drill} drill)",
                           RecorderConfig(num_envs=request.num_envs, physics=request.physics), policy, run_dir,
                           builtin="placo player")
    return Resolved(source=source, trajectory=None, run_dir=run_dir)


def _build_env(task: str, config):
    """The environment a run trained on (soccer: the learner's view, scripted opponents; confined: planned
    worlds), else the task's default."""
    from policies.config import TrainConfig
    from policies.environments import build_env

    return build_env(config if config is not None else TrainConfig(task=task).resolved(), progress=False)


def _has_checkpoints(run_dir: Path) -> bool:
    from policies.run_dir import RunDir

    return bool(RunDir(run_dir).checkpoints())
