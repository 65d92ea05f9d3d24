"""Calls of the core's typed reductions (``incal._incal._reduce``): the
procedure's options as JSON with its own keys, validated by the core as
the CLI's are; the data as a path, or as columns handed over in place (a
float64 column of a DataFrame or a numpy array is read where it lies, a
column of another numeric dtype converted once; text columns as str).

The document's ``inputs`` records, for data in memory, the SHA-256 of
the columns' canonical byte form (``incal_io::frames``: ``INCALCF1``, the
column count, each column's kind and name, then each row's cells,
numbers as little-endian binary64): the same columns always give the
same hash."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Tuple

from ._incal import _reduce, _reduce_record

#: Keywords of the input layer: ``columns`` (``NAME=HEADER,…``, a dict
#: ``{name: header}`` or a list of names), ``delimiter``, ``header_line``
#: and the segmentation of a rig log (``segment_by``, ``segment_tolerance``,
#: ``segment_settle_s``, ``segment_min_s``, ``segment_values``),
#: ``full_scale`` and a robot log's ``topic`` and ``stamps``.
READ = (
    "columns",
    "delimiter",
    "header_line",
    "segment_by",
    "segment_tolerance",
    "segment_settle_s",
    "segment_min_s",
    "segment_values",
    "full_scale",
    "topic",
    "stamps",
)
#: Keywords added to the document by the core after the reduction (the
#: Monte Carlo's ``monte_carlo``, ``seed`` and ``mc_digits`` among them).
FINISH = ("serial", "model", "meta", "output_unit", "limits", "fail_on", "monte_carlo", "seed", "mc_digits")


def _resolve(prop: Dict[str, Any], schema: Dict[str, Any]) -> Dict[str, Any]:
    ref = prop.get("$ref")
    if isinstance(ref, str) and ref.startswith("#/$defs/"):
        return schema.get("$defs", {}).get(ref[len("#/$defs/") :], {})
    return prop


def _types(prop: Dict[str, Any]) -> List[str]:
    t = prop.get("type", [])
    return [t] if isinstance(t, str) else list(t)


def _value(value: Any, prop: Dict[str, Any], schema: Dict[str, Any]) -> Any:
    """A keyword's value as the JSON the option's schema wants: a tuple
    or array as a list; ``"K0,K1"`` (the CLI's comma list) as a list where
    the option is an array."""
    prop = _resolve(prop, schema)
    for option in prop.get("anyOf", []):
        if {"name", "toml"} <= set(_resolve(option, schema).get("properties", {})) or {
            "name",
            "text",
        } <= set(_resolve(option, schema).get("properties", {})):
            prop = _resolve(option, schema)
    fields = set(prop.get("properties", {}))
    if {"name", "toml"} <= fields and isinstance(value, (str, os.PathLike)):
        return _file(value)
    if {"name", "text"} <= fields:
        return _document(value)
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        value = value.tolist()
    if isinstance(value, tuple):
        value = list(value)
    if "array" in _types(prop) and isinstance(value, str):
        items = _resolve(prop.get("items", {}), schema)
        return [_number(p.strip(), items) for p in value.split(",") if p.strip()]
    if isinstance(value, list):
        items = _resolve(prop.get("items", {}), schema)
        return [_number(v, items) for v in value]
    return _number(value, prop)


def _number(value: Any, prop: Dict[str, Any]) -> Any:
    """A number given as text (``"1e-4"``, as on the command line) as the
    number, where the option is one; anything else unchanged (the core
    names what it refuses)."""
    if not isinstance(value, str):
        return value
    kinds = set(_types(prop))
    try:
        if "integer" in kinds and "number" not in kinds:
            return int(value)
        if kinds & {"number", "integer"}:
            return float(value)
    except ValueError:
        pass
    return value


def _file(path: Any) -> Dict[str, Any]:
    """A file option (the gyro-free unit's ``geometry``) as the core takes
    it: its name and path as given, its SHA-256 and its text."""
    import hashlib

    name, data = document_bytes(os.fspath(path))
    return {"name": name, "path": name, "sha256": hashlib.sha256(data).hexdigest(), "toml": decoded(name, data)}


def _document(value: Any) -> Dict[str, Any]:
    """A result document as an option (centrifuge's ``from_``, gyro
    positions' ``k1_from``): an ``incal.Result`` (its JSON text, named
    ``<Result>``) or a path (the file's name, SHA-256 and text)."""
    from . import InputError, Result

    if isinstance(value, Result):
        return {"name": "<Result>", "text": value.to_json()}
    if isinstance(value, (str, os.PathLike)):
        f = _file(value)
        return {"name": f["name"], "sha256": f["sha256"], "text": f["toml"]}
    raise InputError(f"a result document option takes an incal.Result or a path, not {type(value).__name__}")


def _read_value(key: str, value: Any) -> str:
    if key == "columns" and isinstance(value, dict):
        return ",".join(f"{k}={v}" for k, v in value.items())
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        value = value.tolist()
    if key in ("columns", "segment_values", "topic") and isinstance(value, (list, tuple)):
        return ",".join(repr(float(v)) if key == "segment_values" else str(v) for v in value)
    return str(value)


def _finish_value(key: str, value: Any) -> Any:
    if key == "meta":
        if isinstance(value, dict):
            return [f"{k}={v}" for k, v in value.items()]
        if isinstance(value, str):
            return [value]
        return [str(v) for v in value]
    if key == "limits":
        path = os.fspath(value)
        with open(path, "r", encoding="utf-8") as f:
            return {"name": path, "text": f.read()}
    if key in ("monte_carlo", "seed", "mc_digits"):
        # A number of trials, a seed or digits as the integer the core
        # reads ("auto" stays a word; a bool is not a number).
        if isinstance(value, bool):
            return str(value)
        if isinstance(value, int):
            return value
        text = str(value)
        return int(text) if text.isdigit() else text
    return str(value)


def with_defaults(args: List[Dict[str, Any]], options: Dict[str, Any]) -> Dict[str, Any]:
    """``options`` (by option id) with the command line's default of
    every option not given, as text the schema's conversion reads: a call
    from Python runs with the CLI's defaults, whatever the core's own."""
    out = dict(options)
    for a in args:
        if a["name"] in ("input", "json", "output") or a["flag_only"] or not a["default"]:
            continue
        if out.get(a["name"]) is None:
            out[a["name"]] = ",".join(a["default"])
    return out


def split(schema: Dict[str, Any], options: Dict[str, Any]) -> Optional[Tuple[dict, dict, dict]]:
    """The keywords (by option id) as the procedure's options, the read
    options and the finish options; ``None`` when one is an option only
    the command line has (then the call goes through it)."""
    props = schema.get("properties", {})
    opts: Dict[str, Any] = {}
    read: Dict[str, Any] = {}
    finish: Dict[str, Any] = {}
    for key, value in options.items():
        if value is None:
            continue
        if key in props:
            opts[key] = _value(value, props[key], schema)
        elif key in READ:
            read[key] = _read_value(key, value)
        elif key in FINISH:
            finish[key] = _finish_value(key, value)
        else:
            return None
    return opts, read, finish


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{type(value).__name__} is not an option value")


def column(name: str, values: Any) -> Any:
    """One column for the core: a 1-D C-contiguous float64 array (the
    values in place when they already are; ints, unsigned and float32
    converted; a pandas nullable column with NA as NaN), or a list of str
    for any other dtype (labels)."""
    import numpy as np

    dtype = getattr(values, "dtype", None)
    if dtype is not None and not isinstance(dtype, np.dtype):
        # A pandas extension dtype (Int64, Float64, string, category).
        try:
            import pandas as pd

            if pd.api.types.is_numeric_dtype(dtype) and not pd.api.types.is_bool_dtype(dtype):
                return values.to_numpy(dtype=np.float64, na_value=np.nan)
        except ImportError:
            pass
        return ["" if v is None or v != v else str(v) for v in values.tolist()]
    a = np.asarray(values)
    if a.ndim != 1:
        from . import InputError

        raise InputError(f"column '{name}': an array of {a.ndim} dimensions; give one 1-D array per column")
    if a.dtype.kind in "fiu":
        return np.ascontiguousarray(a, dtype=np.float64)
    return ["" if v is None or v != v else str(v) for v in a.tolist()]


def progress_callback(progress: Any) -> Any:
    """The callable the core reports progress to, ``f(stage, done,
    total)``: ``progress`` itself when callable; for ``True`` a tqdm bar
    per stage (none when tqdm is not installed); ``None`` for ``None`` or
    ``False``."""
    if progress is None or progress is False:
        return None
    if progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return None
        bars: Dict[str, Any] = {}

        def bar(stage: str, done: int, total: int) -> None:
            b = bars.get(stage)
            if b is None:
                b = bars[stage] = tqdm(total=total, desc=stage, leave=False)
            b.update(done - b.n)
            if done >= total:
                b.close()

        return bar
    if callable(progress):
        return progress
    raise TypeError("progress must be a callable f(stage, done, total), True (tqdm) or None")


def data_kwargs(data: Any, arrays: Dict[str, Any]) -> Tuple[str, Dict[str, Any]]:
    """The data's name in documents and messages, and the ``path=`` or
    ``columns=`` argument of the compiled functions."""
    from . import InputError

    if data is not None and arrays:
        raise InputError("give the data as one path or DataFrame, or as arrays by keyword, not both")
    if data is None:
        if not arrays:
            raise InputError("no data: give a path, a DataFrame, or arrays by keyword")
        return "<arrays>", {"columns": [(str(k), column(str(k), v)) for k, v in arrays.items()]}
    if isinstance(data, dict):
        return "<arrays>", {"columns": [(str(k), column(str(k), v)) for k, v in data.items()]}
    if isinstance(data, (str, os.PathLike)):
        return os.fspath(data), {"path": os.fspath(data)}
    if hasattr(data, "columns") and hasattr(data, "__getitem__"):
        return "<DataFrame>", {"columns": [(str(c), column(str(c), data[c])) for c in data.columns]}
    raise InputError(
        f"data must be a path, a DataFrame, a dict of arrays or arrays by keyword, not {type(data).__name__}"
    )


def document_bytes(value: Any) -> Tuple[str, bytes]:
    """A result document given as an ``incal.Result`` (named
    ``<Result>``, its JSON text) or a path: its name and bytes."""
    from . import InputError, Result

    if isinstance(value, Result):
        return "<Result>", value.to_json().encode()
    name = os.fspath(value)
    try:
        with open(name, "rb") as f:
            return name, f.read()
    except OSError as e:
        raise InputError(f"{name}: cannot read: {e}", {"file": name}) from None


def decoded(name: str, data: bytes) -> str:
    """A file's bytes as text (UTF-8, a byte-order mark dropped); bytes
    that are not UTF-8 are refused naming the file, as the CLI refuses
    them."""
    from . import InputError

    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{name}: not UTF-8 text", {"file": name}) from None


def document_text(value: Any) -> Tuple[str, str]:
    """As :func:`document_bytes`, the text (:func:`decoded`)."""
    name, data = document_bytes(value)
    return name, decoded(name, data)


def call(
    procedure: str,
    data: Any,
    arrays: Dict[str, Any],
    opts: Dict[str, Any],
    read: Dict[str, Any],
    finish: Dict[str, Any],
    progress: Any = None,
) -> Tuple[int, bytes, List[str], Dict[str, Any]]:
    """Run the typed reduction: (code, document, error lines, where)."""
    name, kwargs = data_kwargs(data, arrays)
    code, out, err, where = _reduce(
        procedure,
        name,
        json.dumps(opts, default=_json_default),
        json.dumps(read),
        json.dumps(finish),
        progress=progress_callback(progress),
        **kwargs,
    )
    return code, bytes(out), list(err), json.loads(where)


def call_record(
    record: Any,
    channels: int,
    f64le: bool,
    opts: Dict[str, Any],
    read: Dict[str, Any],
    finish: Dict[str, Any],
    path: Any = None,
    progress: Any = None,
) -> Tuple[int, bytes, List[str], Dict[str, Any]]:
    """Run the noise analysis of a binary record: ``record`` (a uint8
    view of the samples, read in place) or the file at ``path``."""
    code, out, err, where = _reduce_record(
        json.dumps(opts, default=_json_default),
        json.dumps(read),
        json.dumps(finish),
        channels,
        f64le,
        record=record,
        path=None if path is None else os.fspath(path),
        progress=progress_callback(progress),
    )
    return code, bytes(out), list(err), json.loads(where)
