"""MJX legged-robot environments (Brax API). Use `legged.envs.make(task)`."""

from legged.envs.registry import TASKS, UnknownTaskError, default_config, make

__all__ = ["TASKS", "UnknownTaskError", "default_config", "make"]
