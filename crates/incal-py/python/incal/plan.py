"""Test plans before the test: ``incal.plan.tumble(k1=10, noise=1e-6)``
returns the plan document (``incal.plan/1``) as a dict, with the predicted
u of every coefficient. Options as ``incal plan <name> --help`` lists them,
``_`` for ``-``. One function per plan command of the procedure registry
(``incal.REGISTRY``)."""

from __future__ import annotations

import json
from typing import Any, Dict, List

from . import REGISTRY, _options, run

__all__: List[str] = []


def _plan(name: str):
    def plan(**options: Any) -> Dict[str, Any]:
        out, _ = run(["plan", name, "--json"] + _options(options))
        return json.loads(out)

    plan.__name__ = name.replace("-", "_")
    plan.__qualname__ = plan.__name__
    plan.__doc__ = f"The plan document of ``incal plan {name}``."
    return plan


for _entry in REGISTRY:
    _name = _entry["python"]["plan"]
    if _name and _name not in __all__:
        globals()[_name] = _plan(_entry["plan"].split()[1])
        __all__.append(_name)
del _entry, _name
