"""Running the CLI in-process from tests: exit codes and one-line user errors."""

from __future__ import annotations

from weldplan.cli import main


def run_cli(argv) -> int:
    """Exit code of ``weldplan argv`` (argparse errors exit through SystemExit)."""
    try:
        return main(argv)
    except SystemExit as e:
        return int(e.code)


def one_line_error(capsys) -> str:
    """The one line a user error printed on stderr, with no traceback."""
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    return lines[0]
