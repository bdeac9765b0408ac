"""Keyword conveniences over a settings object: :func:`laid_over`.

A function that takes its inputs and one frozen settings object (../shared/DESIGN.md) may also
take the settings' fields by name, laid over the object given: ``solve_sequence(C,
method="exact")`` is ``solve_sequence(C, SequenceSettings(method="exact"))``. This is the one
place that lays them over and refuses a name that is not a field, as Python refuses an unknown
keyword.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, TypeVar

_S = TypeVar("_S")


def laid_over(cls: type[_S], settings: _S | None, options: Mapping[str, Any], caller: str) -> _S:
    """``settings`` (default ``cls()``) with the fields ``options`` names replaced, validated
    again by the dataclass (its ``__post_init__``).

    Parameters
    ----------
    cls
        The frozen settings dataclass.
    settings
        The settings object given, or ``None``.
    options
        Field name -> value, the caller's keywords.
    caller
        The function's name, for the error.

    Raises
    ------
    TypeError
        For a name that is not a field of ``cls`` (``caller() got an unexpected keyword
        argument 'x'``).
    """
    names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = set(options) - names
    if unknown:
        raise TypeError(f"{caller}() got an unexpected keyword argument {sorted(unknown)[0]!r}")
    base = cls() if settings is None else settings
    return dataclasses.replace(base, **options) if options else base  # type: ignore[type-var]
