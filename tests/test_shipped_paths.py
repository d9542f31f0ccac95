"""Every file or run a shipped policy's config names (its walker, pilot, teacher, warm start, ...) is in the
repository: a policy that plays through another keeps working when that one is retrained or moved."""

from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def _paths(node, where: str):
    """(field, value) of every string in a YAML tree that names a path in the repository (assets/...)."""
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, f"{where}.{key}" if where else str(key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _paths(value, f"{where}[{i}]")
    elif isinstance(node, str) and node.startswith("assets/"):
        yield where, node


def test_every_path_a_shipped_config_names_exists():
    files = sorted((ROOT / "assets" / "policies").glob("*/*.yaml"))
    assert len(files) >= 9                                                # a config per shipped policy at least
    named, missing = 0, []
    for file in files:
        for field, value in _paths(yaml.safe_load(file.read_text()), ""):
            named += 1
            if not (ROOT / value).exists():
                missing.append(f"{file.relative_to(ROOT)}: {field} = {value}")
    assert named >= 20 and not missing, "\n".join(missing)
