"""Test plans before the test: ``incal.plan.tumble(k1=10, noise=1e-6)``
returns the plan document (``incal.plan/1``) as a dict, with the predicted
u of every coefficient. Options as ``incal plan <name> --help`` lists them,
``_`` for ``-``."""

from __future__ import annotations

import json
from typing import Any, Dict

from . import _options, run

__all__ = ["tumble", "misalign", "centrifuge", "gfimu", "gyro_rate", "gyro_positions"]


def _plan(name: str):
    def plan(**options: Any) -> Dict[str, Any]:
        out, _ = run(["plan", name, "--json"] + _options(options))
        return json.loads(out)

    plan.__name__ = name.replace("-", "_")
    plan.__doc__ = f"The plan document of ``incal plan {name}``."
    return plan


tumble = _plan("tumble")
misalign = _plan("misalign")
centrifuge = _plan("centrifuge")
gfimu = _plan("gfimu")
gyro_rate = _plan("gyro-rate")
gyro_positions = _plan("gyro-positions")
