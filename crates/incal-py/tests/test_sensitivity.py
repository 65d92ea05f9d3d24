"""Environmental sensitivities against independent computations on the
same data: the run means' covariance integrated numerically by scipy from
the noise model incal reports, and numpy's generalized least squares with
it, give incal's coefficients and u; the pooled Allan variance at one
sample equals numpy's; the plan and the refusal of one level come through
Python."""

import numpy as np
import pytest
from scipy.integrate import dblquad

import incal


def run_covariance(white, flicker, walk, start, length):
    """The run means' covariance (the chapter's generalized covariances),
    by scipy's numerical double integration, plus a constant the
    intercept absorbs."""
    h = flicker / (2 * np.log(2))
    q = 3 * walk

    def k(tau):
        t = abs(tau)
        return (-h * np.log(t) if t > 0 else 0.0) - 0.5 * q * t

    r = len(start)
    s = np.zeros((r, r))
    for i in range(r):
        for j in range(i + 1):
            a1, b1, a2, b2 = start[i], start[i] + length[i], start[j], start[j] + length[j]
            v, _ = dblquad(lambda y, x: k(x - y), a1, b1, a2, b2, epsabs=1e-10)
            v /= length[i] * length[j]
            if i == j:
                v += white / length[i]
            s[i, j] = s[j, i] = v
    return s + 4 * np.abs(s).max()


def test_the_fit_agrees_with_scipy_integration_and_numpy_gls():
    data, truth = incal.simulate.sensitivity(seed=41, angles_deg="0,45,-45", run_s=20, rate_hz=20, flicker=5.0)
    r = incal.sensitivity(data)
    noise = r.document["sensitivity"]["columns"][0]["noise"]
    runs = data.groupby("run", sort=False)
    y = runs["output"].mean().to_numpy() * 1e6  # g -> µg
    g = runs["vib_g"].first().to_numpy()
    th = np.radians(runs["vib_angle_deg"].first().to_numpy())
    start = runs["time_s"].first().to_numpy()
    length = runs.size().to_numpy() / 20.0
    cov = run_covariance(noise["white"], noise["flicker"], noise["walk"], start, length)
    a = np.column_stack(
        [np.ones_like(g), g**2 * np.cos(th) ** 2, g**2 * np.sin(th) * np.cos(th), g**2 * np.sin(th) ** 2]
    )
    ci = np.linalg.inv(cov)
    c = np.linalg.inv(a.T @ ci @ a)
    x = c @ a.T @ ci @ y
    for k, name in enumerate(["vrc", "vibropendulous", "vrc_pendulous"], start=1):
        e = r.coefficients[name]
        assert abs(e.value - x[k]) < 1e-3 * e.U95, (name, e.value, x[k], e.U95)
        assert e.u == pytest.approx(np.sqrt(c[k, k]), rel=1e-3), name
        assert abs(e.value - truth[name]) < 2 * e.U95, (name, e.value, truth[name])


def test_the_allan_variance_at_one_sample_equals_numpy():
    data, _ = incal.simulate.sensitivity(seed=42, run_s=10, rate_hz=20)
    r = incal.sensitivity(data)
    first = r.document["sensitivity"]["columns"][0]["noise"]["allan"][0]
    diffs = []
    for _, run in data.groupby("run", sort=False):
        v = run["output"].to_numpy() * 1e6
        diffs.append(np.diff(v))
    d = np.concatenate(diffs)
    assert first["avar"] == pytest.approx(0.5 * np.mean(d**2), rel=1e-9)


def test_plan_and_refusal():
    p = incal.plan.sensitivity(angles_deg="0,45,-45")
    assert p["predicted_u"]["vibropendulous"] > 0
    data, _ = incal.simulate.sensitivity(seed=43, levels="4", run_s=2, rate_hz=20)
    with pytest.raises(incal.IncalError, match="single stimulus level"):
        incal.sensitivity(data)
