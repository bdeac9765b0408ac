"""weldplan's modules import each other without cycles (data flows one way: model -> planning ->
route -> export/view).

The graph is read from the source (ast), so it holds every import: module level, inside
functions (the lazy ones), under ``TYPE_CHECKING``. An import of ``weldplan.a.b`` is an edge to
``weldplan.a.b`` and to the packages above it (``weldplan.a``: Python runs its ``__init__``),
except a module's own packages. ``from weldplan.a import b`` is an edge to ``weldplan.a`` (its
``__init__`` runs first, even for a module inside ``weldplan.a``) and to ``weldplan.a.b`` when
``b`` is a module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "weldplan"


def _modules(root: Path) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package) for every ``.py`` under ``root``."""
    mods = {}
    for p in sorted(root.rglob("*.py")):
        parts = list(p.relative_to(root.parent).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        mods[".".join(parts[:-1] if is_pkg else parts)] = (p, is_pkg)
    return mods


def _targets(node: ast.AST, package: str, mods: dict) -> list[str]:
    """The weldplan modules one import statement names."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = package.split(".")[: len(package.split(".")) - node.level + 1]
            mod = ".".join(base + ([node.module] if node.module else []))
        else:
            mod = node.module or ""
        # ``from pkg import sub`` runs pkg's __init__ first, so it imports pkg as well as sub
        names = [mod] + [f"{mod}.{a.name}" for a in node.names if f"{mod}.{a.name}" in mods]
    else:
        return []
    out = []
    for name in names:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        if name:
            out.append(name)
    return out


def import_graph(root: Path = PACKAGE) -> nx.DiGraph:
    """Directed graph of the imports between the modules under ``root`` (edge attribute
    ``line``: where the importing module names the target)."""
    mods = _modules(root)
    g = nx.DiGraph()
    g.add_nodes_from(mods)
    for m, (path, is_pkg) in mods.items():
        package = m if is_pkg else m.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            for t in _targets(node, package, mods):
                # the target itself, even the importer's own package when the import names it
                # (``from pkg import sub`` inside pkg), and the packages above it that are not
                # the importer's own
                if t in mods and t != m:
                    g.add_edge(m, t, line=node.lineno)
                t = t.rpartition(".")[0]
                while t:
                    if t in mods and t != m and not m.startswith(t + "."):
                        g.add_edge(m, t, line=node.lineno)
                    t = t.rpartition(".")[0]
    return g


def _describe(g: nx.DiGraph, comp: set[str]) -> str:
    edges = sorted((a, b, g.edges[a, b]["line"]) for a, b in g.subgraph(comp).edges)
    return "\n".join(f"  {a}:{line} -> {b}" for a, b, line in edges)


def test_weldplan_has_no_import_cycle():
    g = import_graph()
    cycles = [c for c in nx.strongly_connected_components(g) if len(c) > 1]
    report = "\n".join(_describe(g, c) for c in cycles)
    assert not cycles, f"import cycles (module:line -> module):\n{report}"


def test_the_graph_sees_lazy_and_relative_imports(tmp_path):
    pkg = tmp_path / "demo"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from . import b\n")
    (pkg / "a.py").write_text("def f():\n    from demo.sub.b import g\n    return g\n")
    (pkg / "sub" / "b.py").write_text("from ..a import f\n\ndef g():\n    return f\n")
    g = import_graph(pkg)
    assert set(g.edges) == {
        ("demo.a", "demo.sub.b"),
        ("demo.a", "demo.sub"),
        ("demo.sub", "demo.sub.b"),
        ("demo.sub.b", "demo.a"),
    }
    cycles = [c for c in nx.strongly_connected_components(g) if len(c) > 1]
    assert cycles == [{"demo.a", "demo.sub.b", "demo.sub"}]


def test_exporting_a_route_with_poses_does_not_load_the_pose_planner():
    """io/export reads a route's poses through weldplan.tool.route_frames, which runs the tool
    package's ``__init__`` first: that ``__init__`` is lazy (PEP 562), so the pose planner, the
    sweep checker and their FCL models stay unloaded (a fresh interpreter: other tests import
    them)."""
    import subprocess
    import sys

    code = (
        "import sys, weldplan.io.export, weldplan.tool.route_frames; "
        "print(sorted(m for m in sys.modules if m.startswith('weldplan.tool')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        cwd=PACKAGE.parent,
    ).stdout  # fmt: skip
    loaded = set(eval(out))
    assert "weldplan.tool.route_frames" in loaded  # the import ran
    assert not loaded & {"weldplan.tool.poses", "weldplan.tool.sweep", "weldplan.tool.model"}


def test_the_tool_package_still_exports_every_name():
    import importlib

    import weldplan.tool as tool

    for name in tool.__all__:
        obj = getattr(tool, name)
        assert obj is getattr(importlib.import_module(f"weldplan.tool.{tool._EXPORTS[name]}"), name)
        assert name in dir(tool)
    with pytest.raises(AttributeError, match="no attribute 'plan_nothing'"):
        tool.plan_nothing  # noqa: B018


def test_a_tool_module_imported_first_does_not_hide_its_function():
    """``weldplan.tool.verify_poses`` is a module and the function the package exports; importing
    the module first must leave the function as the package's name (fresh interpreter)."""
    import subprocess
    import sys

    code = (
        "import weldplan.tool.verify_poses, weldplan.tool.tool_order, weldplan.tool.verify_sweeps; "
        "from weldplan.tool import tool_order, verify_poses, verify_sweeps; "
        "print([type(f).__name__ for f in (tool_order, verify_poses, verify_sweeps)])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        cwd=PACKAGE.parent,
    ).stdout  # fmt: skip
    assert eval(out) == ["function"] * 3
