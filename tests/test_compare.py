"""The comparison library used by the cross-code pages."""
import numpy as np

from demflow.analysis import compare_distributions, compare_series


def test_series_comparison_on_shared_steps():
    s = np.arange(0, 100)
    a = 1 + np.sin(s / 5.0)
    c = compare_series(s, a, s[::2], a[::2] * 1.01, after=50)
    assert c.n == 50
    assert abs(c.equilibrium_rel - 0.01) < 1e-12
    assert abs(c.max_rel - 0.01 * np.max(np.abs(a[::2])) / np.max(np.abs(a[::2]))) < 1e-12


def test_distribution_comparison_ks_and_q_model():
    rng = np.random.default_rng(0)
    a = rng.gamma(3.0, 1 / 3.0, 2000)
    same = compare_distributions(a, rng.gamma(3.0, 1 / 3.0, 2000))
    other = compare_distributions(a, rng.exponential(1.0, 2000))
    assert same["ks_pvalue"] > 0.01 and other["ks_pvalue"] < 1e-6
    (_, cia), (_, cib) = same["q_model_a"], same["q_model_b"]
    assert cia[0] < 3.0 < cia[1] and cib[0] < 3.0 < cib[1]
    assert other["q_model_b"][1][1] < 1.5  # exponential: N ≈ 1
    assert np.isclose(np.sum(same["pdf_a"] * np.diff(same["edges"])), 1.0)
