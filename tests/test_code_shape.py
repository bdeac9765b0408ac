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
