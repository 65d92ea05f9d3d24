"""Simulators with a known truth: ``data, truth = incal.simulate.tumble(seed=7)``
gives the recording as a pandas DataFrame (the CSV that ``incal simulate``
writes, numbers read back bit for bit) and the simulator's ``# …`` lines
(the truth and how it was simulated) as a list of strings. Options as
``incal simulate <name> --help`` lists them, ``_`` for ``-``; each
function has its command's signature. Run by the core's typed simulator;
the gyro-free unit's and the thermal chamber's truth, which their CSV does
not carry, is the core's truth value (``truth_out=PATH`` also writes it
as ``--truth-out`` does)."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Tuple

from . import REGISTRY, InputError, _by_id, _keyword_ids, _options_doc, _raise, _read_csv, _signature

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
        from ._incal import _simulate as typed
        from ._typed import split, with_defaults

        by_id = _by_id(name, args, ids, ids, options)
        truth_out = by_id.pop("truth_out", None)
        if by_id.get("format") not in (None, "csv"):
            raise InputError("format: a simulator in Python gives a DataFrame (csv)", {"option": "format"})
        parts = split(schema or {}, with_defaults(args, by_id))
        if parts is None or parts[1] or parts[2]:
            unknown = sorted(set(by_id) - set((schema or {}).get("properties", {})))
            raise TypeError(f"{name}() got an unexpected keyword argument among {unknown}")
        code, out, err, where, truth_text = typed(entry["id"], json.dumps(parts[0]))
        if code != 0:
            _raise(code, bytes(out), list(err), json.loads(where))
        truth = json.loads(truth_text)
        if truth_out is not None and truth is not None:
            import os

            with open(os.fspath(truth_out), "w", encoding="utf-8") as f:
                f.write(json.dumps(truth, indent=2, ensure_ascii=False) + "\n")
        data, notes = _frame(bytes(out))
        # The truth: the CSV's notes where it carries them, else the core's
        # truth value (its notes, or the truth as a dict).
        if notes or not isinstance(truth, dict):
            return data, notes
        return data, truth.get("notes", truth)

    simulate.__name__ = name
    simulate.__qualname__ = name
    simulate.__doc__ = f"``incal simulate {' '.join(words)}``: (DataFrame, truth lines)."
    if args:
        simulate.__signature__ = _signature(args, data=False)  # type: ignore[attr-defined]
        simulate.__doc__ += " Options (keywords):\n\n" + _options_doc(args)
    return simulate


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
