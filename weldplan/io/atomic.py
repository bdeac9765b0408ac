"""All-or-nothing writes of one text file: :func:`write_text_atomic`.

The text is written to a temporary file in the destination folder, flushed to disk, then renamed
over the destination with :func:`os.replace`. A run that fails (an error while rendering, a full
disk, an interrupt) leaves an existing file exactly as it was. (A run's several files are
written all or none by :mod:`weldplan.io.outputset`.)
"""

from __future__ import annotations

import logging
import os
import tempfile
from os import PathLike
from pathlib import Path

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)


def write_text_atomic(path: str | PathLike[str], text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` whole or not at all (temp file in the same folder + rename).

    Returns the path written. Raises :class:`~weldplan.errors.WeldplanError` when the folder does
    not exist, so the CLI reports it in one line.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise WeldplanError(f"{path}: folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding=encoding, newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        if path.exists():
            os.chmod(tmp, path.stat().st_mode & 0o777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    log.debug("wrote %s (%d chars)", path, len(text))
    return path
