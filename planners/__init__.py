"""Classical planning: OMPL body-pose paths through confined worlds, handed to the environments as waypoints."""

from planners.batch import cache_key, default_cache_dir, feasible_worlds, plan_world, plan_worlds
from planners.body_check import BodyCheckConfig, BodyChecker
from planners.body_planner import PLANNERS, Plan, PlannerConfig, PlanningError, plan_path, replan
from legged.worlds.maps import HeightMaps
from planners.planned_env import follower_planner, make_planned_env
from planners.scene_maps import maps_from_scene, navigation_maps, reference_between

__all__ = [
    "PLANNERS", "BodyCheckConfig", "BodyChecker", "HeightMaps", "Plan", "PlannerConfig", "PlanningError",
    "cache_key", "default_cache_dir", "feasible_worlds", "follower_planner", "make_planned_env", "maps_from_scene",
    "navigation_maps", "plan_path", "plan_world", "plan_worlds", "reference_between", "replan",
]
