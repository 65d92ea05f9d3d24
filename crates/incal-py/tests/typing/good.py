"""Typed use of incal that mypy --strict accepts."""

from typing import Any, Dict

import numpy as np

import incal

r: incal.Result = incal.tumble("tumble.csv", mount="pendulum", terms=["K0", "K1"], noise=1e-6)
u: float = r.coefficients["K1"].u
g = incal.gyro_rate(
    {"rate_deg_s": np.zeros(3), "output": np.zeros(3)},
    latitude_deg=45.0,
    ia="down",
    serial="SN-1",
    meta={"operator": "lee"},
)
n = incal.noise("gyro.csv", rate_hz=100.0, quantity="gyro", unit="deg/s")
p: Dict[str, Any] = incal.plan.tumble(k1=10.0, noise=1e-6)
data, truth = incal.simulate.tumble(seed=7)
