"""The import layering, enforced: core <- planners, policies <- web <- command line.

Every import statement of every module (top level or inside a function) is read from the source with
`ast`, so a lazy import counts as much as one at the top of a file.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

APP = ("legged.cli",)
"""The command line (legged.cli and every module under it, the demo's included): the top layer, free to import
everything; the core package `legged` must not import it."""
LAYERS = {
    "core": ("legged",),
    "tools": ("planners", "policies"),
    "web": ("web",),
}
"""Layer -> packages; a module may import its own layer and the layers listed before it."""
ORDER = ["core", "tools", "web"]


def _modules():
    for package in ("legged", "planners", "policies", "web"):
        for path in sorted((ROOT / package).rglob("*.py")):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
            yield name, path


def _imports(path: Path) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
    return found


def _layer(module: str) -> str | None:
    if any(module == a or module.startswith(a + ".") for a in APP):
        return "app"
    top = module.split(".")[0]
    for layer, packages in LAYERS.items():
        if top in packages:
            return layer
    return None  # a third-party module


def test_imports_flow_one_way():
    wrong = []
    for name, path in _modules():
        own = _layer(name)
        if own == "app":
            continue
        allowed = set(ORDER[: ORDER.index(own) + 1])
        for imported in _imports(path):
            layer = _layer(imported)
            if layer is not None and layer not in allowed:
                wrong.append(f"{path.relative_to(ROOT)} ({own}) imports {imported} ({layer})")
    assert not wrong, "imports against the layering:\n" + "\n".join(sorted(wrong))


def test_the_checker_sees_lazy_imports(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from web.app import Dashboard\n    import planners.batch\n")
    assert {"web.app", "web.app.Dashboard", "planners.batch"} <= _imports(module)
    assert _layer("legged.cli") == "app" and _layer("legged.envs.base") == "core" and _layer("numpy") is None
    assert _layer("legged.cli.main") == "app" and _layer("legged.cli.demo") == "app"
    assert _layer("legged.client") == "core"  # a name that only starts like the command line's is not it
