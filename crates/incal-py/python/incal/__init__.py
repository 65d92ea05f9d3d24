"""incal in Python: the calibration procedures of the incal CLI as functions.

Every function runs the same code as the ``incal`` command of the same name,
in process (the GIL released while the core computes), so the result
document equals the CLI's ``--json`` output for the same data and options.

>>> import incal
>>> data, truth = incal.simulate.tumble(seed=7)
>>> r = incal.tumble(data, mount="pendulum")
>>> round(r.coefficients["K1"]["value"], 4)
10.0

Data is a path (``str`` or ``os.PathLike``), a pandas ``DataFrame`` with
incal's column names (or any frame whose columns convert to numpy
arrays, such as polars'), a dict of 1-D arrays (``{"angle_deg": a,
"output": y}``), or numpy arrays given by keyword (one per column:
``incal.tumble(angle_deg=a, output=y, mount="pendulum")``; type checkers
know the options' names, so typed code gives arrays as a dict). Columns
in memory are handed to the core in place, without a text round trip,
and rows are numbered from 0 in messages. Options are
keyword arguments named as the CLI options with ``_`` for ``-``
(``gravity_m_s2=9.80665``); ``True`` gives a flag, a list or tuple a
comma-separated value. Errors raise :class:`InputError` (bad data or
options, the CLI's exit 2) or :class:`IncalError`, with the CLI's one-line
message. The warnings of a result are raised as Python warnings, each code
its own category (:mod:`incal.warnings`: ``incal.warnings.LackOfFit``, …,
subclasses of :class:`IncalWarning`).
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple

from ._incal import _version
from .warnings import IncalWarning, warn_all as _warn_all

__version__ = _version()

__all__ = [
    "IncalError",
    "InputError",
    "IncalWarning",
    "Coefficient",
    "Result",
    "thermal_fit",
    "thermal_apply",
    "export_thermal",
    "mag_apply",
    "export_mag",
    "read_result",
    "compare",
    "apply",
    "export_kalibr",
    "export_px4",
    "export_vins",
    "export_orbslam3",
    "export_openvins",
    "export_basalt",
    "plan",
    "simulate",
    "batch",
    "Records",
    "run",

]


class IncalError(Exception):
    """A command failed (the CLI's exit 1), or stopped after writing its
    output (exit 3: ``fail_on`` met by a verdict or a comparison, or a
    record stored whose output could not be written). ``code`` is the
    CLI's exit code; ``output`` what the command wrote before it stopped
    (the result document of a ``fail_on`` stop: ``incal.Result`` of it is
    ``error.result``)."""

    def __init__(self, message: str, code: int = 1, output: bytes = b""):
        super().__init__(message)
        self.code = code
        self.output = output

    @property
    def result(self) -> "Optional[Result]":
        """The result written before a ``fail_on`` stop, if any."""
        try:
            doc = json.loads(self.output)
        except ValueError:
            return None
        return Result(doc, text=self.output.decode()) if isinstance(doc, dict) and "schema" in doc else None


class InputError(IncalError, ValueError):
    """Bad data or options (the CLI's exit 2): the message names the file,
    line and column, or the option. The attributes say the same for a
    program (``None`` where the message names none): ``file`` (the path as
    given), ``line`` (1-based, the header is line 1), ``column`` (the
    column's name), ``option`` (the keyword, ``rate_hz``)."""

    def __init__(self, message: str, where: Optional[Dict[str, Any]] = None):
        super().__init__(message, 2)
        self.file: Optional[str] = None
        self.line: Optional[int] = None
        self.column: Optional[str] = None
        self.option: Optional[str] = None
        self._parse(message)
        # What the core says of where (typed calls) wins over the parse.
        for key, value in (where or {}).items():
            if value is not None:
                setattr(self, key, value)

    def _parse(self, message: str) -> None:
        """Read the attributes from the one-line message's documented
        forms: ``FILE:LINE: column 'NAME': …``, ``FILE: missing column
        'NAME' …``, ``FILE: cannot read …``, ``--option: …``, ``invalid
        value … for '--option …'``, ``unknown option '--option'``."""
        import re

        m = re.match(r"--([a-z0-9][a-z0-9-]*)(?:: | )", message)
        if m is None:
            m = re.search(r"'--([a-z0-9][a-z0-9-]*)[ ']", message)
        if m is not None:
            self.option = m.group(1).replace("-", "_")
            return
        m = re.match(r"(.+?):(\d+): (?:column '([^']*)': )?", message)
        if m is not None:
            self.file, self.line, self.column = m.group(1), int(m.group(2)), m.group(3)
            return
        m = re.match(r"(.+?): (?:missing column '([^']*)'|cannot read|not valid|no column)", message)
        if m is not None:
            self.file, self.column = m.group(1), m.group(2)


def run(words: Sequence[str], stdin: Optional[bytes] = None) -> Tuple[bytes, List[str]]:
    """Run the ``incal`` command line ``words`` (without ``incal``): the
    program named by ``$INCAL_BIN``, else ``incal`` on the ``PATH`` (the
    package itself never needs it). Returns its standard output and its
    standard-error lines (warnings); a failure raises :class:`InputError`
    (exit 2) or :class:`IncalError`."""
    import shutil
    import subprocess

    program = os.environ.get("INCAL_BIN") or shutil.which("incal")
    if not program:
        raise IncalError("incal.run: no incal program (set INCAL_BIN or put incal on the PATH)", 1, b"")
    done = subprocess.run([program] + [str(w) for w in words], input=stdin, capture_output=True)
    err = done.stderr.decode("utf-8", "replace").splitlines()
    if done.returncode != 0:
        message = err[-1] if err else f"incal exited with code {done.returncode}"
        if done.returncode == 2:
            raise InputError(message)
        raise IncalError(message, done.returncode, done.stdout)
    return done.stdout, err


def _is_array(value: Any) -> bool:
    """A data column given by keyword: a numpy array or pandas Series (not
    a list or tuple, which are option values)."""
    return hasattr(value, "__array__") and not isinstance(value, (list, tuple, str))


class Coefficient(dict):
    """One coefficient of a result: a dict of the document's fields
    (``value``, ``u``, ``unit``, ``dof``, ``k95``, ``U95``; JSON units) that
    also reads them as attributes: ``r.coefficients["K1"].u``."""

    @property
    def value(self) -> float:
        """The estimate."""
        return self["value"]

    @property
    def u(self) -> float:
        """Its standard uncertainty (same unit)."""
        return self["u"]

    @property
    def U95(self) -> float:
        """Its expanded uncertainty for 95 % coverage, ``k95 · u``."""
        return self["U95"]

    @property
    def k95(self) -> float:
        """The coverage factor (Student t with ``dof``)."""
        return self["k95"]

    @property
    def dof(self) -> Optional[float]:
        """Effective degrees of freedom of ``u`` (``None``: infinite)."""
        return self.get("dof")

    @property
    def unit(self) -> str:
        """The unit of ``value``, ``u`` and ``U95``."""
        return self["unit"]


class Result:
    """A result document (``incal.result/1``) and its views."""

    def __init__(
        self,
        document: Dict[str, Any],
        warnings: Optional[List[str]] = None,
        text: Optional[str] = None,
    ):
        #: The result document as a dict: the CLI's ``--json`` output.
        self.document = document
        #: Warnings the command wrote on standard error (streaming commands).
        self.warnings = warnings or []
        # The document's text as the CLI wrote it: written back unchanged,
        # so a file from Python is byte for byte the CLI's (and a records
        # store recognises it as the same document).
        self._text = text

    @property
    def coefficients(self) -> Dict[str, Coefficient]:
        """Name → :class:`Coefficient` (``{"value", "u", "unit", "dof",
        "k95", "U95"}`` in JSON units, also as attributes: ``.value``,
        ``.u``, ``.U95``, ``.dof``, ``.unit``)."""
        return {k: Coefficient(v) for k, v in self.document.get("coefficients", {}).items()}

    def table(self, id: str):
        """The document's table ``id`` (``positions``, ``terms``, …) as a
        pandas DataFrame: one column per table column, named ``name`` or
        ``name [unit]``; an unknown id raises :class:`KeyError` naming the
        ids there are."""
        import pandas as pd

        tables = self.document.get("tables", [])
        for t in tables:
            if t.get("id") == id:
                names = [c["name"] if not c.get("unit") else f"{c['name']} [{c['unit']}]" for c in t["columns"]]
                return pd.DataFrame(t["rows"], columns=names)
        raise KeyError(f"no table '{id}' (tables: {', '.join(t.get('id', '?') for t in tables)})")

    @property
    def procedure(self) -> str:
        return self.document["procedure"]

    def to_json(self, path: Optional[str] = None) -> str:
        """The document as JSON text (written to ``path`` when given)."""
        if self._text is not None and json.loads(self._text) == self.document:
            text = self._text
        else:
            text = json.dumps(self.document, indent=2) + "\n"
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        return text

    def to_dataframe(self):
        """The coefficients as a pandas DataFrame, one row per coefficient."""
        import pandas as pd

        rows = [dict(name=k, **v) for k, v in self.coefficients.items()]
        cols = ["name", "value", "u", "U95", "dof", "k95", "unit"]
        return pd.DataFrame(rows, columns=cols).set_index("name")

    def report(
        self,
        path: str,
        limits: Optional[str] = None,
        db: Optional[str] = None,
        lab: Optional[str] = None,
        customer: Optional[str] = None,
        date: Optional[str] = None,
        environment: Optional[str] = None,
        pdf: bool = False,
    ) -> str:
        """Write the HTML report (printable certificate) to ``path`` by the
        report crate, as ``incal report``: judged against ``limits`` (a
        limits file) when given; with ``db`` (a records store's path or
        URL) the record's stamp and the history plots; with ``lab`` (a
        laboratory profile, TOML) a calibration certificate naming
        ``customer``, the calibration ``date`` (YYYY-MM-DD; default the day
        the record was stored) and the ``environment``; with ``pdf`` also
        printed to ``path`` with ``.pdf`` by headless Chromium (an
        :class:`IncalError` naming why when it cannot be, the HTML kept).
        Returns ``path``."""
        from . import _typed
        from ._incal import _report

        finish = {"limits": _typed._finish_value("limits", limits)} if limits is not None else {}
        profile = None
        if lab is not None:
            name, data = _typed.document_bytes(lab)
            profile = _typed.decoded(name, data)
        issue = {"customer": customer, "date": date, "environment": environment}
        location = os.fspath(db) if db is not None else None
        code, html, err = _report(self.to_json(), json.dumps(finish), location, profile, json.dumps(issue))
        if code != 0:
            _raise(code, b"", [err])
        with open(os.fspath(path), "w", encoding="utf-8") as f:
            f.write(html)
        if pdf:
            from ._incal import _pdf

            code, _, err = _pdf(os.fspath(path))
            if code != 0:
                _raise(code, b"", [err])
        return os.fspath(path)

    def to_imucal(self, path: Optional[str] = None) -> Dict[str, Any]:
        """An ``imu_ferraris``, ``imu_multipos`` or ``imu_autocal`` result as
        imucal's calibration JSON (``incal export imucal``), which imucal's
        ``load_calibration_info`` loads; written to ``path`` when given."""
        out = _export("imucal", [self], {})
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(out)
        return json.loads(out)

    def figures(self) -> List[str]:
        """The certificate's plots (residuals with ±U95, deviations,
        coefficients against their limits) as SVG texts."""
        from ._incal import _figures

        return list(_figures(self.to_json()))

    def _repr_html_(self) -> str:
        """The coefficient table and the certificate's plots inline (SVG),
        as a notebook shows a result."""
        import html

        head = "".join(f"<th>{h}</th>" for h in ["name", "value", "u", "U95", "dof", "unit"])
        rows = []
        for name, c in self.coefficients.items():
            cells = [name] + [c.get(k) for k in ["value", "u", "U95", "dof", "unit"]]
            rows.append("<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in cells) + "</tr>")
        title = html.escape(self.document.get("title", self.procedure))
        try:
            plots = "".join(f"<div>{svg}</div>" for svg in self.figures())
        except ValueError:
            plots = ""  # a document changed by hand into one that is not valid
        return f"<p><b>{title}</b></p><table><tr>{head}</tr>{''.join(rows)}</table>{plots}"

    def __repr__(self) -> str:
        return f"<incal.Result {self.procedure}: {len(self.coefficients)} coefficients>"


def _read_csv(csv: bytes):
    """A CSV text as incal writes it into a pandas DataFrame, every number
    read back bit for bit (pandas before 3 needs ``round_trip`` for that);
    ``#`` lines skipped."""
    import io

    import pandas as pd

    text = "\n".join(l for l in csv.decode().splitlines() if not l.startswith("#"))
    if int(pd.__version__.split(".")[0]) < 3:
        return pd.read_csv(io.StringIO(text), float_precision="round_trip")
    return pd.read_csv(io.StringIO(text))


def _noise_record(arrays: Dict[str, Any], opts: Dict[str, Any], read: Dict[str, Any]) -> Any:
    """Noise channels given as numpy arrays, as one binary record read by
    the core in place: the record (a uint8 view of the samples' bytes),
    its channel count and sample width, with ``opts`` and ``read`` set to
    read it (``format``, ``channels``, ``columns`` naming each channel).
    One float64 (or float32) C-contiguous 1-D array is not copied; several
    channels are interleaved into one array (one copy, no text). ``None``
    when the arrays do not fit (a ``time_s`` column, non-numeric data,
    ``format``, ``channels`` or ``columns`` given, a big-endian machine):
    the arrays are then read as columns."""
    import sys

    import numpy as np

    names = list(arrays)
    if "time_s" in names or sys.byteorder != "little":
        return None
    if opts.get("format", "csv") != "csv" or opts.get("channels") is not None or "columns" in read:
        return None
    columns = [np.asarray(arrays[k]) for k in names]
    if any(a.ndim != 1 or a.dtype.kind not in "fiu" for a in columns):
        return None
    n = len(columns[0])
    for name, a in zip(names, columns):
        if len(a) != n:
            raise InputError(f"column '{name}' has {len(a)} values, '{names[0]}' has {n}")
    dtype = np.float32 if all(a.dtype == np.float32 for a in columns) else np.float64
    if len(columns) == 1:
        data = np.ascontiguousarray(columns[0], dtype=dtype)  # no copy when it already is
    else:
        data = np.column_stack([a.astype(dtype, copy=False) for a in columns])
    opts["format"] = "f32le" if dtype == np.float32 else "f64le"
    opts["channels"] = len(names)
    read["columns"] = ",".join(f"{k}=ch{i + 1}" for i, k in enumerate(names))
    return data.reshape(-1).view(np.uint8), len(names), dtype == np.float64


def _result(out: bytes, err: List[str]) -> Result:
    """The result document a command wrote, its warnings raised as Python
    warnings of their category (:mod:`incal.warnings`)."""
    r = Result(json.loads(out), err, out.decode())
    _warn_all(r.document.get("warnings", []))
    return r


def _noise_positional(data: Any, options: Dict[str, Any]) -> Any:
    """``incal.noise(y, rate_hz=…)`` as allantools is called: a 1-D numpy
    array is one channel (``ch1``), a 2-D array one channel per column
    (``ch1``, ``ch2``, …), given to the in-place path as arrays by keyword.
    Returns the data left for the other paths (``None`` when taken)."""
    if data is None or isinstance(data, (str, os.PathLike)) or hasattr(data, "columns"):
        return data
    if not _is_array(data):
        return data
    import numpy as np

    a = np.asarray(data)
    if a.ndim == 1:
        columns = {"ch1": a}
    elif a.ndim == 2:
        columns = {f"ch{k + 1}": a[:, k] for k in range(a.shape[1])}
    else:
        raise InputError(f"noise: an array of {a.ndim} dimensions; give one channel (1-D) or one per column (2-D)")
    clash = [k for k in columns if k in options]
    if clash:
        raise InputError(f"noise: channel '{clash[0]}' given twice (positionally and by keyword)")
    options.update(columns)
    return None


def _raise(code: int, out: bytes, err: List[str], where: Optional[Dict[str, Any]] = None) -> None:
    message = err[-1] if err else f"incal exited with code {code}"
    if code == 2:
        raise InputError(message, where)
    raise IncalError(message, code, out)


def _reduce(entry: Dict[str, Any], data: Any, options: Dict[str, Any]) -> Result:
    """Reduce ``data`` by the registry entry with ``options`` (keyed by
    option id) through the core's typed reduction, the data in place (a
    path, columns, or for noise a binary record). Every option of the
    command has a place there: the procedure's options, the input layer's
    (``columns``, ``delimiter``) and the identity, unit and limits."""
    from . import _typed

    command = entry["command"].split()
    options = dict(options)
    progress = options.pop("progress", None)
    if command == ["noise"]:
        data = _noise_positional(data, options)
        # The library prints no progress; `sequential` is the core's
        # `parallel` turned round.
        options.pop("quiet", None)
        if options.pop("sequential", False):
            options["parallel"] = False
    schema = (entry.get("options") or {}).get("reduce")
    arrays = {k: options.pop(k) for k in list(options) if _is_array(options[k])}
    args = (entry.get("arguments") or {}).get("reduce") or []
    parts = _typed.split(schema or {}, _typed.with_defaults(args, options))
    if parts is None:
        unknown = sorted(set(options) - set((schema or {}).get("properties", {})))
        raise TypeError(f"{entry['python']['function']}(): no place in the core for {unknown}")
    opts, read, finish = parts
    if command == ["noise"] and data is None and arrays:
        record = _noise_record(arrays, opts, read)
        if record is not None:
            code, out, err, where = _typed.call_record(
                record[0], record[1], record[2], opts, read, finish, progress=progress
            )
            if code != 0:
                _raise(code, out, err, where)
            return _result(out, [])
    if command == ["noise"] and opts.get("format") in ("f32le", "f64le"):
        if data is None or not isinstance(data, (str, os.PathLike)):
            raise InputError("noise: format f32le or f64le reads a file: give its path")
        code, out, err, where = _typed.call_record(
            None, int(opts.get("channels") or 0), opts["format"] == "f64le", opts, read, finish,
            path=data, progress=progress,
        )
    else:
        code, out, err, where = _typed.call(entry["id"], data, arrays, opts, read, finish, progress)
    if code != 0:
        _raise(code, out, err, where)
    return _result(out, [])


#: Options of a command that are not keywords of its function: the data
#: (``data``) and the output (the function returns the document).
_NOT_KEYWORDS = ("input", "json", "output")


def _default(arg: Dict[str, Any]) -> Any:
    """An option's default as a Python value (``None``: none; a flag:
    ``False``)."""
    if arg["flag_only"]:
        return False
    texts = arg["default"]
    if not texts:
        return None

    def value(t: str) -> Any:
        for kind in (int, float):
            try:
                return kind(t)
            except ValueError:
                pass
        return t

    if arg["multiple"]:
        return [value(x) for t in texts for x in t.split(",")]
    return value(texts[0])


def _keyword(name: str) -> str:
    """An option's Python keyword: its name, with ``_`` after a Python
    keyword or the data parameter's name (``from`` → ``from_``, noise's
    ``data`` kind → ``data_``)."""
    import keyword

    return name + "_" if keyword.iskeyword(name) or name == "data" else name


def _signature(args: List[Dict[str, Any]], data: bool = True):
    """``(data=None, *, option=default, …)``: every option of the command
    as a keyword-only parameter with its default (required ones without);
    without ``data`` for a plan or a simulator."""
    import inspect

    params = []
    if data:
        params.append(inspect.Parameter("data", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None))
    for a in args:
        if a["name"] in _NOT_KEYWORDS:
            continue
        default = inspect.Parameter.empty if a["required"] else _default(a)
        params.append(inspect.Parameter(_keyword(a["name"]), inspect.Parameter.KEYWORD_ONLY, default=default))
    if data:
        params.append(inspect.Parameter("progress", inspect.Parameter.KEYWORD_ONLY, default=None))
    return inspect.Signature(params)


def _options_doc(args: List[Dict[str, Any]]) -> str:
    lines = []
    for a in args:
        if a["name"] in _NOT_KEYWORDS:
            continue
        extra = []
        if a["required"]:
            extra.append("required")
        elif not a["flag_only"] and a["default"]:
            extra.append("default " + ",".join(a["default"]))
        if a["values"]:
            extra.append("one of " + ", ".join(a["values"]))
        tail = f" ({'; '.join(extra)})" if extra else ""
        lines.append(f"    {_keyword(a['name'])}{tail}: {a['help'] or ''}")
    return "\n".join(lines)


def _keyword_ids(args: List[Dict[str, Any]]) -> Dict[str, str]:
    """Keyword → option id, from a command's argument table: the keyword
    of an option is its name (``from_`` for a Python keyword); its flag's
    spelling and aliases (``g_local``) are accepted too."""
    ids = {_keyword(a["name"]): a["name"] for a in args}
    for a in args:
        for spelling in [a["flag"][2:]] + list(a["aliases"] or []):
            ids.setdefault(spelling.replace("-", "_"), a["name"])
    return ids


def _by_id(
    name: str,
    args: List[Dict[str, Any]],
    ids: Dict[str, str],
    known: Any,
    options: Dict[str, Any],
    columns: bool = False,
) -> Dict[str, Any]:
    """The keywords of a call to ``name`` by option id; a keyword not in
    ``known`` is a ``TypeError``, as for any Python function (with
    ``columns``, an array by keyword is a data column, kept as given)."""
    if args:
        for key, value in options.items():
            if key not in known and not (columns and _is_array(value)):
                raise TypeError(f"{name}() got an unexpected keyword argument '{key}'")
    return {k if columns and _is_array(v) else ids.get(k, k): v for k, v in options.items()}


def _procedure(name: str, entry: Dict[str, Any]):
    command = entry["command"].split()
    doc = entry["title"] + "."
    args = (entry.get("arguments") or {}).get("reduce") or []
    ids = _keyword_ids(args)
    known = (set(ids) - set(_NOT_KEYWORDS)) | {"progress"}

    def reduce(data: Any = None, **options: Any) -> Result:
        return _reduce(entry, data, _by_id(name, args, ids, known, options, columns=True))

    reduce.__name__ = name
    reduce.__qualname__ = name
    reduce.__doc__ = doc + f"\n\nRuns ``incal {' '.join(command)}``."
    if args:
        reduce.__signature__ = _signature(args)  # type: ignore[attr-defined]
        reduce.__doc__ += (
            " Options (keywords; numpy arrays by keyword are data columns):\n\n"
            + _options_doc(args)
            + "\n    progress: a callable f(stage, done, total) the core reports to"
            " (from its own threads, the GIL taken), True for a tqdm bar, or None"
        )
    return reduce


def _registry() -> List[Dict[str, Any]]:
    """The procedure registry of the library (``incal procedures --json``):
    one dict per procedure, with its id, commands, title, rig, chapter,
    Python names and options' schemas from the core, and ``arguments``, the
    command line's argument tables the keyword parameters follow (shipped
    with the package in ``arguments.json``, kept equal to the CLI's by a
    test). Every table of procedures in this package is built from it."""
    from ._incal import _registry as core

    with open(os.path.join(os.path.dirname(__file__), "arguments.json"), encoding="utf-8") as f:
        arguments = json.load(f)
    entries = json.loads(core())
    for e in entries:
        e["arguments"] = arguments.get(e["id"], {"reduce": None, "plan": None, "simulate": None})
    return entries


#: The procedure registry (see :func:`_registry`).
REGISTRY: List[Dict[str, Any]] = _registry()

# One function per procedure that reduces a recording, named as the
# registry says (``incal.gyro_rate`` runs ``incal gyro rate``).
for _entry in REGISTRY:
    if _entry["input"] == "recording":
        _name = _entry["python"]["function"]
        globals()[_name] = _procedure(_name, _entry)
        __all__.append(_name)
del _entry, _name


def _as_files(d: str, items: Sequence[Any], stem: str) -> List[str]:
    files = []
    for i, r in enumerate(items):
        if isinstance(r, Result):
            f = os.path.join(d, f"{stem}{i}.json")
            r.to_json(f)
            files.append(f)
        else:
            files.append(os.fspath(r))
    return files


def thermal_fit(results: Sequence[Any], **options: Any) -> Result:
    """``incal thermal fit``: results (``Result`` or paths) of one instrument
    and one procedure, each at its own temperature (``meta`` ``temperature_c``
    or a ``temperature_c`` column of its recording), into a polynomial in
    (T - T_ref) per coefficient (``NAME.c0``, ``NAME.c1``, ...). Options:
    ``t_ref_c``, ``degree``, and the identity, unit and limits keywords of
    every reduction; with ``db`` (a records store; and ``procedure`` when
    the serial has records of several) and no results, the store's current
    calibrations of ``serial``."""
    import hashlib

    from . import _typed
    from ._incal import _thermal_fit

    db = options.pop("db", None)
    procedure = options.pop("procedure", None)
    fit = {k: options.pop(k) for k in ("t_ref_c", "degree") if options.get(k) is not None}
    parts = _typed.split({"properties": {}}, options)
    if parts is None:
        raise TypeError(f"thermal_fit() got an unexpected keyword argument among {sorted(options)}")
    documents = []
    if db is not None:
        from .records import Records

        serial = parts[2].get("serial")
        if serial is None:
            raise InputError("serial: needed with db=", {"option": "serial"})
        if results:
            raise InputError("results: give results or db=, not both", {"option": "db"})
        found = Records(db)._call("calibrations", serial=serial, procedure=procedure)
        documents = [(d["name"], d["sha256"], d["text"]) for d in found]
    for r in results:
        name, data = _typed.document_bytes(r)
        documents.append((name, hashlib.sha256(data).hexdigest(), _typed.decoded(name, data)))
    code, out, err, where = _thermal_fit(documents, json.dumps(fit, default=_typed._json_default), json.dumps(parts[2]))
    if code != 0:
        _raise(code, bytes(out), list(err), json.loads(where))
    return _result(bytes(out), [])


def _stream(tool: str, model: Any, data: Any, columns: Dict[str, Any], sort_time: bool = False):
    """A streaming tool of the core on data in place: the rows written as
    a DataFrame, the run's warnings raised as Python warnings."""
    from . import _typed
    from ._incal import _stream as stream

    name, kwargs = _typed.data_kwargs(data, columns)
    model_name, model_text = _typed.document_text(model)
    code, out, err, warnings = stream(tool, model_name, model_text, name, sort_time=sort_time, **kwargs)
    if code != 0:
        _raise(code, bytes(out), [err])
    _warn_all(json.loads(warnings))
    return _read_csv(bytes(out))


def mag_apply(calibration: Any, data: Any = None, **columns: Any):
    """``incal mag apply``: a magnetometer calibration (``Result`` or path)
    applied to raw data with ``mag_x, mag_y, mag_z`` (path, DataFrame, dict
    of arrays or arrays by keyword, read in place); a pandas DataFrame with
    those columns calibrated and every other column copied."""
    return _stream("mag-apply", calibration, data, columns)


def export_mag(calibration: Any, stack: str = "px4", path: Optional[str] = None, instance: int = 0) -> str:
    """``incal mag export --to px4|ardupilot``: a magnetometer calibration
    (``Result`` or path) as PX4's ``CAL_MAG<n>_*`` (gauss) or ArduPilot's
    ``COMPASS_*`` (milligauss) parameters, as that stack's parameter file
    text; written to ``path`` when given."""
    if stack not in ("px4", "ardupilot"):
        raise InputError(f"stack: '{stack}' is not px4 or ardupilot")
    return _write(_export(f"mag-{stack}", [calibration], {"instance": int(instance)}), path)


def thermal_apply(model: Any, data: Any = None, **columns: Any):
    """``incal thermal apply``: a thermal model (``Result`` or path) applied
    to raw data with a ``temperature_c`` column (path, DataFrame, dict of
    arrays or arrays by keyword, read in place); a pandas DataFrame. A
    temperature outside the model's range is clamped, with a warning."""
    return _stream("thermal-apply", model, data, columns)


def export_thermal(model: Any, stack: str = "px4", path: Optional[str] = None, **options: Any) -> str:
    """``incal export px4|ardupilot MODEL.json``: a thermal model (``Result``
    or path) as PX4's ``TC_*`` or ArduPilot's ``INS_TCALn_*`` parameters;
    written to ``path`` when given. Options: ``axes``, ``device_id``,
    ``with_offset`` (PX4), ``imu`` (ArduPilot)."""
    if stack not in ("px4", "ardupilot"):
        raise InputError(f"export_thermal: stack '{stack}' is not px4 or ardupilot")
    return _write(_export(stack, [model], options), path)


def read_result(path: str) -> Result:
    """A result document from a file, checked by the core as every
    command that reads one checks it (the schema, then what it cannot
    say: U95 = k95·u, dof > 0, table widths, …): a bad file raises
    :class:`InputError` naming the file and the JSON path."""
    from . import _typed
    from ._incal import _check_result

    name, text = _typed.document_text(os.fspath(path))
    if not text.strip():
        raise InputError(f"{name}: empty file", {"file": name})
    problem = _check_result(text)
    if problem is not None:
        raise InputError(f"{name}: {problem}", {"file": name})
    return Result(json.loads(text), text=text)


def compare(a: Any, b: Any) -> Dict[str, Any]:
    """``incal compare`` of two results (``Result`` or paths; a ``Result``
    is named ``<Result>``): the JSON, by the core's comparison."""
    from . import _typed
    from ._incal import _compare

    (na, ta), (nb, tb) = _typed.document_text(a), _typed.document_text(b)
    code, out, err = _compare(na, ta, nb, tb)
    if code != 0:
        _raise(code, b"", [err])
    return json.loads(out)


def apply(calibration: Any, data: Any = None, sort_time: bool = False, **columns: Any):
    """``incal imu apply``: a calibration (``Result`` or path) applied to
    raw data (path, DataFrame, dict of arrays or arrays by keyword, read in
    place); a pandas DataFrame. ``sort_time`` sorts rows by ``time_s``
    first."""
    return _stream("imu-apply", calibration, data, columns, sort_time)


def _export(kind: str, documents: Sequence[Any], options: Dict[str, Any]) -> str:
    """The core's export ``kind`` of ``documents`` (``Result`` or paths)."""
    from . import _typed
    from ._incal import _export as export

    texts = [_typed.document_text(d) for d in documents]
    if isinstance(options.get("axes"), str):
        options = dict(options, axes=options["axes"].split(","))
    code, out, err = export(kind, texts, json.dumps(options))
    if code != 0:
        _raise(code, b"", [err])
    return out


def _write(text: str, path: Optional[str]) -> str:
    if path is not None:
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
    return text


def export_kalibr(gyro: Any, accel: Any, path: Optional[str] = None) -> str:
    """``incal export kalibr``: a gyro and an accelerometer noise result
    (``Result`` or paths; ``incal.noise(..., quantity="gyro")`` and
    ``quantity="accel"``) as Kalibr's ``imu.yaml`` text (SI continuous
    time, the largest axis per sensor); written to ``path`` when given. A
    term not identified on an axis raises :class:`InputError`."""
    return _write(_export("kalibr", [gyro, accel], {}), path)


def export_px4(
    gyro: Any, accel: Any, path: Optional[str] = None, ekf_rate_hz: float = 100.0
) -> str:
    """``incal export px4``: the same two noise results as PX4's EKF2 IMU
    noise parameters (``EKF2_GYR_NOISE``, ``EKF2_ACC_NOISE``,
    ``EKF2_GYR_B_NOISE``, ``EKF2_ACC_B_NOISE``: each continuous-time density
    times the square root of the EKF prediction rate ``ekf_rate_hz``), as a
    QGroundControl parameter file's text; written to ``path`` when given."""
    return _write(_export("px4", [gyro, accel], {"ekf_rate_hz": float(ekf_rate_hz)}), path)


def _stack(kind: str, gyro: Any, accel: Any, path: Optional[str], inflate: float, rate_hz: Optional[float], **extra: Any) -> str:
    options: Dict[str, Any] = {"inflate": float(inflate)}
    if rate_hz is not None:
        options["rate_hz"] = float(rate_hz)
    options.update({k: v for k, v in extra.items() if v is not None})
    return _write(_export(kind, [gyro, accel], options), path)


def export_vins(gyro: Any, accel: Any, path: Optional[str] = None, inflate: float = 1.0, rate_hz: Optional[float] = None) -> str:
    """``incal export vins``: the two noise results as VINS-Mono /
    VINS-Fusion's ``acc_n``, ``gyr_n`` (continuous density times
    sqrt(2 f)) and ``acc_w``, ``gyr_w`` (random walk times sqrt(f)):
    discrete time per IMU sample at ``rate_hz`` (default the records'),
    every value times ``inflate`` (stated in the file)."""
    return _stack("vins", gyro, accel, path, inflate, rate_hz)


def export_orbslam3(gyro: Any, accel: Any, path: Optional[str] = None, inflate: float = 1.0, rate_hz: Optional[float] = None) -> str:
    """``incal export orbslam3``: ORB-SLAM3's ``IMU.NoiseGyro``,
    ``IMU.NoiseAcc``, ``IMU.GyroWalk``, ``IMU.AccWalk`` (continuous time,
    SI) and ``IMU.Frequency``."""
    return _stack("orbslam3", gyro, accel, path, inflate, rate_hz)


def export_openvins(
    gyro: Any, accel: Any, path: Optional[str] = None, inflate: float = 1.0, rate_hz: Optional[float] = None, topic: Optional[str] = None
) -> str:
    """``incal export openvins``: OpenVINS's ``kalibr_imu_chain.yaml``
    (continuous time, SI; ``rostopic`` ``topic``, default ``/imu0``)."""
    return _stack("openvins", gyro, accel, path, inflate, rate_hz, topic=topic)


def export_basalt(gyro: Any, accel: Any, path: Optional[str] = None, inflate: float = 1.0, rate_hz: Optional[float] = None) -> str:
    """``incal export basalt``: Basalt's calibration keys
    ``accel_noise_std``, ``gyro_noise_std``, ``accel_bias_std``,
    ``gyro_bias_std`` per axis (continuous time, SI) and
    ``imu_update_rate``, as JSON text (``value0``)."""
    return _stack("basalt", gyro, accel, path, inflate, rate_hz)


from . import batch, plan, simulate, warnings  # noqa: E402  (they use the tables above)
from .records import Records  # noqa: E402
