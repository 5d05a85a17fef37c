"""Negative controls of the looser tolerances (issue 18 item 3): a deliberately wrong setting must fail
the check that the right setting passes, so that a pass means something.

Each test runs the case's own check code on a wrong variant (cheap: seconds each).
"""
import pytest

from demflow.cases import get_case
from demflow.cases.base import Check
from demflow.tolerances import tol


def _check(checks, pattern):
    hits = [c for c in checks if pattern in c.name]
    assert hits, f"no check named like {pattern!r}: {[c.name for c in checks]}"
    return hits


def test_table_2_4_one_percent_fails_with_a_hundred_times_softer_contact():
    """impact.rigid-body (1 %): the error against the rigid-body values grows as kN^-1/2 (0.35 % at the
    thesis's kN = 1e7), so kN = 1e5 must fail it and the thesis's kN must pass."""
    case = get_case("thesis-impact")
    for kn, ok in ((1e7, True), (1e5, False)):
        p = case.merged(dict(kn=kn))
        rigid = _check(case.checks(case.run(p), p), "rigid-body value")
        assert all(c.passed for c in rigid) is ok, [(kn, c.name, c.error) for c in rigid]


def test_simple_shear_equilibrium_fails_at_a_rate_that_is_not_quasi_static():
    """simple-shear.equilibrium (1 % rms): the rate study measured 1.73 % at γ̇ = 0.2 /s (loose, seed 1) and
    0.87 % at the default 0.05 /s."""
    from demflow.cases import simple_shear_setup as setup
    from demflow.cases.thesis_simple_shear import equilibrium, run_variant

    case = get_case("thesis-simple-shear")
    spec = setup.compress("loose", 1)
    limit = tol("simple-shear.equilibrium").value
    fast = equilibrium(run_variant(spec, False, case.merged(dict(rate=0.2))))[0]
    slow = equilibrium(run_variant(spec, False, case.merged({})))[0]
    assert fast > limit > slow, (fast, slow)


def test_the_same_frequency_check_fails_when_the_oscillating_system_differs():
    """nine-disc.same-frequency (1e-3): frequencies are per cycle, and Δt is a fixed fraction of
    2√(m/k), so the stiffness drops out; what the check sees is whether the loading speed left the same
    system (contact state). A different system, here the Δt fraction 0.1 instead of 0.08 (a 1.25×
    longer step in units of the oscillation), must fail it."""
    from demflow.cases.cs_nine_disc import oscillation_frequency

    case = get_case("cs-nine-disc")
    p = case.merged({})
    run = case.run(p)
    same = _check(case.checks(run, p), "the same frequency")
    assert all(c.passed for c in same)
    other = case.run(case.merged(dict(dt_fraction=0.1)))
    wrong = oscillation_frequency(other.results["undamped"], 40) / oscillation_frequency(
        run.results["speed-0.04-kn1.35e9"], 120)
    c = Check.against("wrong pairing", wrong, 1.0, "nine-disc.same-frequency", "test")
    assert not c.passed and wrong == pytest.approx(1.25, rel=0.02)
