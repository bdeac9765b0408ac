"""Packages whose public names load on first use (PEP 562), so that importing one module of the
package does not load the others (``weldplan.tool``, ``weldplan.study``)."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of ``package``.

    Parameters
    ----------
    package
        The package's dotted name (its ``__name__``).
    exports
        Public name -> the module of ``package`` that defines it (``"model"`` for
        ``package.model``).

    Returns
    -------
    (__getattr__, __dir__)
        ``__getattr__(name)`` imports the defining module on first use and keeps the name in the
        package (an unknown name: AttributeError); ``__dir__()`` lists the package's names and
        every export.
    """

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
