"""Robot soccer with OP3 teams: the game, and beside it placo's walk and kick and the players' vision.

The game is in this package: its config, the scene composed in code, its layout and the pitch as data, the laws
of the game, observations, rewards, domain randomisation, the multi-agent environment, the players (opponents as
data, the walker, the get-up script) and the learner's view, the drills, the PettingZoo adapter and the benchmark.
legged.soccer.placo holds placo's walk and kick (tables, builders, the scripted player); legged.soccer.vision the
cameras, the sightings, the tracker and a vision player's estimate. This module exports the scene's names.
"""

from legged.soccer.config import SoccerSceneConfig
from legged.soccer.layout import TEAMS, SoccerLayout
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
