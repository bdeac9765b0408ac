"""weldplan's modules import each other without cycles and in the order of their layers (data
flows one way: model -> planning -> route -> export/view; :data:`LAYERS`).

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


#: weldplan's layers, lowest first: a module may import its own layer and the layers below it,
#: never one above (module level or inside a function). A module's layer is the one of the
#: longest prefix that names it. The order is ../shared/DESIGN.md's data flow: the geometry core
#: and the optimisers; the readers; the point-tip route (weld) and the stages above it (tool,
#: robot); the exporters after the models they write ("io and viz never import the planners");
#: the station that runs the stages; the study and the pictures; the commands on top.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("base", ("weldplan.errors", "weldplan.random", "weldplan.lazy", "weldplan._version",
              "weldplan.options")),
    ("geometry", ("weldplan.geometry",)),
    ("optim", ("weldplan.optim",)),
    # the readers of the inputs and the all-or-nothing file writers (io.atomic, io.outputset):
    # every stage uses them
    ("readers", ("weldplan.io", "weldplan.io.joints", "weldplan.io.mesh", "weldplan.io.tsplib",
                 "weldplan.io.outputset")),
    ("planar", ("weldplan.planar",)),
    ("motion", ("weldplan.motion",)),
    ("frames", ("weldplan.cellframe",)),
    ("weld", ("weldplan.weld",)),
    ("tool", ("weldplan.tool",)),
    # the exporters read the route and its poses (weld, tool) and are what the robot's program
    # is written with; io/tool_csv is the tool path's writer, an exporter beside its model
    ("exporters", ("weldplan.io.export", "weldplan.io.route_rows", "weldplan.io.route_posts",
                   "weldplan.io.blending", "weldplan.io.smooth_moves", "weldplan.io.timings",
                   "weldplan.io.trajectory", "weldplan.io.posts", "weldplan.io.tool_csv")),
    ("robot", ("weldplan.robot",)),
    # the allocation of welds among robots: reach and leg times of the robot models
    ("multi", ("weldplan.multi",)),
    ("station", ("weldplan.station",)),
    ("study", ("weldplan.study",)),
    # several robots: their bases and the study per robot, then the single-robot pipeline per share
    ("stations", ("weldplan.multi.station", "weldplan.multi.cell", "weldplan.multi.shares",
                  "weldplan.multi.passes")),
    ("viz", ("weldplan.viz",)),
    # a plan's files: rendered by the exporters and the viewers
    ("outputs", ("weldplan.station.outputs",)),
    # a station of several robots as files: every robot's outputs, the station JSON, its re-check
    ("station files", ("weldplan.multi.saved", "weldplan.multi.recheck",
                       "weldplan.multi.programcheck")),
    ("api", ("weldplan",)),
    ("bench", ("weldplan.bench",)),
    ("commands", ("weldplan.commands",)),
    ("cli", ("weldplan.cli", "weldplan.__main__")),
)  # fmt: skip

#: imports allowed against the layer order, each with its reason (none today)
ALLOWED_UPWARD: dict[tuple[str, str], str] = {}


def layer_of(module: str, layers=LAYERS) -> int:
    """Index in ``layers`` of the longest prefix naming ``module`` (KeyError: none)."""
    best = None
    for k, (_, prefixes) in enumerate(layers):
        for prefix in prefixes:
            if module == prefix or module.startswith(prefix + "."):
                if best is None or len(prefix) > best[1]:
                    best = (k, len(prefix))
    if best is None:
        raise KeyError(f"{module} is in no layer: add it to LAYERS")
    return best[0]


def layer_violations(g: nx.DiGraph, layers=LAYERS, allowed=None) -> list[str]:
    """``importer:line -> imported (layer -> higher layer)`` for every upward import."""
    allowed = ALLOWED_UPWARD if allowed is None else allowed
    out = []
    for a, b in sorted(g.edges):
        la, lb = layer_of(a, layers), layer_of(b, layers)
        if la < lb and (a, b) not in allowed:
            out.append(f"  {a}:{g.edges[a, b]['line']} -> {b} ({layers[la][0]} -> {layers[lb][0]})")
    return out


def test_every_module_imports_only_its_layer_and_the_layers_below():
    g = import_graph()
    for m in g.nodes:
        layer_of(m)  # every module has a layer
    bad = layer_violations(g)
    assert not bad, "imports from a higher layer (LAYERS):\n" + "\n".join(bad)
    stale = [e for e in ALLOWED_UPWARD if not g.has_edge(*e)]
    assert not stale, f"allowed imports that no longer exist: {stale}"


def test_the_layer_rule_catches_an_upward_import_even_inside_a_function(tmp_path):
    pkg = tmp_path / "demo"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "low.py").write_text("def f():\n    from demo.high import g\n    return g\n")
    (pkg / "high.py").write_text("from demo.low import f\n\ng = f\n")
    layers = (("low", ("demo", "demo.low")), ("high", ("demo.high",)))
    g = import_graph(pkg)
    assert layer_violations(g, layers, allowed={}) == ["  demo.low:2 -> demo.high (low -> high)"]
    assert layer_violations(g, layers, allowed={("demo.low", "demo.high"): "why"}) == []
    assert layer_of("demo.high.sub", layers) == 1  # the longest prefix wins
    with pytest.raises(KeyError, match="in no layer"):
        layer_of("other.mod", layers)


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
    """io/export reads a route's poses through weldplan.tool.poses.route_frames, which runs the tool
    package's ``__init__`` first: that ``__init__`` is lazy (PEP 562), so the pose planner, the
    sweep checker and their FCL models stay unloaded (a fresh interpreter: other tests import
    them)."""
    import subprocess
    import sys

    code = (
        "import sys, weldplan.io.export, weldplan.tool.poses.route_frames; "
        "print(sorted(m for m in sys.modules if m.startswith('weldplan.tool')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        cwd=PACKAGE.parent,
    ).stdout  # fmt: skip
    loaded = set(eval(out))
    assert "weldplan.tool.poses.route_frames" in loaded  # the import ran
    assert not loaded & {
        "weldplan.tool.poses.plan",
        "weldplan.tool.transitions.sweep",
        "weldplan.tool.model.tool",
    }


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
    """``weldplan.tool.verify.poses`` is a module and the function the package exports; importing
    the module first must leave the function as the package's name (fresh interpreter)."""
    import subprocess
    import sys

    code = (
        "import weldplan.tool.verify.poses, weldplan.tool.transitions.order, "
        "weldplan.tool.verify.sweeps; "
        "from weldplan.tool import tool_order, verify_poses, verify_sweeps; "
        "print([type(f).__name__ for f in (tool_order, verify_poses, verify_sweeps)])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        cwd=PACKAGE.parent,
    ).stdout  # fmt: skip
    assert eval(out) == ["function"] * 3
