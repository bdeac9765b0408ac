"""The command layer stays thin (issue 28, "Done when"): no function in weldplan/commands/ over
:data:`MAX_LINES` lines, read from the source (ast), decorators and docstrings included."""

from __future__ import annotations

import ast
from pathlib import Path

COMMANDS = Path(__file__).resolve().parents[1] / "weldplan" / "commands"
#: the longest function the command layer may hold, lines from ``def`` to its last line
MAX_LINES = 40
#: functions allowed over the limit, each with its reason
ALLOWED: dict[str, str] = {}


def long_functions(root: Path, limit: int) -> dict[str, int]:
    """``file:function`` -> lines, for every function (methods and nested ones too) over
    ``limit`` lines in the ``.py`` files under ``root``."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1  # type: ignore[operator]
                if n > limit:
                    out[f"{path.relative_to(root)}:{node.name}"] = n
    return out


def test_no_command_function_is_over_the_limit():
    long = {k: n for k, n in long_functions(COMMANDS, MAX_LINES).items() if k not in ALLOWED}
    assert not long, f"functions over {MAX_LINES} lines in weldplan/commands: {long}"


def test_the_rule_counts_nested_functions_and_methods(tmp_path):
    body = "\n".join(f"        x{k} = {k}" for k in range(5))
    (tmp_path / "a.py").write_text(
        f"def short():\n    return 1\n\n\nclass C:\n    def long(self):\n{body}\n"
    )
    assert long_functions(tmp_path, 5) == {"a.py:long": 6}
    assert long_functions(tmp_path, 6) == {}


def test_no_tool_signature_over_ten():
    """Issue 28, "Done when": no function in weldplan/tool/ takes more than 10 parameters
    (positional, keyword-only, ``*args`` and ``**kwargs`` counted; a method's ``self`` / ``cls``
    not): a search takes its inputs and one settings object (weldplan.tool.settings)."""
    limit = 10

    def wide(tree: ast.Module, where: str) -> dict[str, int]:
        methods = {id(f) for c in ast.walk(tree) if isinstance(c, ast.ClassDef) for f in c.body}
        out = {}
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                names = [p.arg for p in (*a.posonlyargs, *a.args)]
                n = len(names) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
                if id(node) in methods and names[:1] in (["self"], ["cls"]):
                    n -= 1
                if n > limit:
                    out[f"{where}:{node.name}"] = n
        return out

    # the rule itself: keyword-only, *args and **kwargs count; a method's self does not
    probe = ast.parse(
        "def f(a, b, c, d, e, *g, h, i, j, **k): pass\n"
        "class C:\n    def m(self, a, b, c, d, e, f, g, h, i, j): pass\n"
        "    def w(self, a, b, c, d, e, f, g, h, i, j, k): pass\n"
    )
    assert wide(probe, "probe") == {"probe:w": 11}, wide(probe, "probe")
    root = Path(__file__).resolve().parents[1] / "weldplan" / "tool"
    found: dict[str, int] = {}
    for path in sorted(root.rglob("*.py")):
        found.update(wide(ast.parse(path.read_text(encoding="utf-8")), str(path.name)))
    assert not found, f"signatures over {limit} parameters in weldplan/tool: {found}"
