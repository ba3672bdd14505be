"""Layers import one way: no cycle among symmech's modules.

The graph is read with ``ast`` from every ``symmech/**.py`` file, counting imports anywhere in a file
(module level and inside functions alike: a lazy import still ties the two layers together).
``from a import b`` is an edge to ``a.b`` when that is a module, else to ``a``; a module named by its dotted
name in a string (``importlib.import_module("symmech.x")``, an engine's registered implementation) is an edge
too. Modules found by ``core.discovery`` (``ROLE``) are imported by the registries that discover them, and each
imports its registry to register: those plug-in edges are left out (the registry names no module).

One node is left out: the root package ``symmech``. Python runs it before any submodule whatever the
graph says, and it holds only ``__version__`` (which the lower layers read) and the facade
``symmech.load`` (a function-level import of the pipeline, the top layer); an edge into it orders nothing.
"""
import ast
import graphlib
import importlib.util
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "symmech"


def _modules(package: Path) -> dict[str, Path]:
    """{dotted name: file} of every module under the package folder ``package``."""
    modules = {}
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package.parent).with_suffix("").parts
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def _targets(node, package: str, modules) -> list[str]:
    if isinstance(node, ast.Constant) and node.value in modules:  # imported by importlib under this name
        return [node.value]
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom):
        base = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
        return [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
    return []


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """{module: the modules it imports}, the root package left out."""
    root = min(modules, key=len)
    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        graph[name] = {t for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
                       for t in _targets(node, package, modules) if t in modules and t != root}
    del graph[root]
    return graph


def cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import cycle [a, b, ..., a], or [] when the graph is acyclic."""
    try:
        graphlib.TopologicalSorter(graph).prepare()
    except graphlib.CycleError as exc:
        return exc.args[1]
    return []


def test_the_reader_sees_lazy_and_relative_imports(tmp_path):
    """A cycle closed by a function-level import, and one closed by relative imports, are found."""
    files = {"__init__.py": "", "sub/__init__.py": "", "sub/a.py": "from pkg.sub import b\n",
             "sub/b.py": "def f():\n    from pkg.sub.a import x\n", "sub/c.py": "from . import d\n",
             "sub/d.py": "from .c import y\n", "e.py": "import pkg.sub.a\n",
             "f.py": "import importlib\ndef g():\n    return importlib.import_module('pkg.e')\n"}
    (tmp_path / "pkg" / "sub").mkdir(parents=True)
    for name, text in files.items():
        (tmp_path / "pkg" / name).write_text(text)
    graph = import_graph(_modules(tmp_path / "pkg"))
    assert graph["pkg.sub.b"] == {"pkg.sub.a"} and graph["pkg.sub.d"] == {"pkg.sub.c"}
    assert graph["pkg.e"] == {"pkg.sub.a"} and graph["pkg.f"] == {"pkg.e"}  # importlib by name
    assert set(cycle(graph)) in ({"pkg.sub.a", "pkg.sub.b"}, {"pkg.sub.c", "pkg.sub.d"})
    del graph["pkg.sub.d"]
    assert set(cycle(graph)) == {"pkg.sub.a", "pkg.sub.b"}
    graph["pkg.sub.b"] = set()
    assert cycle(graph) == []


def test_symmech_modules_import_without_cycles():
    graph = import_graph(_modules(PACKAGE))
    assert len(graph) > 50 and sum(map(len, graph.values())) > 100  # the reader found the package
    assert graph["symmech.trolley.plots"] >= {"symmech.trolley.elastic.body"}  # a function-level import is an edge
    assert "symmech.grain.motion_engine.driver" in graph["symmech.grain.motion_engine"]  # a registered implementation
    assert cycle(graph) == []
