"""Simulators with a known truth: ``data, truth = incal.simulate.tumble(seed=7)``
gives the recording as a pandas DataFrame (the CSV that ``incal simulate``
writes, numbers read back bit for bit) and the simulator's ``# …`` lines
(the truth and how it was simulated) as a list of strings. Options as
``incal simulate <name> --help`` lists them, ``_`` for ``-``."""

from __future__ import annotations

from typing import Any, List, Tuple

from . import REGISTRY, _options, _read_csv, run

__all__: List[str] = []


def _frame(csv: bytes):
    notes = [l[1:].strip() for l in csv.decode().splitlines() if l.startswith("#")]
    return _read_csv(csv), notes


def _simulator(words: List[str], name: str):
    def simulate(**options: Any) -> Tuple[Any, List[str]]:
        if words in (["gfimu"], ["thermal"]):
            # The gyro-free unit's truth is written beside the CSV (the
            # CSV holds rows only): read back from a temporary file.
            import json
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
        out, _ = run(["simulate"] + words + _options(options))
        return _frame(out)

    simulate.__name__ = name
    simulate.__doc__ = f"``incal simulate {' '.join(words)}``: (DataFrame, truth lines)."
    return simulate


# One function per simulator command of the procedure registry
# (``incal.REGISTRY``): ``incal simulate misalign gyro`` is
# ``incal.simulate.misalign_gyro``.
for _entry in REGISTRY:
    _name = _entry["python"]["simulate"]
    if _name and _name not in __all__:
        globals()[_name] = _simulator(_entry["simulate"].split()[1:], _name)
        __all__.append(_name)
del _entry, _name

thermal = globals()["thermal"]
thermal.__doc__ = (
    "``incal simulate thermal``: (DataFrame with time_s, chamber_c, temperature_c and the "
    "channels, truth dict: t_ref_c, lag_s, unit and per channel c, hysteresis, noise)."
)
