"""Batch reduction on Dask: one task per recording.

>>> b = incal.batch.reduce(paths, "tumble", mount="pendulum")
>>> b.results          # {path: Result} of the recordings reduced
>>> b.errors           # {path: FileError} of the others, each one line

Each task runs ``incal.<procedure>(path, **options)`` on a worker, so every
result equals the one-file run. With no ``client`` a ``LocalCluster`` of
worker processes is started on this machine (and closed after); give a
``distributed.Client`` connected to any scheduler to spread a batch over
a cluster (the workers need the ``incal`` package and must see the
recordings' paths, e.g. on a shared filesystem). With ``records``, each
result is added to that store (a path or a ``postgresql://`` URL) by one
writer, this process, in the order of the paths; a batch run again finds
its records and stores nothing twice. ``incal batch`` on the command line
does the same on the local cores without Dask.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Dict, Iterable, List, Optional, Union

__all__ = ["reduce", "Batch", "FileError", "PROCEDURES"]

#: Procedure ids (the registry's, ``incal procedures``) that reduce one
#: recording, and their function names; from the procedure registry.
PROCEDURES: Dict[str, str] = {}
#: A document id written by exactly one such procedure, and that
#: procedure's id (``thermal`` is ``thermal-ramp``), as ``incal batch``
#: takes it.
_BY_DOCUMENT: Dict[str, str] = {}


def _tables() -> None:
    from . import REGISTRY

    seen: Dict[str, List[str]] = {}
    for e in REGISTRY:
        if e["input"] == "recording":
            PROCEDURES[e["id"]] = e["python"]["function"]
            seen.setdefault(e["document"], []).append(e["id"])
    for doc, ids in seen.items():
        if len(ids) == 1 and doc not in PROCEDURES:
            _BY_DOCUMENT[doc] = ids[0]


_tables()


class FileError:
    """A recording the procedure refused or failed on: ``message`` is the
    CLI's one line (it names the file), ``code`` its exit code."""

    def __init__(self, path: str, message: str, code: int):
        self.path, self.message, self.code = path, message, code

    def __repr__(self) -> str:
        return f"<incal.batch.FileError {self.message!r}>"

    def __str__(self) -> str:
        return self.message


class Batch(list):
    """The outcome of every recording, in the order given: a
    :class:`incal.Result` or a :class:`FileError` each."""

    def __init__(
        self,
        paths: List[str],
        items: Iterable[Any],
        records: Optional[List[Optional[int]]] = None,
        stopped: Optional[Dict[str, str]] = None,
    ):
        super().__init__(items)
        self.paths = paths
        #: Record id of each recording when ``records`` was given (None for an error).
        self.record_ids = records
        #: Path → message of the results a ``fail_on`` verdict stopped (they
        #: are in the list and recorded like the others).
        self.stopped = stopped or {}

    @property
    def results(self) -> Dict[str, Any]:
        return {p: r for p, r in zip(self.paths, self) if not isinstance(r, FileError)}

    @property
    def errors(self) -> Dict[str, FileError]:
        return {p: r for p, r in zip(self.paths, self) if isinstance(r, FileError)}

    def __repr__(self) -> str:
        return f"<incal.batch.Batch {len(self)} recordings: {len(self.results)} reduced, {len(self.errors)} failed>"


def _function(procedure: str) -> str:
    pid = procedure.replace("_", "-")
    pid = _BY_DOCUMENT.get(pid, pid)
    if pid not in PROCEDURES:
        from . import InputError

        raise InputError(f"batch: '{procedure}' is not a procedure (one of: {', '.join(PROCEDURES)})")
    return PROCEDURES[pid]


def _task(path: str, function: str, options: Dict[str, Any], serial_from_stem: bool):
    """On a worker: ``("ok", document text, None)``, ``("ok", document
    text, message)`` for a result a ``fail_on`` verdict stopped (kept and
    recorded like the others), or ``("error", code, message)``."""
    import incal

    options = dict(options)
    if serial_from_stem:
        options["serial"] = os.path.splitext(os.path.basename(path))[0]
    try:
        r = getattr(incal, function)(path, **options)
    except incal.IncalError as e:
        stopped = e.result if e.code == 3 else None
        if stopped is not None:
            return ("ok", stopped.to_json(), f"{path}: {e}")
        return ("error", e.code, str(e))
    return ("ok", r.to_json(), None)


def reduce(
    paths: Iterable[Any],
    procedure: str,
    client: Any = None,
    records: Optional[Any] = None,
    serial_from_stem: bool = False,
    progress: bool = True,
    **options: Any,
) -> Batch:
    """Reduce every recording of ``paths`` with ``procedure`` (``"tumble"``,
    ``"imu_ferraris"``, …) and ``options`` (as for ``incal.<procedure>``)
    on Dask: one task per recording; the outcomes in the order of
    ``paths``. One bad recording never stops the batch: it is a
    :class:`FileError` in its place. ``serial_from_stem`` gives each file's
    stem as the instrument serial. Progress goes to standard error."""
    import json

    from distributed import Client, LocalCluster, as_completed

    from . import Result

    paths = [os.fspath(p) for p in paths]
    function = _function(procedure)
    if "serial" in options and serial_from_stem:
        from . import InputError

        raise InputError("batch: give serial or serial_from_stem, not both")
    if not paths:
        return Batch([], [], [] if records is not None else None)
    own = None
    if client is None:
        workers = max(1, min(len(paths), os.cpu_count() or 1))
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        own = (cluster, Client(cluster))
        client = own[1]
    try:
        futures = [
            client.submit(_task, p, function, options, serial_from_stem, key=f"incal-{function}-{k}", pure=False)
            for k, p in enumerate(paths)
        ]
        index = {f.key: k for k, f in enumerate(futures)}
        outcomes: List[Any] = [None] * len(paths)
        done = failed = 0
        for f in as_completed(futures):
            k = index[f.key]
            try:
                outcomes[k] = f.result()
            except Exception as e:  # a worker lost, an unpicklable error
                outcomes[k] = ("error", 1, f"{paths[k]}: {type(e).__name__}: {e}")
            done += 1
            failed += outcomes[k][0] == "error"
            if progress:
                print(f"\rincal batch: {done}/{len(paths)} done, {failed} failed", end="", file=sys.stderr, flush=True)
        if progress and paths:
            print(file=sys.stderr)
    finally:
        if own is not None:
            own[1].close()
            own[0].close()
    items: List[Any] = []
    stopped: Dict[str, str] = {}
    for p, o in zip(paths, outcomes):
        if o[0] == "ok":
            items.append(Result(json.loads(o[1]), text=o[1]))
            if o[2] is not None:
                stopped[p] = o[2]
        else:
            items.append(FileError(p, o[2], o[1]))
    ids = None
    if records is not None:
        from .records import Records

        store = records if isinstance(records, Records) else Records(records)
        ids = [None if isinstance(r, FileError) else store.add(r) for r in items]
    return Batch(paths, items, ids, stopped)
