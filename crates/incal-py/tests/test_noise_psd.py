"""The noise record's power spectral density against scipy.signal.welch on
the same samples (same window, segment and overlap), and the white level
against the simulated truth."""

import math

import numpy as np
import pytest

import incal


@pytest.mark.parametrize("window,scipy_window", [("hann", "hann"), ("rectangular", "boxcar")])
def test_the_psd_equals_scipy_welch(window, scipy_window):
    from scipy import signal

    rng = np.random.default_rng(7)
    n = 1 << 16
    # White rate noise plus a slow wander and an offset (removed per segment).
    y = 3.0 + 0.05 * rng.standard_normal(n) + 1e-4 * np.cumsum(rng.standard_normal(n))
    r = incal.noise(gx=y, rate_hz=100.0, quantity="gyro", psd=True, psd_segment_samples=2048, psd_window=window)
    p = r.document["channels"]["gx"]["psd"]
    f, g = signal.welch(y, fs=100.0, window=scipy_window, nperseg=2048, noverlap=1024, detrend="constant", scaling="density")
    assert np.allclose(p["freq_hz"], f, rtol=1e-12, atol=0)
    # Bin 0 holds only what the mean removal leaves (rounding).
    assert np.allclose(np.asarray(p["density"])[1:], g[1:], rtol=1e-10, atol=0)
    assert p["segments"] == (n - 1024) // 1024
    lo, hi = np.asarray(p["lo"]), np.asarray(p["hi"])
    assert (lo[1:] < g[1:]).all() and (g[1:] < hi[1:]).all()


def test_the_white_level_reads_the_simulated_arw():
    data, truth = incal.simulate.noise(rate_hz=100, duration_s=1800, arw_deg_rth=0.2, seed=4)
    r = incal.noise(data, quantity="gyro", psd=True)
    c = r.coefficients
    # One-sided G = 2 N^2 with N in deg/s*sqrt(s): ASD = sqrt(2) N / 60.
    asd = math.sqrt(2.0) * 0.2 / 60.0
    assert abs(c["ch1.white_asd"].value - asd) <= c["ch1.white_asd"].U95
    white = r.document["channels"]["ch1"]["psd"]["white"]
    assert white["n_unit"] == "deg/sqrt(h)"
    assert abs(white["n_equivalent"] - 0.2) <= 3 * white["u_n_equivalent"]
