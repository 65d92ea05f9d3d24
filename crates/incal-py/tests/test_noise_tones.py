"""Lines in the noise record's PSD: the frequency and rms amplitude incal
reports equal scipy.optimize.least_squares fitting the same model
(offset, slope and sinusoid) to the same samples, and a simulated line is
found within its U95."""

import math

import numpy as np

import incal


def test_a_line_equals_scipy_least_squares_on_the_same_samples():
    from scipy import optimize

    rng = np.random.default_rng(11)
    fs, n = 200.0, 60_000
    t = np.arange(n) / fs
    y = 0.2 + 0.01 * rng.standard_normal(n) + 0.02 * math.sqrt(2) * np.sin(2 * math.pi * 23.3 * t + 0.4)
    r = incal.noise(gx=y, rate_hz=fs, quantity="gyro", psd=True, psd_segment_samples=4096)
    tones = r.document["channels"]["gx"]["psd"]["tones"]
    assert len(tones) == 1, tones
    line = tones[0]
    tc = t - 0.5 * (n - 1) / fs

    def residual(p):
        c0, c1, a, b, f = p
        w = 2 * math.pi * f * tc
        return c0 + c1 * tc + a * np.cos(w) + b * np.sin(w) - y

    fit = optimize.least_squares(residual, [0.2, 0.0, 0.02, 0.0, line["frequency_hz"]], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    a, b, f = fit.x[2], fit.x[3], fit.x[4]
    assert abs(line["frequency_hz"] - f) <= 1e-3 * line["u_frequency_hz"]
    amp = math.sqrt((a * a + b * b) / 2)
    assert abs(line["amplitude_rms"] - amp) <= 1e-3 * line["u_amplitude_rms"]
    k = line["k95"]
    assert abs(line["frequency_hz"] - 23.3) <= k * line["u_frequency_hz"]
    assert abs(line["amplitude_rms"] - 0.02) <= k * line["u_amplitude_rms"]


def test_a_simulated_line_is_found_within_its_u95():
    data, _ = incal.simulate.noise(rate_hz=200, duration_s=300, arw_deg_rth=0.3, tones=[{"frequency_hz": 37.0, "amplitude_rms": 0.01}], seed=8)
    r = incal.noise(data, quantity="gyro", psd=True)
    tones = r.document["channels"]["ch1"]["psd"]["tones"]
    assert len(tones) == 1
    line = tones[0]
    assert abs(line["frequency_hz"] - 37.0) <= line["k95"] * line["u_frequency_hz"]
    assert abs(line["amplitude_rms"] - 0.01) <= line["k95"] * line["u_amplitude_rms"]
    assert any(w["code"] == "tones" for w in r.document["warnings"])


def test_a_gauss_markov_bias_from_python():
    data, _ = incal.simulate.noise(rate_hz=100, duration_s=7200, arw_deg_rth=0.6, gm_sigma=0.01, gm_tau_s=100, seed=4)
    r = incal.noise(data, quantity="gyro", gauss_markov=True, gm_filter_rate_hz=200)
    c = r.coefficients
    assert abs(c["ch1.gm_sigma"].value - 0.01) <= c["ch1.gm_sigma"].U95
    assert abs(c["ch1.gm_tau_c_s"].value - 100) <= c["ch1.gm_tau_c_s"].U95
    g = r.document["channels"]["ch1"]["gauss_markov"]
    assert g["filter_rate_hz"] == 200 and 0 < g["phi"] < 1
