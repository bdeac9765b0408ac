"""The ``weldplan`` command line.

Each command lives in its own module exposing ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int``; this file only dispatches and turns errors into exit codes (:data:`EPILOG`).

What becomes one line on stderr instead of a traceback, and what does not:

- :class:`~weldplan.errors.WeldplanError`: exit 2 for bad input or settings, 1 for a run that
  could not finish (:class:`~weldplan.errors.PlanningError`, :class:`~weldplan.errors.RunError`);
- ``OSError``: a missing or unreadable file, a path that is a folder, a denied permission are
  bad input (2); any other (a full disk, an I/O error, a refused or timed-out connection) is a
  failure of the environment (1);
- ``MemoryError``: a failure (1), with the options that size the work;
- anything else (``TypeError``, ``IndexError``, ...) is a bug in weldplan and keeps its traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import logging
import sys
from collections.abc import Iterator
from importlib import import_module
from typing import NoReturn

from weldplan.errors import EXIT_FAILURE, EXIT_INPUT, WeldplanError, exit_code

#: the exit codes, as ``weldplan --help`` prints them (weldplan.errors holds the numbers)
EPILOG = """exit codes:
  0  done (a route was written and verified)
  1  the run failed: no route exists, verification refused it, or the environment failed
     (disk full, Dask scheduler unreachable, out of memory)
  2  bad input or settings: the message names the file, line and field or the option
  3  partial route: --skip-unreachable left joints out, or --tool found welds without a free
     tool pose; listed in the summary and the route JSON
  130  interrupted (Ctrl-C)"""

#: OSError numbers that mean the user's input or paths are wrong (exit 2); any other OSError is
#: the environment failing (exit 1)
_INPUT_ERRNOS = {
    errno.ENOENT,
    errno.EISDIR,
    errno.ENOTDIR,
    errno.EACCES,
    errno.EPERM,
    errno.ENAMETOOLONG,
    errno.EEXIST,
}

log = logging.getLogger(__name__)

#: command name -> module implementing it
COMMANDS: dict[str, str] = {
    "bench": "weldplan.commands.bench",
    "plan": "weldplan.commands.plan",
    "demo": "weldplan.commands.demo",
    "verify": "weldplan.commands.verify",
    "view": "weldplan.commands.view",
    "planar": "weldplan.commands.planar",
    "check-spots": "weldplan.commands.check_spots",
}


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line (``prog: error: ...``), exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="weldplan",
        description="Collision-free welding-torch routes through car bodies, and 2D path planning.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name, module_name in COMMANDS.items():
        module = import_module(module_name)
        p = sub.add_parser(
            name,
            help=module.HELP,
            description=module.HELP,
            epilog=EPILOG,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with _log_to_stderr(logging.WARNING - 10 * min(args.verbose, 2)):
        return _run(args)


@contextlib.contextmanager
def _log_to_stderr(level: int) -> Iterator[None]:
    """weldplan's own log records (warnings: coincident joints, repaired faces, ...) go to this
    call's stderr, whatever the root logger holds (``logging.basicConfig`` is a no-op when an
    embedding program or a test runner configured logging first, and the warnings were lost)."""
    logger = logging.getLogger("weldplan")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    saved = logger.level, logger.propagate
    logger.addHandler(handler)
    logger.setLevel(level)
    logger.propagate = False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(saved[0])
        logger.propagate = saved[1]


def _run(args: argparse.Namespace) -> int:
    """The command, with user errors turned into one line and an exit code."""
    try:
        return int(args._run(args) or 0)
    except WeldplanError as exc:
        print(f"weldplan {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return exit_code(exc)
    except OSError as exc:
        log.debug("the OS refused", exc_info=True)  # -vv shows where
        code = EXIT_INPUT if exc.errno in _INPUT_ERRNOS else EXIT_FAILURE
        print(f"weldplan {args.command}: error: {_describe_os_error(exc)}", file=sys.stderr)
        return code
    except MemoryError:
        log.debug("out of memory", exc_info=True)  # -vv shows where
        print(
            f"weldplan {args.command}: error: out of memory; make the work smaller "
            "(--margin, --pitch, --candidates) or see --memory-limit",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    except KeyboardInterrupt:
        print("weldplan: interrupted", file=sys.stderr)
        return 130


def _one_line(exc: BaseException) -> str:
    """``str(exc)`` on one line (messages that quote a file's content may hold line breaks)."""
    return " ".join(str(exc).split()) or type(exc).__name__


def _describe_os_error(exc: OSError) -> str:
    """``strerror: filename`` when the OS gave them, else the exception's text."""
    if exc.strerror:
        where = exc.filename if exc.filename is not None else ""
        if exc.filename2 is not None:
            where = f"{where} -> {exc.filename2}"
        return f"{exc.strerror}: {where}" if where else exc.strerror
    return _one_line(exc)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
