"""The dynamic Allan variance and noise against temperature from Python:
each window's ADEV equals an overlapping Allan deviation written here with
numpy on the same samples; a noise that doubles half-way raises the
non-stationary warning; a temperature_c array is the environment, not a
channel, and bins the record by temperature."""

import warnings

import numpy as np

import incal


def _oadev(y, m, tau0):
    """Overlapping Allan deviation of rate samples y at tau = m tau0."""
    x = np.concatenate([[0.0], np.cumsum(y) * tau0])
    d = x[2 * m:] - 2 * x[m:-m] + x[: -2 * m]
    return np.sqrt(np.mean(d * d) / (2 * (m * tau0) ** 2))


def test_each_window_equals_numpy_and_a_step_is_warned():
    rng = np.random.default_rng(4)
    fs, n = 10.0, 40_000
    y = 0.01 * rng.standard_normal(n)
    y[n // 2:] *= 2.0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = incal.noise(gx=y, rate_hz=fs, davar="400,200")
    d = r.document["channels"]["gx"]["davar"]
    assert d["window_samples"] == 4000 and d["step_samples"] == 2000
    assert d["windows"] == (n - 4000) // 2000 + 1
    for j in (0, 7, d["windows"] - 1):
        start = round(d["start_s"][j] * fs)
        for k, tau in enumerate(d["taus_s"]):
            want = _oadev(y[start:start + 4000], round(tau * fs), 1 / fs)
            assert abs(d["adev"][j][k] - want) <= 1e-10 * want, (j, tau, d["adev"][j][k], want)
    assert d["test"]["non_stationary"] is True
    codes = [getattr(w.category, "code", None) for w in caught]
    assert "non-stationary" in codes, codes


def test_a_temperature_array_bins_the_record():
    rng = np.random.default_rng(5)
    fs, n = 10.0, 80_000
    t_c = np.linspace(-20.0, 60.0, n, endpoint=False)
    arw = 0.5 * (1 + 0.005 * (t_c - 25.0))
    y = rng.standard_normal(n) * arw / 60.0 * np.sqrt(fs)
    r = incal.noise(gx=y, temperature_c=t_c, rate_hz=fs, quantity="gyro", temperature_bin_c=20.0)
    doc = r.document
    assert list(doc["channels"]) == ["gx"]
    assert abs(doc["environment"]["temperature_c"]["mean"] - t_c.mean()) < 1e-9
    bins = doc["channels"]["gx"]["temperature"]["bins"]
    assert [b["t_low_c"] for b in bins] == [-20.0, 0.0, 20.0, 40.0]
    c = doc["coefficients"]
    for name, want in [("gx.ARW.c0", 0.5), ("gx.ARW.c1", 0.0025)]:
        # one record: a gross check (the Rust tests measure the coverage)
        assert abs(c[name]["value"] - want) <= 2 * c[name]["U95"], (name, c[name])
