"""Preprocessing from Python: the drifts incal removes equal numpy's and
scipy's least squares on the same samples, the outliers it removes are the
rows a MAD rule written here flags, and a bad rule raises with the option
named."""

import math

import numpy as np
import pytest

import incal


def _samples(n=20_000, fs=10.0, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    return t, 0.01 * rng.standard_normal(n)


def test_linear_and_quadratic_drifts_equal_numpy_polyfit():
    t, e = _samples()
    for model, deg, keys in [("linear", 1, ["slope_per_s", "offset"]), ("quadratic", 2, ["curvature_per_s2", "slope_per_s", "offset"])]:
        y = 0.3 + 2e-3 * t - 4e-7 * t * t + e
        r = incal.noise(gx=y, rate_hz=10.0, detrend=model)
        step = r.document["preprocessing"][0]
        assert step["step"] == "detrend" and step["model"] == model
        got = step["channels"]["gx"]["coefficients"]
        want = np.polyfit(t, y, deg)
        for k, w in zip(keys, want):
            assert abs(got[k] - w) <= 1e-8 * max(abs(w), 1e-12) + 1e-12, (model, k, got[k], w)


def test_log_drift_equals_scipy_curve_fit():
    from scipy import optimize

    t, e = _samples()
    y = 1.0 + 0.5 * np.log1p(0.01 * t) + e
    r = incal.noise(gx=y, rate_hz=10.0, detrend="log")
    got = r.document["preprocessing"][0]["channels"]["gx"]["coefficients"]
    p, _ = optimize.curve_fit(lambda t, c, a, b: c + a * np.log1p(b * t), t, y, p0=[1.0, 0.4, 0.02], maxfev=20000)
    for k, w in zip(["offset", "a", "b_per_s"], p):
        assert abs(got[k] - w) <= 1e-5 * abs(w), (k, got[k], w)


def test_outliers_are_the_rows_a_mad_rule_flags():
    t, e = _samples(seed=9)
    y = e.copy()
    y[[50, 51, 7000]] += 1.0
    r = incal.noise(gx=y, rate_hz=10.0, outliers="mad:5", fill="gaps")
    med = np.median(y)
    sigma = 1.4826 * np.median(np.abs(y - med))
    flagged = np.flatnonzero(np.abs(y - med) > 5 * sigma)
    step = r.document["preprocessing"][0]["channels"]["gx"]
    listed = [i for a, b in step["samples"] for i in range(a, b + 1)]
    assert listed == flagged.tolist() and step["removed"] == len(flagged)
    assert math.isclose(step["sigma_mad"], sigma, rel_tol=1e-12)
    assert r.document["preprocessing"][1]["channels"]["gx"]["filled"] == len(flagged)


def test_a_bad_rule_names_the_option():
    _, e = _samples(n=2000)
    with pytest.raises(Exception, match="outliers"):
        incal.noise(gx=e, rate_hz=10.0, outliers="mad:1")
