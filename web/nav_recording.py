"""A navigation's frames (`policies.navigate.navigate(on_step=...)`) recorded as a dashboard trajectory, its
replans included: `legged navigate --view` and `--record`."""

from __future__ import annotations

import numpy as np

from web.trajectory import Trajectory


class NavigationRecording:
    """Collects a navigation's frames (via `navigate(on_step=...)`) into a dashboard trajectory with its replans."""

    def __init__(self):
        self.frames, self.plans, self.env = [], [], None

    def add(self, env, state, plan) -> None:
        """One frame of environment 0; a plan not seen before is a replan from this frame on."""
        self.env = env
        if not self.plans or self.plans[-1][1] is not plan:
            self.plans.append((len(self.frames), plan))
        self.frames.append({"qpos": np.asarray(state.pipeline_state.qpos[0], np.float32),
                            "reward": float(state.reward[0]), "waypoint": int(state.info["waypoint"][0]),
                            "metrics": {k: float(v[0]) for k, v in state.metrics.items()}})

    def trajectory(self, info: dict) -> Trajectory:
        """The recorded navigation as a web.trajectory.Trajectory (one environment)."""
        width = max(len(p.waypoints) for _, p in self.plans)
        padded = lambda w: np.concatenate([w, np.repeat(w[-1:], width - len(w), 0)]).astype(np.float32)
        first, later = self.plans[0][1], self.plans[1:]
        column = lambda key: np.array([f[key] for f in self.frames])[:, None]
        info = {k: v for k, v in info.items() if isinstance(v, (str, int, float, bool, type(None), list))}
        return Trajectory(
            model=self.env.mj_model, dt=float(self.env.dt), qpos=np.stack([f["qpos"] for f in self.frames])[:, None],
            reward=column("reward").astype(np.float32), done=np.zeros((len(self.frames), 1), bool),
            metrics={k: np.array([f["metrics"][k] for f in self.frames], np.float32)[:, None]
                     for k in self.frames[0]["metrics"]},
            offsets=np.zeros((1, 3)), info=info, paths=padded(first.waypoints)[None],
            path_len=np.array([len(first.waypoints)]), waypoint=column("waypoint").astype(np.int32),
            goal=np.asarray(first.waypoints[-1:, :3], np.float32),
            replans=np.stack([padded(p.waypoints) for _, p in later]) if later else None,
            replan_len=np.array([len(p.waypoints) for _, p in later]) if later else None,
            replan_frame=np.array([f for f, _ in later]) if later else None)
