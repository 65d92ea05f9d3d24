"""Magnetometer calibration against an independent fit on the same data
(numpy's algebraic ellipsoid, then scipy's least squares on the
magnitude), apply and the flight-stack exports against the calibration
applied by hand, and the planar refusal."""

import numpy as np
import pytest
from scipy.optimize import least_squares

import incal

SOFT = ["xx", "yy", "zz", "xy", "xz", "yz"]
PAIRS = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]


def sym(c):
    s = np.zeros((3, 3))
    for v, (i, j) in zip(c, PAIRS):
        s[i, j] = s[j, i] = v
    return s


def independent_fit(m, field):
    """Algebraic quadric fit, then least squares of |C (m - h)| - 1 with C
    symmetric (scipy), scaled to the field: (h, S)."""
    mu = m.mean(axis=0)
    p = m - mu
    s = np.sqrt((p**2).sum(axis=1).mean())
    p = p / s
    x, y, z = p.T
    a = np.column_stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, 2 * x, 2 * y, 2 * z])
    v = np.linalg.lstsq(a, np.ones(len(p)), rcond=None)[0]
    q = sym(v[:6])
    c = -np.linalg.solve(q, v[6:])
    k = 1 + c @ q @ c
    w, u = np.linalg.eigh(q / k)
    c0 = u @ np.diag(np.sqrt(w)) @ u.T / s
    h0 = mu + s * c
    start = np.concatenate([h0, [c0[i, j] for i, j in PAIRS]])

    def res(t, target):
        return np.linalg.norm((m - t[:3]) @ sym(t[3:]).T, axis=1) - target

    t = least_squares(res, start, args=(1.0,), xtol=1e-14, ftol=1e-14).x
    # The noise's bias on a magnitude (the same correction incal states).
    target = 1 + np.mean(res(t, 1.0) ** 2)
    t = least_squares(res, t, args=(target,), xtol=1e-14, ftol=1e-14).x
    return t[:3], field * sym(t[3:])


def test_the_fit_agrees_with_an_independent_fit_within_u95():
    data, truth = incal.simulate.mag(seed=31, orientations=24, dwell_s=1, rate_hz=20, no_accelerometer=True)
    r = incal.mag(data, field_ut=50.0)
    m = data[["mag_x", "mag_y", "mag_z"]].to_numpy()
    h, s = independent_fit(m, 50.0)
    for k, a in enumerate("xyz"):
        c = r.coefficients[f"hard_iron_{a}"]
        assert abs(c.value - h[k]) < 0.05 * c.U95, (a, c.value, h[k], c.U95)
    for name, (i, j) in zip(SOFT, PAIRS):
        c = r.coefficients[f"soft_iron_{name}"]
        assert abs(c.value - s[i, j]) < 0.05 * c.U95, (name, c.value, s[i, j], c.U95)
    # And both near the truth.
    assert abs(r.coefficients["hard_iron_x"].value - 12.0) < 3 * r.coefficients["hard_iron_x"].U95


def test_apply_and_exports_equal_the_calibration_by_hand():
    data, _ = incal.simulate.mag(seed=32, orientations=24, dwell_s=1, rate_hz=20)
    r = incal.mag(data, field_ut=50.0)
    h = np.array([r.coefficients[f"hard_iron_{a}"].value for a in "xyz"])
    s = sym([r.coefficients[f"soft_iron_{n}"].value for n in SOFT])
    m = data[["mag_x", "mag_y", "mag_z"]].to_numpy()
    out = incal.mag_apply(r, data)
    b = out[["mag_x", "mag_y", "mag_z"]].to_numpy()
    assert np.allclose(b, (m - h) @ s.T, rtol=1e-12, atol=1e-12)
    assert np.array_equal(out["acc_x"].to_numpy(), data["acc_x"].to_numpy())
    px4 = dict(
        (line.split("\t")[2], float(line.split("\t")[3]))
        for line in incal.export_mag(r, stack="px4").splitlines()
        if not line.startswith("#")
    )
    o = np.array([px4[f"CAL_MAG0_{a}OFF"] for a in "XYZ"])
    su = sym([px4["CAL_MAG0_XSCALE"], px4["CAL_MAG0_YSCALE"], px4["CAL_MAG0_ZSCALE"],
              px4["CAL_MAG0_XODIAG"], px4["CAL_MAG0_YODIAG"], px4["CAL_MAG0_ZODIAG"]])
    gauss = (m / 100 - o) @ su.T
    assert np.allclose(gauss * 100, b, rtol=1e-9, atol=1e-9)
    ap = dict(l.split(",") for l in incal.export_mag(r, stack="ardupilot", instance=1).splitlines())
    o = np.array([float(ap[f"COMPASS2_OFS_{a}"]) for a in "XYZ"])
    su = sym([float(ap[f"COMPASS2_DIA_{a}"]) for a in "XYZ"] + [float(ap[f"COMPASS2_ODI_{a}"]) for a in "XYZ"])
    mgauss = (m * 10 + o) @ su.T
    assert np.allclose(mgauss / 10, b, rtol=1e-9, atol=1e-9)


def test_a_planar_session_is_refused_naming_the_terms():
    data, _ = incal.simulate.mag(seed=33, motion="planar", orientations=24, dwell_s=1, rate_hz=20)
    with pytest.raises(incal.InputError, match="cannot separate hard_iron_z"):
        incal.mag(data, field_ut=50.0)
