"""Batch reduction on Dask: one task per recording.

>>> b = incal.batch.reduce(paths, "tumble", mount="pendulum")
>>> b.results          # {path: Result} of the recordings reduced
>>> b.errors           # {path: FileError} of the others, each one line
>>> incal.batch.reduce(["fixture.csv"], "tumble", units=["out_1", "out_2"], mount="pendulum")

``units`` reduces several units recorded in one file (a fixture), each as
its own result with its own serial, as ``incal batch --units`` does: a
list of output columns (each column's name its serial), a dict
``{serial: column}`` (or ``{serial: "acc_x=u1_ax,…"}``), or the path of a
mapping file (CSV: ``serial``, ``columns``, optional ``slot`` and
``options``, the unit's own options as ``--flag value`` words, given as
keywords ``flag=value``). A bare column is read as ``unit_column``
(default ``output``); results are keyed ``"PATH [SERIAL]"``.

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


def _columns_of(cell: str, target: str) -> str:
    return cell if "=" in cell else f"{target}={cell}"


def _flags(words: str) -> Dict[str, Any]:
    """A unit's own options, ``--mount gate --axes x,-y,z``, as keywords."""
    out: Dict[str, Any] = {}
    tokens = words.split()
    k = 0
    while k < len(tokens):
        t = tokens[k]
        if not t.startswith("--"):
            from . import InputError

            raise InputError(f"units: '{t}': a unit's options are --flag value words")
        key = t[2:].replace("-", "_")
        if "=" in key:
            key, value = key.split("=", 1)
            out[key.replace("-", "_")], k = value, k + 1
        elif k + 1 < len(tokens) and not tokens[k + 1].startswith("--"):
            out[key], k = tokens[k + 1], k + 2
        else:
            out[key], k = True, k + 1
    return out


def _units(units: Any, target: str) -> List[Dict[str, Any]]:
    """Each unit's keywords: ``serial``, ``columns``, ``meta`` (its slot)
    and its own options."""
    import csv

    from . import InputError

    if isinstance(units, os.PathLike) and not os.path.isfile(units):
        raise InputError(f"units: {os.fspath(units)}: no such mapping file")
    if isinstance(units, (str, os.PathLike)) and os.path.isfile(units):
        name = os.fspath(units)
        with open(units, newline="", encoding="utf-8-sig") as f:
            lines = [(n, l) for n, l in enumerate(f, start=1) if l.strip() and not l.lstrip().startswith("#")]
        if not lines:
            raise InputError(f"{name}: no header row")
        head = lines[0][1]
        delimiter = max(",;\t", key=head.count)
        header = [h.strip() for h in next(csv.reader([head], delimiter=delimiter))]
        for need in ("serial", "columns"):
            if need not in header:
                raise InputError(f"{name}:{lines[0][0]}: no column '{need}' (columns: {', '.join(header)})")
        out = []
        for line, text in lines[1:]:
            cells = [c.strip() for c in next(csv.reader([text], delimiter=delimiter))]
            r = dict(zip(header, cells))
            serial, cols = r.get("serial", ""), r.get("columns", "")
            if not serial or not cols:
                raise InputError(f"{os.fspath(units)}:{line}: a unit needs its serial and its columns")
            u: Dict[str, Any] = {"serial": serial, "columns": _columns_of(cols, target)}
            if (r.get("slot") or "").strip():
                u["meta"] = {"slot": r["slot"].strip()}
            u.update(_flags(r.get("options") or ""))
            out.append(u)
    elif isinstance(units, dict):
        out = [{"serial": str(k), "columns": _columns_of(str(v), target)} for k, v in units.items()]
    else:
        entries = units.split(",") if isinstance(units, str) else list(units)
        out = []
        for e in entries:
            serial, _, col = str(e).strip().partition("=")
            col = col or serial
            if not serial.strip() or not col.strip():
                raise InputError(f"units: '{e}': give COLUMN or SERIAL=COLUMN (or a mapping file that exists)")
            out.append({"serial": serial.strip(), "columns": _columns_of(col.strip(), target)})
    seen = set()
    for u in out:
        if u["serial"] in seen:
            raise InputError(f"units: serial '{u['serial']}' given twice")
        seen.add(u["serial"])
    if not out:
        raise InputError("units: no units")
    return out


def _with_unit(options: Dict[str, Any], unit: Dict[str, Any]) -> Dict[str, Any]:
    """The batch's options and a unit's: its slot added to the batch's
    ``meta``; a unit's own option that repeats the batch's is refused, as
    the command line refuses it."""
    from . import InputError

    out = dict(options)
    for k, v in unit.items():
        if k == "meta":
            meta = out.get("meta")
            if meta is None:
                out["meta"] = v
            elif isinstance(meta, dict):
                out["meta"] = {**meta, **v}
            else:
                words = [meta] if isinstance(meta, str) else list(meta)
                out["meta"] = words + [f"{a}={b}" for a, b in v.items()]
        elif k in out:
            raise InputError(f"units: unit {unit['serial']}: {k} is given by the batch too")
        else:
            out[k] = v
    return out


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
    units: Any = None,
    unit_column: str = "output",
    **options: Any,
) -> Batch:
    """Reduce every recording of ``paths`` with ``procedure`` (``"tumble"``,
    ``"imu_ferraris"``, …) and ``options`` (as for ``incal.<procedure>``)
    on Dask: one task per recording; the outcomes in the order of
    ``paths``. One bad recording never stops the batch: it is a
    :class:`FileError` in its place. ``serial_from_stem`` gives each file's
    stem as the instrument serial; ``units`` reduces each unit of a
    fixture's file as its own result (module docs). Progress goes to
    standard error."""
    import json

    from distributed import Client, LocalCluster, as_completed

    from . import Result

    paths = [os.fspath(p) for p in paths]
    function = _function(procedure)
    if "serial" in options and serial_from_stem:
        from . import InputError

        raise InputError("batch: give serial or serial_from_stem, not both")
    jobs: List[Any] = [(p, p, options) for p in paths]
    if units is not None:
        if serial_from_stem or "serial" in options or "columns" in options:
            from . import InputError

            raise InputError("batch: units give each unit's serial and columns: leave out serial, columns and serial_from_stem")
        each = _units(units, unit_column)
        jobs = [(f"{p} [{u['serial']}]", p, _with_unit(options, u)) for p in paths for u in each]
    paths = [j[0] for j in jobs]
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
            client.submit(_task, path, function, opts, serial_from_stem, key=f"incal-{function}-{k}", pure=False)
            for k, (_, path, opts) in enumerate(jobs)
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
    for (p, _, opts), o in zip(jobs, outcomes):
        if o[0] == "ok":
            items.append(Result(json.loads(o[1]), text=o[1]))
            if o[2] is not None:
                stopped[p] = o[2]
        else:
            message = o[2] if units is None else f"{o[2]} (unit {opts['serial']})"
            items.append(FileError(p, message, o[1]))
    ids = None
    if records is not None:
        from .records import Records

        store = records if isinstance(records, Records) else Records(records)
        ids = [None if isinstance(r, FileError) else store.add(r) for r in items]
    return Batch(paths, items, ids, stopped)
