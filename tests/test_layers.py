"""The import layering, enforced: core <- planners, policies <- web <- command line; inside `legged` and `policies`
an order of groups (LEGGED_ORDER, POLICIES_ORDER); and no import cycle anywhere.

Every import statement of every module (top level or inside a function) is read from the source with
`ast`, so a lazy import counts as much as one at the top of a file. Imports inside functions are counted
too: they are kept for the command line's start-up, optional or heavy modules, and their number may not grow.
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


def _names(node: ast.Import | ast.ImportFrom) -> set[str]:
    """What an import statement names: its modules, and for `from m import x` both m and m.x (x may be a module)."""
    if isinstance(node, ast.Import):
        return {a.name for a in node.names}
    if node.module and node.level == 0:
        return {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    return set()


def _statements(path: Path) -> list[tuple[ast.Import | ast.ImportFrom, bool]]:
    """Every import statement of the file and whether it lies inside a function."""
    found = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                found.append((child, in_function))
            visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    visit(ast.parse(path.read_text()), False)
    return found


def _imports(path: Path) -> set[str]:
    return set().union(*(_names(node) for node, _ in _statements(path)))


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


MODULES = dict(_modules())
"""Every project module (dotted name -> file)."""


def _module_of(name: str) -> str | None:
    """The project module an imported name lives in (`policies.config.TrainConfig` -> `policies.config`)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (anywhere in it)."""
    graph = {}
    for name, path in MODULES.items():
        graph[name] = {m for m in map(_module_of, _imports(path)) if m is not None and m != name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (each holds at least one import cycle)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def connect(v: str) -> None:  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            connect(v)
    return found


def test_no_import_cycles():
    cycles = _cycles(_graph())
    assert not cycles, "import cycles (each line: modules that import each other, directly or through the others):\n" \
        + "\n".join(", ".join(c) for c in cycles)


def test_the_cycle_finder_finds_cycles():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert _cycles(graph) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


LEGGED_ORDER = [
    ("base", ("legged", "legged.files", "legged.mjx_collisions", "legged.robots", "legged.worlds", "legged.sensors",
              "legged.envs.math")),
    ("environments", ("legged.envs", "legged.soccer")),
    ("skills", ("legged.skills",)),
    ("tasks", ("legged.tasks", "legged.bench", "legged.physics_cost", "legged.setting_cost", "legged.soccer.bench",
               "legged.soccer.parallel_env", "legged.peers")),
    ("cli", ("legged.cli",)),
]
"""The groups of `legged`, lowest first: a module may import its own group and those before it. Each entry is a
module and everything under it; the most specific entry places a module, and `legged` alone is the package's
own __init__. The skills (legged.skills: op3-walk, op3-getup, drills of the soccer game made tasks) sit between
the soccer game they build on and the registry that names them. legged.files (atomic file writes, for every
layer) and legged.mjx_collisions (MJX's sphere-height-field contacts, installed by the robots' MJX models) are in the
base. Placed apart from their folders: legged.envs.math (rotation helpers that import nothing
of the project, read by the sensors too) in the base; legged.soccer.bench
(the soccer throughput benchmark, built on legged.bench) and legged.soccer.parallel_env (the PettingZoo adapter,
which builds its game through the registry) with the tasks. Beside the registry sit the benchmarks built on it,
legged/bench.py, legged/physics_cost.py and legged/setting_cost.py, and legged/peers (MuJoCo Playground's timing script, run with the peer's
own Python: it imports
nothing of legged)."""

POLICIES_ORDER = [
    ("run files", ("policies", "policies.config_io", "policies.config", "policies.soccer", "policies.soccer.config",
                   "policies.recipes", "policies.run_dir", "policies.distributed")),
    ("checkpoints", ("policies.checkpoints", "policies.slim")),
    ("models", ("policies.algorithms", "policies.latent_models", "policies.memory_models", "policies.hib",
                "policies.teacher_kl", "policies.students", "policies.warm_start", "policies.probe",
                "policies.soccer.selfplay", "policies.brax_networks")),
    ("policy loading", ("policies.policy_io", "policies.provenance")),
    ("environments", ("policies.environments", "policies.rsl_vecenv", "policies.training_hooks",
                      "policies.soccer.steered", "policies.soccer.hooks")),
    ("backends", ("policies.rsl_backend", "policies.brax_backend")),
    ("orchestration", ("policies.training", "policies.distill", "policies.evaluate", "policies.eval_report",
                       "policies.card_tables", "policies.cards", "policies.card_summary", "policies.figure_lint",
                       "policies.soccer.drill", "policies.navigate", "policies.nav_bench", "policies.export",
                       "policies.convert", "policies.average", "policies.tables", "policies.plots",
                       "policies.bench_encoder", "policies.bench_train", "policies.bench_update",
                       "policies.learning_curve")),
]
"""The groups of `policies`, lowest first, as LEGGED_ORDER: run files (config I/O, configs, the soccer section of
the config, the tasks' recipes, run directories, the process launch) < checkpoints (the data-only formats, their weights-only form) <
models (networks, the HIB and teacher-KL losses, the students' distillation losses and starts, warm starts, the
linear probe, self-play snapshots) < policy loading (and the provenance of results) < the environments runs train
and play in (a pilot's steered game among them) and the hooks through which a task family adds to the training loop < trainer backends < orchestration
(the commands: train, distill, evaluate, drill, navigate, export, convert, average, tables and plots). The
soccer-only modules (policies.soccer) sit in the groups of their jobs: the subpackage and its config with the run
files (policies.config imports the config), selfplay with the models, steered and the training hooks with the
environments, drill with the orchestration."""


def _group(module: str, order: list) -> int | None:
    """The index in `order` of the group the most specific entry places `module` in (None: not placed)."""
    best, length = None, -1
    for rank, (_, entries) in enumerate(order):
        for entry in entries:
            root = "." not in entry  # the package itself: its __init__ only
            if (module == entry or (not root and module.startswith(entry + "."))) and len(entry) > length:
                best, length = rank, len(entry)
    return best


def _order_violations(package: str, order: list) -> list[str]:
    wrong, graph = [], _graph()
    for module in sorted(m for m in MODULES if m.split(".")[0] == package):
        mine = _group(module, order)
        if mine is None:
            wrong.append(f"{module} is in no group: place it")
            continue
        for imported in sorted(graph[module]):
            theirs = _group(imported, order) if imported.split(".")[0] == package else None
            if theirs is not None and theirs > mine:
                wrong.append(f"{module} ({order[mine][0]}) imports {imported} ({order[theirs][0]})")
    return wrong


def test_legged_groups_import_downwards():
    wrong = _order_violations("legged", LEGGED_ORDER)
    assert not wrong, "imports against the order of legged's groups:\n" + "\n".join(wrong)


def test_policies_layers_import_downwards():
    wrong = _order_violations("policies", POLICIES_ORDER)
    assert not wrong, "imports against the order of policies' layers:\n" + "\n".join(wrong)


def test_the_groups_place_modules_by_their_most_specific_entry():
    assert [_group(m, LEGGED_ORDER) for m in ("legged", "legged.envs.base", "legged.envs.math", "legged.soccer.env",
                                              "legged.soccer.placo.player", "legged.soccer.vision.tracker",
                                              "legged.skills", "legged.skills.env", "legged.soccer.bench",
                                              "legged.cli.main", "legged.client")] == \
        [0, 1, 0, 1, 1, 1, 2, 2, 3, 4, None]
    assert _group("policies.checkpoints", POLICIES_ORDER) == 1 and _group("policies.new", POLICIES_ORDER) is None
    assert [_group(f"policies.soccer.{m}", POLICIES_ORDER) for m in ("config", "selfplay", "steered", "drill")] == \
        [0, 2, 4, 6]


LAZY_IMPORTS = 99
"""Import statements inside functions that import a project module, today: the command line's (legged.cli, 67:
each command imports what it runs) and the dashboard's checks' (web.source), which answer before torch and the
task registry load; the registry's soccer environments (legged.tasks), loaded when a soccer task is built; Brax's
trainer (policies.training), loaded by Brax runs only; the placo solver and JAX in the gait table's open-loop
checks; policies.plots'; and legged.mjx_collisions in legged.robots.models.mjx_model_of, which imports MJX there
(its collision code with it) for the models that run in MJX only.
Every other import sits at the top of its module. The number may fall, not grow."""


def _lazy_imports() -> list[str]:
    found = []
    for name, path in MODULES.items():
        for node, in_function in _statements(path):
            targets = sorted({m for m in map(_module_of, _names(node)) if m is not None})
            if in_function and targets:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} {', '.join(targets)}")
    return sorted(found)


def test_imports_inside_functions_do_not_grow():
    lazy = _lazy_imports()
    print(f"{len(lazy)} imports of project modules inside functions (ceiling {LAZY_IMPORTS})")
    assert len(lazy) <= LAZY_IMPORTS, f"{len(lazy)} imports of project modules inside functions, more than " \
        f"{LAZY_IMPORTS}: import at the top of the module (move code to the layer it belongs in if that makes a " \
        "cycle), or justify it beside the import and raise LAZY_IMPORTS:\n" + "\n".join(lazy)


def test_every_module_imports():
    """Every module of the four packages imports (command-line entry scripts `__main__` aside): the fast tier
    (`pytest -m "not slow"`) touches each one at least this far."""
    import importlib

    failed = []
    for name, _ in _modules():
        if name.endswith("__main__"):
            continue
        try:
            importlib.import_module(name)
        except Exception as exc:  # noqa: BLE001 (the report names every module that fails, and why)
            failed.append(f"{name}: {exc!r}")
    assert not failed, "\n".join(failed)
