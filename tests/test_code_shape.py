"""The code keeps its shape (issue 28, "Done when"), read from the source (ast): no function in
weldplan/commands/ over :data:`MAX_LINES` lines, decorators and docstrings included; no function
in weldplan/robot/ over :data:`MAX_PARAMS` parameters (a stage takes its data and one settings
object, weldplan/robot/settings.py)."""

from __future__ import annotations

import ast
from pathlib import Path

COMMANDS = Path(__file__).resolve().parents[1] / "weldplan" / "commands"
ROBOT = COMMANDS.parent / "robot"
#: the longest function the command layer may hold, lines from ``def`` to its last line
MAX_LINES = 40
#: functions allowed over the limit, each with its reason
ALLOWED: dict[str, str] = {}
#: the most parameters a function may take, ``self`` and ``cls`` not counted
MAX_PARAMS = 10


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


def wide_signatures(root: Path, limit: int) -> dict[str, int]:
    """``file:function`` -> parameters, for every function (methods and nested ones too) in the
    ``.py`` files under ``root`` that takes more than ``limit``: positional, keyword-only,
    ``*args`` and ``**kwargs`` each count one; ``self`` and ``cls`` do not."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                names = [p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
                names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
                n = sum(name not in ("self", "cls") for name in names)
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


def test_no_robot_signature_over_ten():
    wide = wide_signatures(ROBOT, MAX_PARAMS)
    assert not wide, f"functions over {MAX_PARAMS} parameters in weldplan/robot: {wide}"


def test_the_signature_rule_counts_keyword_only_and_star_arguments(tmp_path):
    (tmp_path / "a.py").write_text(
        "def f(a, b, /, c, *d, e, f=1, **g):\n    pass\n\n\n"
        "class C:\n    def m(self, a, *, b):\n        def inner(cls, x):\n            pass\n"
    )
    assert wide_signatures(tmp_path, 6) == {"a.py:f": 7}
    assert wide_signatures(tmp_path, 1) == {"a.py:f": 7, "a.py:m": 2}
    assert wide_signatures(tmp_path, 7) == {}


def test_no_tool_signature_over_ten():
    """Issue 28, "Done when": a tool search takes its inputs and one settings object
    (weldplan.tool.settings)."""
    wide = wide_signatures(ROBOT.parent / "tool", MAX_PARAMS)
    assert not wide, f"functions over {MAX_PARAMS} parameters in weldplan/tool: {wide}"
