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

from . import Result, run

__all__ = ["Records"]


def _document(result: Any) -> bytes:
    if isinstance(result, Result):
        return result.to_json().encode()
    with open(os.fspath(result), "rb") as f:
        return f.read()


class Records:
    """A records store: ``location`` is a file path or a ``postgresql://``
    URL (the ``--db`` of ``incal record``)."""

    def __init__(self, location: Any):
        self.location = os.fspath(location) if not isinstance(location, str) else location

    def _run(self, words: List[str], stdin: Optional[bytes] = None) -> bytes:
        out, _ = run(["record"] + words + ["--db", self.location], stdin)
        return out

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
        words = ["add", "-", "--json"]
        for flag, value in [
            ("--serial", serial),
            ("--operator", operator),
            ("--station", station),
            ("--created-utc", created_utc),
        ]:
            if value is not None:
                words += [flag, value]
        return json.loads(self._run(words, _document(result)))["id"]

    def supersede(self, record_id: int, result: Any, reason: str) -> int:
        """Correct record ``record_id`` with a new result and a reason."""
        words = ["supersede", str(record_id), "-", "--reason", reason, "--json"]
        return json.loads(self._run(words, _document(result)))["id"]

    def list(self, serial: Optional[str] = None) -> List[Dict[str, Any]]:
        """Every record (of ``serial`` only, when given), by id."""
        words = ["list", "--json"] + (["--serial", serial] if serial else [])
        return json.loads(self._run(words))["records"]

    def show(self, record_id: int) -> Dict[str, Any]:
        """One record: its identity and the stored result under ``result``."""
        return json.loads(self._run(["show", str(record_id), "--json"]))

    def history(self, serial: str, coefficient: str) -> Dict[str, Any]:
        """One coefficient across the instrument's calibrations, with drift."""
        words = ["history", "--serial", serial, "--coefficient", coefficient, "--json"]
        return json.loads(self._run(words))

    def verify(self, head: Optional[str] = None) -> Dict[str, Any]:
        """Recompute the hash chain: ``{"records", "head"}``; a broken chain
        raises :class:`incal.IncalError` naming the first bad record."""
        words = ["verify", "--json"] + (["--head", head] if head else [])
        return json.loads(self._run(words))

    def export(self, path: Any) -> None:
        """Write every record as JSON lines (``incal record export``)."""
        self._run(["export", "-o", os.fspath(path)])

    def import_(self, path: Any) -> Dict[str, Any]:
        """Append the records of an export, all or none
        (``incal record import``): ``{"added", "present", "chain"}``."""
        return json.loads(self._run(["import", os.fspath(path), "--json"]))

    def __repr__(self) -> str:
        return f"<incal.Records {self.location!r}>"
