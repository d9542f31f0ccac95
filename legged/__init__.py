"""legged: reinforcement learning for legged robots in MuJoCo / MJX.

Confined-space navigation for a quadruped (Unitree Go1), robot soccer for humanoids, teacher-student
distillation. The command line: docs/cli.md.
"""

import contextlib as _contextlib
import io as _io

# mujoco.mjx prints "Failed to import warp" to stdout on machines without NVIDIA Warp; keep stdout
# clean for `--json` output by importing it once here, quietly.
with _contextlib.redirect_stdout(_io.StringIO()):
    from mujoco import mjx as _mjx  # noqa: F401

__version__ = "0.1.0"
