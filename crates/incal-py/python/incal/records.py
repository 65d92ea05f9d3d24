"""Calibration records from Python: ``incal.Records(location)`` is the
store of ``incal record …`` (an SQLite file, or a PostgreSQL database given
as ``postgresql://user@host:port/db``), with the same append-only hash
chain, the same checks and the same one-line errors.

>>> store = incal.Records("lab.db")
>>> store.add(result)            # the record id
>>> store.verify()               # {"records": n, "head": "…"}
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional

from . import Result, _raise

__all__ = ["Records"]


def _document(result: Any) -> Dict[str, str]:
    """A result to store: its name in messages and its text."""
    from . import _typed

    name, text = _typed.document_text(result)
    return {"name": name, "text": text}


class Records:
    """A records store: ``location`` is a file path or a ``postgresql://``
    URL (the ``--db`` of ``incal record``). Every method calls the records
    crate directly (the same checks, hash chain, JSON and errors as
    ``incal record``), with the GIL released."""

    def __init__(self, location: Any):
        self.location = os.fspath(location) if not isinstance(location, str) else location

    def _call(self, op: str, **args: Any) -> Any:
        from ._incal import _records

        code, out, err = _records(self.location, op, json.dumps({k: v for k, v in args.items() if v is not None}))
        if code != 0:
            _raise(code, b"", [err])
        return json.loads(out)

    def add(
        self,
        result: Any,
        serial: Optional[str] = None,
        operator: Optional[str] = None,
        station: Optional[str] = None,
        created_utc: Optional[str] = None,
    ) -> int:
        """Store a result (``Result`` or path) as a new record; its id. The
        same document already stored for the instrument is that record
        (nothing is stored twice)."""
        return self._call(
            "add", serial=serial, operator=operator, station=station, created_utc=created_utc, **_document(result)
        )["id"]

    def supersede(self, record_id: int, result: Any, reason: str) -> int:
        """Correct record ``record_id`` with a new result and a reason."""
        return self._call("supersede", id=int(record_id), reason=reason, **_document(result))["id"]

    def list(self, serial: Optional[str] = None) -> List[Dict[str, Any]]:
        """Every record (of ``serial`` only, when given), by id."""
        return self._call("list", serial=serial)["records"]

    def show(self, record_id: int) -> Dict[str, Any]:
        """One record: its identity and the stored result under ``result``."""
        return self._call("show", id=int(record_id))

    def history(self, serial: str, coefficient: str, procedure: Optional[str] = None) -> Dict[str, Any]:
        """One coefficient across the instrument's calibrations, with drift
        (of ``procedure`` only, when given)."""
        return self._call("history", serial=serial, coefficient=coefficient, procedure=procedure)

    def verify(self, head: Optional[str] = None) -> Dict[str, Any]:
        """Recompute the hash chain: ``{"records", "head"}``; a broken chain
        raises :class:`incal.IncalError` naming the first bad record."""
        return self._call("verify", head=head)

    def export(self, path: Any) -> Dict[str, Any]:
        """Write every record as JSON lines (``incal record export``):
        ``{"records", "head"}`` of the chain exported."""
        return self._call("export", path=os.fspath(path))

    def import_(self, path: Any) -> Dict[str, Any]:
        """Append the records of an export, all or none
        (``incal record import``): ``{"added", "present", "chain"}``."""
        return self._call("import", path=os.fspath(path))

    def __repr__(self) -> str:
        return f"<incal.Records {self.location!r}>"
