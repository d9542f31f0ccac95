"""Robot specifications (joint order, default pose, gains, geoms) and their MJCF files."""

from legged.robots.go1 import GO1
from legged.robots.op3 import OP3
from legged.robots.spec import RobotSpec

ROBOTS = {"go1": GO1, "op3": OP3}

__all__ = ["GO1", "OP3", "ROBOTS", "RobotSpec"]
