"""The package's import graph (read with ast, nothing imported or compiled): no module imports
itself back through others, each package of tidem/ imports only from itself and from packages of
a lower layer (LAYERS, drawn in tidem/__init__.py and docs/architecture.md), scene validation
(tidem/scene/) stands on nothing above it, and the kernels (kernels/, installed as tidem.kernels) import nothing of tidem outside kernels/, and
every name a script of benchmarks/ imports from tidem exists (no test runs those scripts).

Imports inside functions count like those at the top of a module: a lazy import only moves
the moment a cycle bites, it does not take the dependency away."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"tidem": ROOT / "tidem", "tidem.kernels": ROOT / "kernels"}
LAYERS = {
    "tidem.version": 0, "tidem.scene": 0, "tidem.io": 0, "tidem.analytic": 0, "tidem.runtime": 0,
    "tidem.walls": 1,
    "tidem.gas": 2,
    "tidem.particles": 3, "tidem.heat": 3,
    "tidem.results": 4,
    "tidem.sim": 5, "tidem.render": 5,
    "tidem.runner": 6,
    "tidem.studies": 7,
    "tidem.api": 8, "tidem.cli": 8,
    "tidem": 9, "tidem.__main__": 9,
}
"""Layer of each package (or top-level module) of tidem/: a module may import its own package and
any package of a strictly lower layer, never one of its own layer or above. tidem.kernels, which
imports nothing of tidem, may be imported from any layer."""


def modules() -> dict[str, Path]:
    """{dotted module name: file} for every module of the package, kernels included."""
    out = {}
    for package, folder in PACKAGES.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join([package, *parts])] = path
    return out


def imported(name: str, path: Path, known: set[str]) -> set[str]:
    """The package's modules that module `name` imports, anywhere in its file."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            # `from tidem.kernels import contact_laws` imports a module, `from tidem.sim.model import Model` a name
            targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base for alias in node.names]
        else:
            continue
        found |= {t for t in targets if t in known and t != name}
    return found


def import_graph() -> dict[str, set[str]]:
    files = modules()
    return {name: imported(name, path, set(files)) for name, path in files.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules (first = last), or None."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def unit(module: str) -> str:
    """The entry of LAYERS a module belongs to: its package (tidem.gas.phase -> tidem.gas), or itself."""
    parts = module.split(".")
    return next((u for u in (".".join(parts[:n]) for n in range(len(parts), 0, -1)) if u in LAYERS), module)


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """`module -> imported` for each import into the module's own layer or above, other package."""
    bad = []
    for module, targets in graph.items():
        if module.startswith("tidem.kernels"):
            continue
        for target in targets:
            if target.startswith("tidem.kernels") or unit(target) == unit(module):
                continue
            if LAYERS[unit(target)] >= LAYERS[unit(module)]:
                bad.append(f"{module} (layer {LAYERS[unit(module)]}) -> {target} (layer {LAYERS[unit(target)]})")
    return sorted(bad)


def test_every_module_has_a_layer():
    unplaced = sorted(m for m in import_graph() if not m.startswith("tidem.kernels") and unit(m) not in LAYERS)
    assert not unplaced, f"modules of no layer (add their package to LAYERS): {unplaced}"


def test_packages_import_only_lower_layers():
    bad = layer_violations(import_graph())
    assert not bad, "imports into the same layer or above:\n" + "\n".join(bad)


def test_the_layer_check_catches_an_upward_import():
    graph = {"tidem.gas.phase": {"tidem.sim.model", "tidem.walls.mesh_bins", "tidem.gas.fields"},
             "tidem.heat.limits": {"tidem.particles.timestep", "tidem.kernels.heat"}}
    assert layer_violations(graph) == ["tidem.gas.phase (layer 2) -> tidem.sim.model (layer 5)",
                                       "tidem.heat.limits (layer 3) -> tidem.particles.timestep (layer 3)"]


def test_scene_validation_imports_nothing_above_it():
    graph = import_graph()
    upward = {f"{m} -> {t}" for m, ts in graph.items() if m.startswith("tidem.scene.")
              for t in ts if not t.startswith("tidem.scene.")}
    assert not upward, f"tidem/scene/ imports from outside tidem/scene/: {sorted(upward)}"


def test_kernels_import_only_kernels():
    graph = import_graph()
    upward = {f"{m} -> {t}" for m, ts in graph.items() if m.startswith("tidem.kernels")
              for t in ts if not t.startswith("tidem.kernels")}
    assert not upward, f"kernels/ imports from tidem outside kernels/: {sorted(upward)}"


def test_the_graph_sees_lazy_and_relative_imports():
    graph = import_graph()
    assert "tidem.scene.observable_names" in graph["tidem.scene.schema"]  # inside a validator
    assert "tidem.kernels.geometry" in graph["tidem.kernels.broadphase"]  # `from .geometry import`
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def top_level_names(path: Path) -> set[str]:
    """Names a module defines or imports at its top level (functions, classes, assignments, imports)."""
    names = set()
    for node in ast.parse(path.read_text(), str(path)).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(alias.asname or alias.name).split(".")[0] for alias in node.names}
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
    return names


def missing_benchmark_imports() -> list[str]:
    """`script: from module import name` for each name a benchmark script imports from tidem that the
    module neither defines nor has as a submodule."""
    files = modules()
    missing = []
    for script in sorted((ROOT / "benchmarks").rglob("*.py")):
        for node in ast.walk(ast.parse(script.read_text(), str(script))):
            if not isinstance(node, ast.ImportFrom) or not (node.module or "").startswith("tidem"):
                continue
            defined = top_level_names(files[node.module]) if node.module in files else set()
            missing += [f"{script.relative_to(ROOT)}: from {node.module} import {alias.name}" for alias in node.names
                        if alias.name not in defined and f"{node.module}.{alias.name}" not in files]
    return missing


def test_benchmark_scripts_import_what_exists():
    """kernel_repeat.py and resume_speed.py imported `tidem.cli.commands._checkpoint` after it had moved
    (tidem.runner.launch.load_checkpoint): found only by running them."""
    assert missing_benchmark_imports() == []
