"""Errors that carry enough context for a user to fix their input.

The CLI turns every :class:`WeldplanError` into one line on stderr and exit code 2;
anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

from os import PathLike


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
