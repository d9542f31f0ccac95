"""Robot soccer with OP3 teams: the scene composed in code, its layout, and the pitch as data."""

from legged.soccer.config import TEAMS, SoccerSceneConfig
from legged.soccer.layout import SoccerLayout
from legged.soccer.pitch import goal_boxes, goal_centres, kickoff_poses, pitch_lines
from legged.soccer.scene import (
    KICKOFF_KEY,
    build_soccer_scene,
    soccer_scene_xml,
    soccer_spec,
)

__all__ = [
    "KICKOFF_KEY", "TEAMS", "SoccerLayout", "SoccerSceneConfig", "build_soccer_scene", "goal_boxes",
    "goal_centres", "kickoff_poses", "pitch_lines", "soccer_scene_xml", "soccer_spec",
]
