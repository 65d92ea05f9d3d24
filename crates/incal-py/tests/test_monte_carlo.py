"""The Monte Carlo propagation (JCGM 101) from Python: the keywords
``monte_carlo``, ``seed`` and ``mc_digits`` give the CLI's document for
the same file; with a known noise the Monte Carlo standard deviations are
the GUM u within the sampling error of a standard deviation (scipy's χ²
quantiles); a ratio with a poor denominator is not validated; and the
refusals name the keyword."""

import json
import os
import pathlib
import subprocess

import pytest
from scipy import stats

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]
BIN = os.environ.get("INCAL_BIN", str(ROOT / "target" / "debug" / "incal"))

RATIO = dict(k1=1, k0_g=5, k2=0, k3=0, delta_o_arcsec=0, k_ip=0, noise=0.8, samples=4, seed=3)


def recording(tmp_path, name, **kw):
    data, _ = incal.simulate.tumble(**kw)
    path = tmp_path / name
    data.to_csv(path, index=False)
    return path


def test_python_equals_the_cli(tmp_path):
    path = recording(tmp_path, "ratio.csv", **RATIO)
    r = incal.tumble(path, mount="pendulum", terms="K0,K1", monte_carlo=300, seed=7)
    out = subprocess.run(
        [BIN, "tumble", "--input", str(path), "--mount", "pendulum", "--terms", "K0,K1",
         "--monte-carlo", "300", "--seed", "7", "--json"],
        capture_output=True, check=True,
    ).stdout
    assert r.document["monte_carlo"] == json.loads(out)["monte_carlo"]
    k0 = r.document["monte_carlo"]["coefficients"]["K0"]
    assert k0["validated"] is False
    assert any(w["code"] == "gum-not-validated" for w in r.document["warnings"])
    # The same seed, the same numbers; the keyword as text too.
    again = incal.tumble(path, mount="pendulum", terms="K0,K1", monte_carlo="300", seed=7)
    assert again.document["monte_carlo"] == r.document["monte_carlo"]


def test_known_noise_std_is_the_gum_u(tmp_path):
    path = recording(tmp_path, "linear.csv", k1=1, k0_g=0.01, k2=0, k3=0, delta_o_arcsec=0,
                     k_ip=0, noise=1e-3, samples=10, seed=4)
    m = 2000
    r = incal.tumble(path, mount="pendulum", terms="K0,K1", noise=1e-3, monte_carlo=m, seed=2)
    mc = r.document["monte_carlo"]
    # (M − 1) s²/σ² is χ² with M − 1 degrees of freedom: the ratio s/u lies
    # in its 99.9 % interval.
    lo, hi = ((stats.chi2.ppf(q, m - 1) / (m - 1)) ** 0.5 for q in (0.0005, 0.9995))
    for name, c in r.coefficients.items():
        ratio = mc["coefficients"][name]["std"] / c.u
        assert lo <= ratio <= hi, (name, ratio, lo, hi)


def test_auto_and_refusals(tmp_path):
    path = recording(tmp_path, "auto.csv", **RATIO)
    r = incal.tumble(path, mount="pendulum", terms="K0,K1", noise=0.8, monte_carlo="auto")
    mc = r.document["monte_carlo"]
    assert mc["requested"] == "auto" and mc["stabilised"] is True
    assert mc["trials"] + mc["failed"]["count"] >= 20000
    with pytest.raises(incal.InputError) as e:
        incal.tumble(path, mount="pendulum", monte_carlo=10)
    assert e.value.option == "monte_carlo"
    with pytest.raises(incal.InputError) as e:
        incal.tumble(path, mount="pendulum", seed=3)
    assert e.value.option == "seed"
    with pytest.raises(incal.InputError) as e:
        incal.tumble(path, mount="pendulum", monte_carlo=200, mc_digits=7)
    assert e.value.option == "mc_digits"
