"""Parallel pair planning: the cell reaches each worker once, tasks carry only pair numbers.

:func:`weldplan.weld.pipeline.plan_route` takes any ``concurrent.futures.Executor``. A naive
``executor.submit(plan_pair, cell, ...)`` would pickle the cell (mesh + bit-packed grid) with every
task and rebuild its FCL model in the worker each time. Instead :func:`share_cell` gives a
picklable reference whose unpickling looks the cell up in a per-process cache keyed by a token:

* a pool from :func:`process_pool` installs the cell in each worker at start (``initializer``),
  so a task carries the token only;
* a Dask executor (``Client.get_executor()``) gets the cell scattered to every worker once
  (``Client.scatter(..., broadcast=True)``); tasks carry the Dask future, resolved in worker memory;
* any other executor gets the cell pickled once in this process; each worker unpickles (and builds
  the collision model) once, the first time, and reuses it; tasks are sent in a few batches so
  the bytes travel a few times per worker, not once per pair.

Tasks are batches of pairs; each pair has its own seed, so the route does not depend on the
executor, the batching or the order in which workers finish.
"""

from __future__ import annotations

import contextlib
import logging
import math
import pickle
import uuid
from collections.abc import Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any

log = logging.getLogger(__name__)

#: per-process cache: token -> cell (a worker keeps the last few cells it was sent)
_CELLS: dict[str, Any] = {}
_CACHE_SIZE = 4
#: batches per worker when splitting pair-planning tasks
BATCHES_PER_WORKER = 4
#: seconds to wait for a Dask scheduler before giving up (``--dask tcp://...``)
DASK_CONNECT_TIMEOUT = 5.0


def _remember(key: str, cell: Any) -> Any:
    _CELLS[key] = cell
    while len(_CELLS) > _CACHE_SIZE:
        _CELLS.pop(next(iter(_CELLS)))
    return cell


def _attach(key: str, payload: bytes | None) -> Any:
    """Unpickling of a :class:`CellRef`: the cached cell, else the payload's (cached)."""
    cell = _CELLS.get(key)
    if cell is not None:
        return cell
    if payload is None:
        raise RuntimeError(f"cell {key} is not installed in this worker process")
    return _remember(key, pickle.loads(payload))


def _install(key: str, payload: bytes) -> None:
    """Process-pool initializer: unpickle the cell once per worker."""
    _remember(key, pickle.loads(payload))


class CellRef:
    """Picklable reference to a cell; unpickles to the cell itself (built once per process).

    Parameters
    ----------
    cell
        The cell.
    key
        Token of the cell in the worker caches (a new one when None).
    ship
        Whether the pickle carries the cell's bytes (False when the workers already hold it).
    """

    def __init__(self, cell: Any, key: str | None = None, *, ship: bool = True) -> None:
        self.cell = cell
        self.key = key or uuid.uuid4().hex
        self.ship = ship
        self._payload: bytes | None = None

    def payload(self) -> bytes:
        """The cell pickled once (protocol 5)."""
        if self._payload is None:
            self._payload = pickle.dumps(self.cell, protocol=pickle.HIGHEST_PROTOCOL)
            log.debug("cell %s pickled: %.1f MB", self.key, len(self._payload) / 1e6)
        return self._payload

    def __reduce__(self) -> tuple[Any, tuple[str, bytes | None]]:
        return _attach, (self.key, self.payload() if self.ship else None)


def process_pool(cell: Any, jobs: int) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` workers, each holding ``cell`` from its start."""
    ref = CellRef(cell)
    ex = ProcessPoolExecutor(
        max_workers=jobs, initializer=_install, initargs=(ref.key, ref.payload())
    )
    ex._weldplan_cells = {id(cell): ref.key}  # type: ignore[attr-defined]
    return ex


def _dask_client(executor: Executor) -> Any | None:
    if type(executor).__module__.startswith("distributed"):
        return getattr(executor, "_client", None)
    return None


def resolve(cell: Any) -> Any:
    """The cell behind what :func:`share_cell` gave (a :class:`CellRef` not yet pickled, as in
    an executor that runs tasks in this process, is unwrapped)."""
    return cell.cell if isinstance(cell, CellRef) else cell


def n_workers(executor: Executor | None) -> int:
    """Workers behind ``executor`` (1 when unknown)."""
    if executor is None:
        return 1
    client = _dask_client(executor)
    if client is not None:
        return max(1, sum(client.nthreads().values()))
    return int(getattr(executor, "_max_workers", 1) or 1)


def share_cell(cell: Any, executor: Executor | None) -> Any:
    """What tasks should carry to reach ``cell`` on ``executor``'s workers (module docstring)."""
    if executor is None or isinstance(executor, ThreadPoolExecutor):
        return cell  # same process: nothing to ship
    key = getattr(executor, "_weldplan_cells", {}).get(id(cell))
    if key is not None:
        return CellRef(cell, key, ship=False)
    client = _dask_client(executor)
    if client is not None:
        return client.scatter(cell, broadcast=True, hash=False)
    return CellRef(cell)


def batches(items: Sequence[Any], workers: int, max_size: int | None = None) -> list[list[Any]]:
    """``items`` cut into about ``BATCHES_PER_WORKER * workers`` consecutive batches, each of at
    most ``max_size`` items when given (more, smaller batches: a worker that runs out of work
    waits at most one small batch for the last one to finish)."""
    if not items:
        return []
    size = max(1, math.ceil(len(items) / (BATCHES_PER_WORKER * max(1, workers))))
    if max_size is not None:
        size = min(size, max(1, int(max_size)))
    return [list(items[k : k + size]) for k in range(0, len(items), size)]


def _connect(client_cls: Any, address: str, timeout: float) -> Any:
    """A Dask client of the scheduler at ``address``; a one-line weldplan error when the address
    is malformed (:class:`~weldplan.errors.InputError`) or nothing usable answers within
    ``timeout`` seconds (:class:`~weldplan.errors.RunError`)."""
    from weldplan.errors import InputError, RunError

    try:
        return client_cls(address, timeout=timeout)
    except ValueError as exc:
        raise InputError(f"not a Dask scheduler address ({exc})", field="--dask") from exc
    except OSError as exc:  # refused, unreachable, timed out (TimeoutError is an OSError)
        raise RunError(
            f"cannot reach the Dask scheduler at {address} within {timeout:g} s ({exc})"
        ) from exc
    except MemoryError as exc:  # a service that is not a Dask scheduler sent a bogus length
        raise RunError(
            f"{address} answered, but not as a Dask scheduler (its reply made no sense)"
        ) from exc


@contextlib.contextmanager
def dask_executor(
    address: str, *, workers: int = 2, timeout: float = DASK_CONNECT_TIMEOUT
) -> Iterator[Executor]:
    """A ``concurrent.futures`` executor on Dask: ``"local"`` starts a LocalCluster of
    ``workers`` single-threaded processes, ``"tcp://HOST:PORT"`` joins a running scheduler
    (waiting at most ``timeout`` seconds for it)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - optional extra
        from weldplan.errors import WeldplanError

        raise WeldplanError(
            "--dask needs the optional extra: pip install 'weldplan[dask]'"
        ) from exc
    with contextlib.ExitStack() as stack:
        if address == "local":
            cluster = stack.enter_context(
                LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                )
            )
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(_connect(Client, address, timeout))
        log.info("dask: %s, %d worker threads", client, sum(client.nthreads().values()))
        yield client.get_executor()
