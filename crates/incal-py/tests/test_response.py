"""Dynamic response by stepped sine: incal's dwell sine fits against an
independent least-squares fit (numpy) on the same samples, and the
simulated truth inside U95."""

import math

import numpy as np
import pytest

import incal


def _numpy_fit(t, y, f, harmonics, nyquist):
    """The IEEE Std 1057 three-parameter fit with harmonics and a linear
    drift, by numpy's least squares: (R, phi) of the fundamental."""
    tp = t - t[0]
    cols = []
    for k in range(1, harmonics + 1):
        if k == 1 or k * f < nyquist:
            cols += [np.cos(2 * math.pi * k * f * tp), np.sin(2 * math.pi * k * f * tp)]
    cols += [np.ones_like(tp), tp - tp.mean()]
    x, *_ = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)
    return math.hypot(x[0], x[1]), math.atan2(-x[1], x[0])


@pytest.fixture(scope="module")
def reduced():
    data, truth = incal.simulate.response_sine(seed=21, dwells=7, seconds_per_dwell=0.5, distortion_pct=1.0)
    return data, truth, incal.response_sine(data)


def test_the_dwell_sine_fits_equal_numpy_least_squares(reduced):
    data, _, r = reduced
    dwells = r.table("dwells")
    t = np.asarray(data["time_s"], dtype=float)
    f_all = np.asarray(data["freq_hz"], dtype=float)
    for _, row in dwells.iterrows():
        f = row["freq_hz [Hz]"]
        m = f_all == f
        rate = (m.sum() - 1) / (t[m][-1] - t[m][0])
        for channel, amp, ph in (("reference", "ref_amplitude [reference]", "ref_phase_deg [deg]"),
                                 ("output", "out_amplitude [output]", "out_phase_deg [deg]")):
            R, phi = _numpy_fit(t[m], np.asarray(data[channel], dtype=float)[m], f, 3, rate / 2)
            assert row[amp] == pytest.approx(R, rel=1e-9), (f, channel)
            assert math.radians(row[ph]) == pytest.approx(phi, rel=1e-9, abs=1e-12), (f, channel)


def test_the_four_parameter_fit_finds_the_least_squares_frequency_of_scipy():
    """IEEE Std 1057's four-parameter fit: the estimated frequency of
    each dwell is the least-squares optimum scipy.optimize.least_squares
    finds from the true frequency (the table runs 0.2 % off freq_hz), to
    1e-9 relative; found without freq_hz, the same dwells and nearly the
    same frequencies."""
    from scipy import optimize

    kw = dict(seed=4, dwells_hz=[3, 8, 20, 50, 120], seconds_per_dwell=3, frequency_error_pct=0.2)
    data, truth = incal.simulate.response_sine(**kw)
    r = incal.response_sine(data, estimate_frequency=True, harmonics=1, order="second")
    t_all = np.asarray(data["time_s"], dtype=float)
    ref_all = np.asarray(data["reference"], dtype=float)
    nominal = np.asarray(data["freq_hz"], dtype=float)
    rows = r.table("dwells")
    assert rows["u_freq_hz [Hz]"].notna().all()
    for (_, row), f_nom, t_dwell in zip(rows.iterrows(), [3, 8, 20, 50, 120], truth["dwells"]):
        m = nominal == f_nom
        t, y = t_all[m] - t_all[m][0], ref_all[m]

        def resid(x):
            w = 2 * math.pi * x[4]
            return x[0] * np.cos(w * t) + x[1] * np.sin(w * t) + x[2] + x[3] * (t - t.mean()) - y

        f0 = t_dwell["freq_hz"]
        sol = optimize.least_squares(resid, [0.0, 1.0, 0.0, 0.0, f0], xtol=1e-15, ftol=1e-15, gtol=1e-15)
        assert row["freq_hz [Hz]"] == pytest.approx(sol.x[4], rel=1e-9), f_nom
        assert abs(row["freq_hz [Hz]"] - f0) <= 3 * row["u_freq_hz [Hz]"]
    found, _ = incal.simulate.response_sine(no_freq_column=True, **kw)
    assert "freq_hz" not in found
    rf = incal.response_sine(found, harmonics=1, order="second").table("dwells")
    assert len(rf) == 5
    for a, b, u in zip(rf["freq_hz [Hz]"], rows["freq_hz [Hz]"], rows["u_freq_hz [Hz]"]):
        assert abs(a - b) <= 5 * u


def test_the_simulated_truth_lies_inside_u95(reduced):
    _, truth, r = reduced
    c = r.coefficients
    for name in ("bandwidth_hz", "delay_s", "latency_s", "phase_freq_hz"):
        assert abs(c[name].value - truth[name]) <= c[name].U95, name
    assert r.document["procedure"] == "response-sine"
    # The distortion the simulator put in the output shows as its THD.
    thd = r.table("dwells")["thd_out_pct [%]"]
    assert thd.min() == pytest.approx(1.0, abs=0.05)


def test_a_plan_without_a_dwell_above_the_corner_is_refused_naming_the_bandwidth():
    with pytest.raises(incal.IncalError, match="bandwidth_hz is not determined"):
        incal.plan.response_sine(f_max_hz=40)


@pytest.mark.parametrize(
    "excitation,window,scipy_window",
    [("random", "hann", "hann"), ("multisine", "rectangular", "boxcar")],
)
def test_the_broadband_h1_and_coherence_equal_scipy(excitation, window, scipy_window):
    """H1 = Pxy/Pxx and γ² by Welch averaging equal scipy.signal.csd,
    welch and coherence on the same data with the same segment length,
    window (Hann, or none for a multisine) and overlap (half), to 1e-9
    relative (align="none": the plain estimate)."""
    from scipy import signal

    data, truth = incal.simulate.response_broadband(
        seed=5, duration_s=8, excitation=excitation, period_samples=512
    )
    x = np.asarray(data["reference"], dtype=float)
    y = np.asarray(data["output"], dtype=float)
    r = incal.response_broadband(data, align="none", segment_samples=512, window=window)
    spec = r.table("spectrum")
    kw = dict(fs=1000.0, nperseg=512, window=scipy_window)
    f, pxy = signal.csd(x, y, **kw)
    _, pxx = signal.welch(x, **kw)
    _, pyy = signal.welch(y, **kw)
    _, coh = signal.coherence(x, y, **kw)
    h1 = pxy / pxx
    k = slice(1, len(f))
    assert np.allclose(spec["freq_hz [Hz]"], f[k], rtol=1e-12)
    # The bins the excitation drives (a multisine leaves the rest at
    # rounding: 1e-28 against 0.25).
    m = pxx[k] > 1e-12 * pxx.max()
    assert m.sum() > 200
    col = lambda name: np.asarray(spec[name], dtype=float)[m]
    assert np.allclose(col("pxx [reference^2/Hz]"), pxx[k][m], rtol=1e-9, atol=0)
    assert np.allclose(col("pyy [output^2/Hz]"), pyy[k][m], rtol=1e-9, atol=0)
    assert np.allclose(col("coherence [1]"), coh[k][m], rtol=1e-9, atol=0)
    assert np.allclose(col("gain [output/reference]"), np.abs(h1[k][m]), rtol=1e-9, atol=0)
    dphi = col("phase_deg [deg]") * np.pi / 180 - np.angle(h1[k][m])
    assert np.allclose(np.angle(np.exp(1j * dphi)), 0.0, atol=1e-9)
    c = r.coefficients
    for name in ("bandwidth_hz", "delay_s", "latency_s"):
        assert abs(c[name].value - truth[name]) <= c[name].U95, name


def test_a_simulated_step_reduces_with_its_truth_inside_u95():
    data, truth = incal.simulate.response_step(seed=8)
    r = incal.response_step(data)
    c = r.coefficients
    assert r.document["procedure"] == "response-step"
    for name in ("rise_time_s", "overshoot_pct", "bandwidth_hz"):
        assert abs(c[name].value - truth[name]) <= c[name].U95, name
