"""Errors that carry enough context for a user to fix their input.

The CLI turns every :class:`WeldplanError` into one line on stderr: exit code 2 for bad input or
settings (:class:`InputError`, :class:`ConfigError` and the base class), 1 for a run that could
not finish (:class:`PlanningError`, :class:`RunError`). Anything else is a bug and keeps its
traceback. The codes are :data:`EXIT_OK`, :data:`EXIT_FAILURE`, :data:`EXIT_INPUT` and
:data:`EXIT_PARTIAL`.
"""

from __future__ import annotations

from os import PathLike

#: exit codes of the ``weldplan`` command (documented in its ``--help`` and the README)
EXIT_OK = 0
#: the run could not finish: no route, failed verification, an environment failure
EXIT_FAILURE = 1
#: bad input or settings (a usage error, a bad file, an impossible option)
EXIT_INPUT = 2
#: a partial result was written: ``--skip-unreachable`` left joints out, or ``--tool`` found no
#: free pose for some welds (both listed in the summary)
EXIT_PARTIAL = 3


class WeldplanError(Exception):
    """Base class of every error caused by the user's input or settings."""


class InputError(WeldplanError, ValueError):
    """Bad input data, located as precisely as we can: file, line and field.

    Parameters
    ----------
    message
        What is wrong, in words a user understands.
    path
        The file the input came from, if any.
    line
        1-based line number in that file, if known.
    field
        The column or field name, if known.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | PathLike[str] | None = None,
        line: int | None = None,
        field: str | None = None,
    ) -> None:
        self.message = message
        self.path = None if path is None else str(path)
        self.line = line
        self.field = field
        super().__init__(str(self))

    def __str__(self) -> str:
        where = []
        if self.path is not None:
            where.append(self.path)
        if self.line is not None:
            where.append(f"line {self.line}")
        if self.field is not None:
            where.append(f"field '{self.field}'")
        prefix = ", ".join(where)
        return f"{prefix}: {self.message}" if prefix else self.message


class PlanningError(WeldplanError):
    """A planning problem that has no answer (unreachable joint, no finite order, ...)."""


class ConfigError(WeldplanError, ValueError):
    """A setting of a run (a :class:`~weldplan.weld.pipeline.PlanConfig` field, a keyword of
    :func:`~weldplan.weld.pipeline.plan_route`, a CLI option) that is out of range or of the
    wrong type. ``field`` names the setting."""

    def __init__(self, message: str, *, field: str | None = None) -> None:
        self.message = message
        self.field = field
        super().__init__(message)


class RunError(WeldplanError):
    """The environment stopped a run that had good input: a full disk, an unreachable Dask
    scheduler, not enough memory for the grid the settings ask for. The CLI exits with 1."""


class UnreachableJointsError(PlanningError):
    """Some joints have no collision-free path to the others (enclosed, or behind a panel).

    Attributes
    ----------
    groups
        The joints as groups of joint ids with no collision-free path between them (the largest
        first); a single group when the failure is not a partition.
    stranded
        Joint ids with no path to any other joint at all.
    """

    def __init__(
        self,
        message: str,
        *,
        groups: list[list[str]] | None = None,
        stranded: list[str] | None = None,
    ) -> None:
        self.groups = [list(g) for g in (groups or [])]
        self.stranded = list(stranded or [])
        super().__init__(message)


def exit_code(exc: WeldplanError) -> int:
    """The CLI exit code of ``exc``: :data:`EXIT_FAILURE` for a run that could not finish
    (:class:`PlanningError`, :class:`RunError`), :data:`EXIT_INPUT` for every other
    :class:`WeldplanError` (bad input or settings)."""
    return EXIT_FAILURE if isinstance(exc, (PlanningError, RunError)) else EXIT_INPUT
