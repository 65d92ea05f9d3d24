"""Threshold and resolution: each step size's response ratio, the noise
at the plateau scale and K1 against numpy's by-hand computation on the
same record, Fieller's interval against scipy's t quantile, the
accelerometer's tilt input, and the refusals."""

import numpy as np
import pytest

import incal


def plateaus(u, y):
    """Consecutive rows at one input: (input, mean, n)."""
    out, start = [], 0
    for k in range(1, len(u) + 1):
        if k == len(u) or u[k] != u[start]:
            out.append((u[start], y[start:k].mean(), k - start))
            start = k
    return out


def by_hand(u, y, base):
    p = plateaus(u, y)
    level = [0 if q[0] == 0 else (1 if q[0] == base else None) for q in p]
    # s² from the revisits of each level.
    num = den = 0.0
    for g in (0, 1):
        at = [q for q, l in zip(p, level) if l == g]
        for a, b in zip(at, at[1:]):
            num += (b[1] - a[1]) ** 2
            den += 1 / a[2] + 1 / b[2]
    s2 = num / den
    zero = np.mean([q[1] for q, l in zip(p, level) if l == 0])
    at_base = np.mean([q[1] for q, l in zip(p, level) if l == 1])
    k1 = (at_base - zero) / base
    # Each size's mean output change per unit input, about zero.
    sizes = {}
    for k in range(len(p) - 1):
        a, b = p[k], p[k + 1]
        if (level[k] == 0) != (level[k + 1] == 0) and None in (level[k], level[k + 1]):
            d = abs(b[0] - a[0])
            key = round(d, 12)
            sizes.setdefault(key, []).append((b[1] - a[1]) / (b[0] - a[0]))
    ratios = {s: np.mean(v) / k1 for s, v in sizes.items()}
    return s2, k1, ratios


def test_ratios_noise_and_k1_equal_numpy():
    data, truth = incal.simulate.threshold(seed=11, dwell_s=10)
    r = incal.threshold(data)
    u = data["rate_deg_s"].to_numpy()
    y = data["output"].to_numpy()
    s2, k1, ratios = by_hand(u, y, 10.0)
    d = r.document
    assert d["threshold"]["noise_long_sd"] == pytest.approx(np.sqrt(s2), rel=1e-9)
    assert r.coefficients["K1"].value == pytest.approx(k1, rel=1e-9)
    rows = [row for row in d["tables"][0]["rows"] if row[0] == "zero"]
    assert len(rows) == len(ratios)
    for row in rows:
        assert row[4] == pytest.approx(ratios[round(row[1], 12)], rel=1e-9, abs=1e-12)
    t = r.coefficients["threshold_deg_s"]
    assert abs(t.value - truth["threshold_deg_s"]) < 3 * t.U95


def test_fieller_interval_matches_scipy():
    """The 95 % interval the document reports solves Fieller's quadratic
    with scipy's t quantile at the document's degrees of freedom."""
    from scipy import stats

    data, _ = incal.simulate.threshold(seed=12, dwell_s=10)
    r = incal.threshold(data)
    d = r.document
    c = r.coefficients["threshold_deg_s"]
    lo, hi = d["threshold"]["brackets"]["threshold"]["interval_95"]
    k = stats.t.ppf(0.975, c.dof)
    assert c.U95 == pytest.approx(0.5 * (hi - lo), rel=1e-6)
    assert c.value == pytest.approx(0.5 * (hi + lo), rel=1e-9)
    assert c.U95 / c.u == pytest.approx(k, rel=1e-6)


def test_an_accelerometer_reports_in_g():
    data, truth = incal.simulate.threshold(sensor="accel", seed=13, dwell_s=10)
    assert "tilt_deg" in data.columns
    r = incal.threshold(data)
    assert r.coefficients["threshold_g"].unit == "g"
    assert abs(r.coefficients["threshold_g"].value - truth["threshold_g"]) < 3 * r.coefficients["threshold_g"].U95


def test_steps_that_do_not_bracket_are_refused():
    data, _ = incal.simulate.threshold(seed=14, dwell_s=10, dead_band=1e-5)
    with pytest.raises(Exception, match="every step at zero passes"):
        incal.threshold(data)
    with pytest.raises(Exception, match="bracket"):
        incal.plan.threshold(steps=[0.01, 0.02, 0.05])
