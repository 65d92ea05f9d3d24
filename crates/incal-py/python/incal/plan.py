"""Test plans before the test: ``incal.plan.tumble(k1=10, noise=1e-6)``
returns the plan document (``incal.plan/1``) as a dict, with the predicted
u of every coefficient. Options as ``incal plan <name> --help`` lists them,
``_`` for ``-``; each function has its command's signature. One function
per plan of the procedure registry (``incal.REGISTRY``), run by the core's
typed plan (the plans by simulation, IMU and noise, take the session's
keywords and derive the reduction's options from them as the CLI does);
``run_sheet=PATH`` also writes the operator's run sheet (CSV)."""

from __future__ import annotations

import json
from typing import Any, Dict, List

from . import REGISTRY, _by_id, _keyword_ids, _options_doc, _raise, _signature

__all__: List[str] = []


def _nest(schema: Dict[str, Any], options: Dict[str, Any]) -> Dict[str, Any]:
    """Flat keywords into the plan's options: a key of a nested options
    object (an IMU plan's ``session``, a noise plan's ``reduce``) goes
    into it, as the command line's flat options do."""
    from ._typed import _resolve, _value

    props = schema.get("properties", {})
    out: Dict[str, Any] = {}
    nested = {k: _resolve(p, schema) for k, p in props.items() if "properties" in _resolve(p, schema)}
    for key, value in options.items():
        if value is None:
            continue
        if key in props and key not in nested:
            out[key] = _value(value, props[key], schema)
            continue
        for name, sub in nested.items():
            if key in sub["properties"]:
                out.setdefault(name, {})[key] = _value(value, sub["properties"][key], schema)
                break
        else:
            out[key] = value  # the core names what it does not know
    return out


def _plan(entry: Dict[str, Any], name: str):
    args = (entry.get("arguments") or {}).get("plan") or []
    schema = (entry.get("options") or {}).get("plan")
    ids = _keyword_ids(args)
    words = entry["plan"].split()[1:]

    def plan(**options: Any) -> Dict[str, Any]:
        from ._incal import _plan as typed
        from ._incal import _run_sheet
        from ._typed import with_defaults

        by_id = _by_id(name, args, ids, ids, options)
        sheet = by_id.pop("run_sheet", None)
        code, out, err, where = typed(entry["id"], json.dumps(_nest(schema or {}, with_defaults(args, by_id))))
        if code != 0:
            _raise(code, bytes(out), list(err), json.loads(where))
        if sheet is not None:
            code, csv, message = _run_sheet(bytes(out).decode())
            if code != 0:
                _raise(code, b"", [f"run_sheet: {message}" if code == 2 else message], {"option": "run_sheet"})
            import os

            with open(os.fspath(sheet), "w", encoding="utf-8", newline="") as f:
                f.write(csv)
        return json.loads(bytes(out))

    plan.__name__ = name
    plan.__qualname__ = name
    plan.__doc__ = f"The plan document of ``incal plan {' '.join(words)}``."
    if args:
        plan.__signature__ = _signature(args, data=False)  # type: ignore[attr-defined]
        plan.__doc__ += " Options (keywords):\n\n" + _options_doc(args)
    return plan


for _entry in REGISTRY:
    _name = _entry["python"]["plan"]
    if _name and _name not in __all__:
        globals()[_name] = _plan(_entry, _name)
        __all__.append(_name)
del _entry, _name
