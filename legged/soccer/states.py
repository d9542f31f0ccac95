"""Soccer game states for inspection (camera images, the dashboard) before the environments own resets."""

from __future__ import annotations

import mujoco
import numpy as np

from legged.soccer.config import SoccerSceneConfig
from legged.soccer.layout import SoccerLayout
from legged.soccer.pitch import kickoff_poses

SCENES = {"soccer-1v1": 1, "soccer-2v2": 2, "soccer-1v1-vision": 1}
"""Soccer task names and their players per team."""


def scene_config(task: str) -> SoccerSceneConfig:
    """The scene of a soccer task; ValueError listing the soccer tasks for any other name."""
    if task not in SCENES:
        raise ValueError(f"unknown soccer task {task!r}; soccer tasks: {', '.join(sorted(SCENES))}")
    return SoccerSceneConfig(players_per_team=SCENES[task])


def match_state(model: mujoco.MjModel, config: SoccerSceneConfig, seed: int, spread: float = 0.5) -> mujoco.MjData:
    """A forward-computed game state: seed 0 is the kick-off; other seeds move every robot up to `spread`
    metres from its kick-off spot, turn it within +-90 degrees of facing the opponent goal, and put the
    ball anywhere on the pitch 0.3 m inside the lines. Robots stand in their default pose."""
    layout = SoccerLayout.from_model(model)
    poses = np.asarray(kickoff_poses(config), dtype=np.float64)
    rng = np.random.default_rng(seed)
    if seed:
        poses = poses + np.column_stack([rng.uniform(-spread, spread, (len(poses), 2)),
                                         rng.uniform(-np.pi / 2, np.pi / 2, len(poses))])
    qpos = layout.kickoff_qpos(model, poses)
    if seed:
        half = np.array([config.field_length, config.field_width]) / 2 - 0.3
        qpos[layout.ball_qpos_adr: layout.ball_qpos_adr + 2] = rng.uniform(-half, half)
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.ctrl[:] = layout.default_ctrl(model)
    mujoco.mj_forward(model, data)
    return data
