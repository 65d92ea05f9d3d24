"""Repeatability: the nested analysis of variance against numpy's by-hand
computation on the same runs (balanced and unbalanced), and the runs of
result documents."""

import numpy as np
import pytest

import incal


def by_hand(day, x, u):
    """The method-of-moments components (turn-on, day) as numpy computes them."""
    days = list(dict.fromkeys(day))
    groups = [x[np.asarray(day) == d] for d in days]
    n, k = len(x), len(groups)
    means = np.array([g.mean() for g in groups])
    sizes = np.array([len(g) for g in groups], dtype=float)
    ms_on = sum(((g - m) ** 2).sum() for g, m in zip(groups, means)) / (n - k)
    ms_day = (sizes * (means - x.mean()) ** 2).sum() / (k - 1)
    t0 = (n - (sizes**2).sum() / n) / (k - 1)
    s2_on = ms_on - np.mean(u**2)
    s2_day = (ms_day - ms_on) / t0
    return np.sqrt(max(s2_on, 0.0)), np.sqrt(max(s2_day, 0.0))


@pytest.mark.parametrize("drop", [0, 2])
def test_the_analysis_of_variance_equals_numpy(drop):
    data, truth = incal.simulate.repeatability(days=6, turn_ons_per_day=4, seed=9)
    if drop:
        data = data.iloc[:-drop]
    r = incal.repeatability(data, coefficient="K1")
    on, day = by_hand(list(data["day"]), data["value"].to_numpy(), data["u"].to_numpy())
    c = r.coefficients
    assert c["turn_on_repeatability"].value == pytest.approx(on, rel=1e-9)
    assert c["day_repeatability"].value == pytest.approx(day, rel=1e-9)
    x = data["value"].to_numpy()
    assert c["repeatability_simple"].value == pytest.approx(np.std(x, ddof=1), rel=1e-9)
    assert r.document["repeatability"]["method"] == "anova"


def test_u_spread_over_three_is_weighted():
    data, _ = incal.simulate.repeatability(days=5, turn_ons_per_day=3, u_spread=10, seed=2)
    r = incal.repeatability(data)
    assert r.document["repeatability"]["method"] == "weighted"
    assert any("Paule-Mandel" in d["message"] for d in r.document["decisions"])


def test_two_days_are_refused_naming_the_level():
    data, _ = incal.simulate.repeatability(days=2, seed=2)
    with pytest.raises(Exception, match="day level"):
        incal.repeatability(data)
