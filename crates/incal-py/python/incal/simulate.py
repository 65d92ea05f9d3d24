"""Simulators with a known truth: ``data, truth = incal.simulate.tumble(seed=7)``
gives the recording as a pandas DataFrame (the CSV that ``incal simulate``
writes, numbers read back bit for bit) and the simulator's ``# …`` lines
(the truth and how it was simulated) as a list of strings. Options as
``incal simulate <name> --help`` lists them, ``_`` for ``-``; each
function has its command's signature. Run by the core's typed simulator
(the gyro-free unit's and the thermal chamber's truth, written beside the
CSV, through the command line)."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Tuple

from . import REGISTRY, _by_id, _keyword_ids, _options, _options_doc, _raise, _read_csv, _signature, run

__all__: List[str] = []


def _frame(csv: bytes):
    notes = [l[1:].strip() for l in csv.decode().splitlines() if l.startswith("#")]
    return _read_csv(csv), notes


def _simulator(entry: Dict[str, Any], name: str):
    words = entry["simulate"].split()[1:]
    args = (entry.get("arguments") or {}).get("simulate") or []
    schema = (entry.get("options") or {}).get("simulate")
    ids = _keyword_ids(args)

    def simulate(**options: Any) -> Tuple[Any, Any]:
        by_id = _by_id(name, args, ids, ids, options)
        if words in (["gfimu"], ["thermal"]):
            return _with_truth(words, by_id)
        if schema is not None:
            from ._incal import _simulate as typed
            from ._typed import split

            from ._typed import with_defaults

            parts = split(schema, with_defaults(args, by_id))
            if parts is not None and not parts[1] and not parts[2]:
                code, out, err, where = typed(entry["id"], json.dumps(parts[0]))
                if code != 0:
                    _raise(code, bytes(out), list(err), json.loads(where))
                return _frame(bytes(out))
        out, _ = run(["simulate"] + words + _options(by_id))
        return _frame(out)

    simulate.__name__ = name
    simulate.__qualname__ = name
    simulate.__doc__ = f"``incal simulate {' '.join(words)}``: (DataFrame, truth lines)."
    if args:
        simulate.__signature__ = _signature(args, data=False)  # type: ignore[attr-defined]
        simulate.__doc__ += " Options (keywords):\n\n" + _options_doc(args)
    return simulate


def _with_truth(words: List[str], options: Dict[str, Any]) -> Tuple[Any, Any]:
    """The gyro-free unit's and the thermal chamber's simulators write
    their truth beside the CSV (the CSV holds rows only): read back from
    a temporary file."""
    import os
    import tempfile

    fd, path = tempfile.mkstemp(suffix=".json")
    os.close(fd)
    try:
        out, _ = run(["simulate"] + words + _options(options) + ["--truth-out", path])
        with open(path) as f:
            truth = json.load(f)
        notes = truth["notes"] if words == ["gfimu"] else truth
    finally:
        os.unlink(path)
    return _read_csv(out), notes


# One function per simulator of the procedure registry
# (``incal.REGISTRY``): ``incal simulate misalign gyro`` is
# ``incal.simulate.misalign_gyro``.
for _entry in REGISTRY:
    _name = _entry["python"]["simulate"]
    if _name and _name not in __all__:
        globals()[_name] = _simulator(_entry, _name)
        __all__.append(_name)
del _entry, _name

thermal = globals()["thermal"]
thermal.__doc__ = (
    "``incal simulate thermal``: (DataFrame with time_s, chamber_c, temperature_c and the "
    "channels, truth dict: t_ref_c, lag_s, unit and per channel c, hysteresis, noise)."
)
