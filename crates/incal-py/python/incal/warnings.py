"""incal's warnings as Python warning categories.

Every warning code of the result document (``lack-of-fit``,
``time-repeats``, …; the ``WarningCode`` of ``incal schema``) is a
subclass of :class:`IncalWarning` named in CamelCase (``LackOfFit``,
``TimeRepeats``), built from the library's schema at import, so a code the
library adds is a category at once. A reduction raises each warning of its
document with :func:`warnings.warn`, so a production script can turn one
into an error::

    import warnings, incal
    warnings.filterwarnings("error", category=incal.warnings.LackOfFit)

The document keeps them too (``Result.document["warnings"]``).
"""

from __future__ import annotations

import json
import warnings as _warnings
from typing import Any, Dict, Iterable, List, Tuple, Type

from ._incal import _schema

__all__ = ["IncalWarning", "CATEGORIES", "category", "warn_all"]


class IncalWarning(UserWarning):
    """A warning of incal: the numbers stand, with what they mean said."""

    #: The warning's stable code in documents (``lack-of-fit``).
    code: str = ""


def _camel(code: str) -> str:
    return "".join(part.capitalize() for part in code.split("-"))


def _codes() -> List[Tuple[str, str]]:
    """``(code, description)`` of every warning code, from the result
    document's JSON Schema."""
    schema = json.loads(_schema())
    out_codes = []
    for v in schema["$defs"]["WarningCode"]["oneOf"]:
        doc = " ".join(v.get("description", "").split())
        out_codes.append((v["const"], doc))
    return out_codes


#: Code → category, for every warning code of the library.
CATEGORIES: Dict[str, Type[IncalWarning]] = {}

for _code, _doc in _codes():
    _cls = type(_camel(_code), (IncalWarning,), {"__doc__": _doc, "code": _code, "__module__": __name__})
    CATEGORIES[_code] = _cls
    globals()[_cls.__name__] = _cls
    __all__.append(_cls.__name__)
del _code, _doc, _cls


def category(code: str) -> Type[IncalWarning]:
    """The category of ``code`` (:class:`IncalWarning` for a code this
    library does not know)."""
    return CATEGORIES.get(code, IncalWarning)


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside this package, seen from
    :func:`warn_all`: a warning points at the line of the user's call."""
    import os
    import sys

    package = os.path.dirname(os.path.abspath(__file__))
    frame = sys._getframe(2)  # the caller of warn_all
    level = 2
    while frame is not None and os.path.dirname(os.path.abspath(frame.f_code.co_filename)) == package:
        frame = frame.f_back
        level += 1
    return level


def warn_all(warnings: Iterable[Any]) -> None:
    """Raise every warning of a document (``{"code", "message"}`` dicts)
    or of a streaming command's standard error (``warning [code]: message``
    lines) with :func:`warnings.warn`, in its category, pointing at the
    user's call."""
    level = _caller_level()
    for w in warnings:
        if isinstance(w, dict):
            code, message = str(w.get("code", "")), str(w.get("message", ""))
        else:
            text = str(w)
            if not text.startswith("warning ["):
                continue
            code, _, message = text[len("warning [") :].partition("]: ")
        _warnings.warn(f"[{code}] {message}", category(code), stacklevel=level)
