"""Confined worlds: generation (data), tiling into terrains, and realisation as MJCF."""

from legged.worlds.generator import World, WorldConfig, WorldError, generate_world
from legged.worlds.mjcf import SceneOptions, compile_scene, scene_xml, write_world
from legged.worlds.terrain import Terrain

__all__ = ["SceneOptions", "Terrain", "World", "WorldConfig", "WorldError", "compile_scene", "generate_world",
           "scene_xml", "write_world"]
