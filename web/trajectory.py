"""Recorded rollouts as numpy arrays, saved to and loaded from self-contained .npz files.

A trajectory holds the compiled model (as MJB bytes), so playing it back needs neither the environment
nor JAX: body poses and contacts are recomputed from the recorded joint positions with native MuJoCo.
Arrays are indexed [frame, environment, ...]; frame 0 is the state after reset.
"""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import mujoco
import numpy as np

from legged.files import write_atomic

FORMAT = "legged-trajectory-1"
"""Format tag stored in every file."""

OPTIONAL = ("paths", "path_len", "waypoint", "goal", "floor_scan", "ceiling_scan", "camera", "estimates", "sightings",
            "tracked", "replans", "replan_len", "replan_frame")
"""Arrays a trajectory may lack."""


def model_to_bytes(model: mujoco.MjModel) -> bytes:
    """The model as MJB bytes."""
    buffer = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    return buffer.tobytes()


def model_from_bytes(blob: bytes) -> mujoco.MjModel:
    """A model from MJB bytes."""
    return mujoco.MjModel.from_binary_path("model.mjb", {"model.mjb": blob})


@dataclasses.dataclass
class Trajectory:
    """One recorded rollout of `num_envs` environments."""

    model: mujoco.MjModel
    """The compiled scene the rollout ran in."""
    dt: float
    """Time between frames (the control period), seconds."""
    qpos: np.ndarray
    """Joint positions (frames, envs, nq)."""
    reward: np.ndarray
    """Reward of the step that led to each frame (frames, envs); 0 at frame 0."""
    done: np.ndarray
    """Whether the episode had ended at each frame (frames, envs); an ended environment stays frozen."""
    metrics: dict[str, np.ndarray]
    """Per-frame environment metrics by name, each (frames, envs): 'reward/<term>' and task metrics."""
    offsets: np.ndarray
    """Where each environment is drawn relative to its simulated position (envs, 3), metres."""
    info: dict = dataclasses.field(default_factory=dict)
    """Free-form description: task, seed, policy, checkpoint, run directory (JSON-serialisable)."""
    paths: np.ndarray | None = None
    """Planned body-pose waypoints (envs, max_waypoints, 6: x, y, z, roll, pitch, yaw), or None."""
    path_len: np.ndarray | None = None
    """Number of valid waypoints of each environment's path (envs,)."""
    waypoint: np.ndarray | None = None
    """Index of the current target waypoint (frames, envs)."""
    goal: np.ndarray | None = None
    """Goal position of each environment (envs, 3), or None."""
    floor_scan: np.ndarray | None = None
    """World positions of the floor height-scan points (frames, envs, points, 3), or None."""
    ceiling_scan: np.ndarray | None = None
    """World positions of the ceiling height-scan points (frames, envs, points, 3), or None."""
    camera: np.ndarray | None = None
    """Camera observations (frames, envs, H, W, 3) uint8, or None."""
    estimates: np.ndarray | None = None
    """World positions of what a vision player estimated from its camera (frames, envs, 4, 3): ball, own goal,
    opponent goal, first other player (legged.soccer.learner.LearnerView.estimate_points), or None."""
    sightings: np.ndarray | None = None
    """World positions of what a vision player's camera sighted (frames, envs, 3, 3): ball, own goal, opponent goal
    (legged.soccer.learner.LearnerView.sighting_points), NaN where not in view, or None."""
    tracked: np.ndarray | None = None
    """Where a vision player's tracker put its torso, and a point ahead along its tracked heading (frames, envs, 2,
    3; legged.soccer.learner.LearnerView.tracked_points), NaN before it locked on, or None."""
    replans: np.ndarray | None = None
    """Paths a navigation replanned for environment 0 (replans, max_waypoints, 6), or None."""
    replan_len: np.ndarray | None = None
    """Number of valid waypoints of each replanned path (replans,)."""
    replan_frame: np.ndarray | None = None
    """Frame from which each replanned path is followed (replans,)."""

    def __post_init__(self):
        frames, envs = self.qpos.shape[:2]
        if self.qpos.shape[2] != self.model.nq:
            raise ValueError(f"qpos has {self.qpos.shape[2]} values per frame; the model has nq={self.model.nq}")
        checks = {"reward": (self.reward, (frames, envs)), "done": (self.done, (frames, envs)),
                  "offsets": (self.offsets, (envs,)), "waypoint": (self.waypoint, (frames, envs)),
                  "floor_scan": (self.floor_scan, (frames, envs)), "ceiling_scan": (self.ceiling_scan, (frames, envs)),
                  "camera": (self.camera, (frames, envs)), "estimates": (self.estimates, (frames, envs, 4, 3)),
                  "sightings": (self.sightings, (frames, envs, 3, 3)), "tracked": (self.tracked, (frames, envs, 2, 3)),
                  "paths": (self.paths, (envs,)),
                  "path_len": (self.path_len, (envs,)), "goal": (self.goal, (envs,))}
        checks.update({f"metric {k}": (v, (frames, envs)) for k, v in self.metrics.items()})
        for name, (array, lead) in checks.items():
            if array is not None and tuple(array.shape[:len(lead)]) != lead:
                raise ValueError(f"trajectory {name} has shape {array.shape}; expected it to start with {lead}")
        if (self.paths is None) != (self.path_len is None):
            raise ValueError("a trajectory needs both paths and path_len, or neither")
        replans = [getattr(self, k) is None for k in ("replans", "replan_len", "replan_frame")]
        if len(set(replans)) > 1 or (not replans[0] and self.paths is None):
            raise ValueError("a trajectory's replans need replan_len, replan_frame and the first paths")
        if not replans[0] and not (len(self.replans) == len(self.replan_len) == len(self.replan_frame)):
            raise ValueError("replans, replan_len and replan_frame must have one entry per replan")

    @property
    def num_frames(self) -> int:
        """Number of recorded frames (steps + 1)."""
        return self.qpos.shape[0]

    @property
    def num_envs(self) -> int:
        """Number of environments recorded side by side."""
        return self.qpos.shape[1]

    def episode_return(self) -> np.ndarray:
        """Cumulative reward up to each frame (frames, envs)."""
        return np.cumsum(self.reward, axis=0)

    def _arrays(self) -> dict[str, np.ndarray]:
        arrays = {"format": np.array(FORMAT), "model_mjb": np.frombuffer(model_to_bytes(self.model), np.uint8),
                  "dt": np.array(self.dt), "info": np.array(json.dumps(self.info)), "qpos": self.qpos,
                  "reward": self.reward, "done": self.done, "offsets": self.offsets}
        for name in OPTIONAL:
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        arrays.update({f"metric/{k}": v for k, v in self.metrics.items()})
        return arrays

    def to_bytes(self) -> bytes:
        """The compressed .npz file's content."""
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **self._arrays())
        return buffer.getvalue()

    def save(self, path: str | Path) -> Path:
        """Write a compressed .npz file (created with its parent directories)."""
        path = Path(path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(path, self.to_bytes())  # a killed save never leaves a half-written file under the real name
        except OSError as exc:
            raise OSError(f"cannot write trajectory {path}: {exc.strerror}") from None
        return path


def load_trajectory(path: str | Path) -> Trajectory:
    """Read a trajectory written by `Trajectory.save`; errors name the file and what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"trajectory file not found: {path}")
    try:
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    except Exception as exc:  # zip, npy and pickle errors alike
        raise ValueError(f"{path} is not a readable .npz file: {exc}") from None
    if arrays.get("format") is None or str(arrays["format"]) != FORMAT:
        raise ValueError(f"{path} is not a legged trajectory (format tag {FORMAT!r} missing)")
    missing = [k for k in ("model_mjb", "dt", "info", "qpos", "reward", "done", "offsets") if k not in arrays]
    if missing:
        raise ValueError(f"{path} lacks {', '.join(missing)}")
    try:
        model = model_from_bytes(arrays["model_mjb"].tobytes())
    except Exception as exc:
        raise ValueError(f"{path}: the stored model cannot be loaded: {exc}") from None
    optional = {k: arrays.get(k) for k in OPTIONAL}
    return Trajectory(model=model, dt=float(arrays["dt"]), qpos=arrays["qpos"], reward=arrays["reward"],
                      done=arrays["done"], offsets=arrays["offsets"], info=json.loads(str(arrays["info"])),
                      metrics={k[7:]: v for k, v in arrays.items() if k.startswith("metric/")}, **optional)
