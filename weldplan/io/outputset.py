"""The outputs of one run as a set: checked before the work, written all or none.

A planning run writes several files (route CSV, JSON, HTML page, robot program). Writing them one
after the other, each atomically, is not enough: when the third fails the first two are already
replaced, and the set on disk mixes two runs. Here:

1. :func:`check_outputs` runs before any planning: every folder exists and can be written (a probe
   file is created and removed, which also catches read-only file systems and, for root, folders
   whose permission bits say "read only"), and no target is a folder or a write-protected file.
2. :func:`write_outputs` writes every text to a temporary file in its target's folder (same file
   system, so the final rename is atomic), keeps a hard link (or a copy) of every file it will
   replace, and renames the temporaries only once all were written. When a rename fails, the
   files already renamed are put back from their backups (or removed when they are new), so a
   failed run leaves every previous file as it was.

The only window left is a crash of the machine between two renames of step 2.
"""

from __future__ import annotations

import errno
import logging
import os
import shutil
import stat
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

from weldplan.errors import InputError, RunError

log = logging.getLogger(__name__)

#: prefix of the temporary and backup files (hidden; removed on success and on failure)
TEMP_PREFIX = ".weldplan-"

#: OSError numbers that are the user's paths being wrong rather than the environment failing
_PATH_ERRNOS = {
    errno.ENOENT,
    errno.ENOTDIR,
    errno.EISDIR,
    errno.EACCES,
    errno.EPERM,
    errno.ENAMETOOLONG,
    errno.EROFS,
}


def comment_lines(lines: Sequence[str], mark: str, indent: str = "") -> str:
    """``lines`` as comment lines of an output file, each ended by a newline.

    ``mark``: ``"#"`` (CSV), ``"!"`` (RAPID), ``";"`` (KRL); ``indent`` goes before it. Every
    reader of weldplan's files skips such lines (:func:`weldplan.io.posts.parse.parse_rapid`,
    :func:`~weldplan.io.posts.parse.parse_krl`; a CSV's ``#`` lines)."""
    return "".join(f"{indent}{mark} {line}\n" for line in lines)


def _folder(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def _write_protected(path: Path) -> bool:
    """True when ``path`` may not be written: no write permission for this user, or (since root
    passes every access check) no write bit at all in its mode."""
    mode = path.stat().st_mode
    return not os.access(path, os.W_OK) or not (mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def check_outputs(paths: Mapping[str, Path]) -> None:
    """Raise :class:`~weldplan.errors.InputError` naming the first output that cannot be written.

    Parameters
    ----------
    paths
        ``kind -> path`` of every file the run will write (``kind`` names the option in messages,
        e.g. ``"csv"``, ``"json"``).
    """
    probed: set[Path] = set()
    for kind, path in paths.items():
        path = Path(path)
        try:
            _check_one(kind, path, probed)
        except OSError as exc:  # a name too long, a path through a file, ...
            raise InputError(
                f"cannot be written ({exc.strerror or exc})", path=path, field=kind
            ) from exc


def _check_one(kind: str, path: Path, probed: set[Path]) -> None:
    folder = _folder(path)
    if not folder.is_dir():
        raise InputError(f"folder {folder} does not exist", path=path, field=kind)
    if path.is_dir():
        raise InputError("is a folder, not a file", path=path, field=kind)
    if path.exists() and _write_protected(path):
        raise InputError(
            "the file exists and is write-protected (remove it or make it writable)",
            path=path,
            field=kind,
        )
    key = folder.resolve()
    if key in probed:
        return
    if _write_protected(folder):
        raise InputError(f"folder {folder} is not writable", path=path, field=kind)
    try:
        fd, probe = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=".probe", dir=folder)
    except OSError as exc:
        raise InputError(
            f"folder {folder} is not writable ({exc.strerror})", path=path, field=kind
        ) from exc
    os.close(fd)
    os.unlink(probe)
    probed.add(key)


def _new_mode(path: Path) -> int:
    """Mode of the file written at ``path``: the replaced file's, else 0o666 minus the umask."""
    if path.exists():
        return path.stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _write_temp(path: Path, text: str | bytes, encoding: str) -> Path:
    """``text`` (or bytes, e.g. a PNG) in a new temporary file next to ``path``, flushed to
    disk; its path."""
    fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=".tmp", dir=_folder(path))
    binary = isinstance(text, bytes)
    try:
        with os.fdopen(fd, "wb" if binary else "w", encoding=None if binary else encoding,
                       newline=None if binary else "") as f:  # fmt: skip
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _new_mode(path))
    except BaseException:
        _remove(Path(tmp))
        raise
    return Path(tmp)


def _backup(path: Path) -> Path | None:
    """A second name for the current content of ``path`` (hard link, else a copy); None when
    there is no file to keep."""
    if not path.exists():
        return None
    fd, name = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=".bak", dir=_folder(path))
    os.close(fd)
    backup = Path(name)
    try:
        backup.unlink()
        os.link(path, backup)
    except OSError:  # no hard links on this file system: copy the bytes
        shutil.copy2(path, backup)
    return backup


def _remove(path: Path | None) -> None:
    if path is None:
        return
    try:
        path.unlink()
    except FileNotFoundError:
        pass
    except OSError as exc:  # pragma: no cover - cleanup must not hide the first error
        log.warning("could not remove %s: %s", path, exc)


def _as_weldplan_error(exc: OSError, path: Path) -> Exception:
    msg = f"could not write it ({exc.strerror or exc}); no output file was changed"
    if exc.errno in _PATH_ERRNOS:
        return InputError(msg, path=path)
    return RunError(f"{path}: {msg}")


def write_outputs(texts: Mapping[Path, str | bytes], *, encoding: str = "utf-8") -> list[Path]:
    """Write every ``path -> text`` of ``texts`` (bytes are written as they are), all or none
    (module docstring).

    Returns
    -------
    The paths written, in the order given.

    Raises
    ------
    InputError
        A path that cannot be written (permissions, a missing folder, a name too long).
    RunError
        The environment failed (disk full, I/O error). In both cases every file that existed
        before has its previous content and no temporary file is left.
    """
    items = [(Path(p), t) for p, t in texts.items()]
    temps: list[Path] = []
    backups: list[Path | None] = []
    renamed: list[int] = []
    current = items[0][0] if items else Path(".")
    try:
        for path, text in items:
            current = path
            temps.append(_write_temp(path, text, encoding))
        for path, _ in items:
            current = path
            backups.append(_backup(path))
        for k, (path, _) in enumerate(items):
            current = path
            os.replace(temps[k], path)
            renamed.append(k)
    except OSError as exc:
        _roll_back(items, temps, backups, renamed)
        raise _as_weldplan_error(exc, current) from exc
    except BaseException:
        _roll_back(items, temps, backups, renamed)
        raise
    for b in backups:
        _remove(b)
    for path, text in items:
        log.debug("wrote %s (%d chars)", path, len(text))
    return [p for p, _ in items]


def _roll_back(
    items: list[tuple[Path, str]],
    temps: list[Path],
    backups: list[Path | None],
    renamed: list[int],
) -> None:
    """Undo a partial :func:`write_outputs`: previous files back, new files and temporaries
    removed."""
    for k in reversed(renamed):
        path = items[k][0]
        backup = backups[k] if k < len(backups) else None
        try:
            if backup is not None:
                os.replace(backup, path)
                backups[k] = None
            else:
                path.unlink()
        except OSError as exc:  # pragma: no cover - nothing more we can do
            log.error("could not restore %s: %s", path, exc)
    for k, tmp in enumerate(temps):
        if k not in renamed:
            _remove(tmp)
    for b in backups:
        _remove(b)
