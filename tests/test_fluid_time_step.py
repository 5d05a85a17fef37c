"""The coupled time step (issue 4 item 4): the drag-relaxation criterion of demflow.coupling keeps
high-viscosity and near-wall runs stable where a larger step is not."""
import math

import numpy as np
import pytest

from demflow.build import build
from demflow.cases.thesis_falling_disc import FallingDisc
from demflow.scene import Discs, SceneError
from demflow.simulation import BlowUpError

CASE = FallingDisc()


def _unstable(sim, n, v_ref):
    """Run n steps; True if it blows up or the speed exceeds 10 × the terminal velocity."""
    vmax = 0.0
    try:
        for _ in range(n // 50):
            sim.run(50)
            vmax = max(vmax, float(np.hypot(sim.vx[0], sim.vy[0])))
    except BlowUpError:
        return True
    return vmax > 10 * abs(v_ref)


def test_high_viscosity_limit_is_two_relaxation_times():
    """μ = 5000 (100 × thesis §5.1): Δt = 1e-4 s is refused, blows up if forced; the run is stable
    at 0.8 × 2τ (τ = min(m/K, I/K_rot) from BEM solves) and unstable at 1.25 × 2τ."""
    p = CASE.merged(dict(elements=16))
    mu = 5000.0
    with pytest.raises(SceneError, match="fluid drag limit"):
        build(CASE.scene(p, mu=mu, dt=1e-4, name="hv"))
    with pytest.raises(BlowUpError):
        build(CASE.scene(p, mu=mu, dt=1e-4, allow=True, name="hv")).run(200)
    probe = build(CASE.scene(p, mu=mu, dt=1e-6, name="hv"))
    fc = probe.fluid
    tau = float(fc._taus(probe, fc.K0)[0])
    assert tau < float(probe.mass[0] / fc.K0[0])  # spin relaxes faster than translation (I/K_rot = m/8πμ free)
    v_inf = math.pi * p["g"] * p["r"] ** 2 * (p["rho_s"] - p["rho_l"]) / fc.K0[0]
    ok = build(CASE.scene(p, mu=mu, dt=0.8 * 2 * tau, allow=True, name="hv"))
    assert not _unstable(ok, 300, v_inf)
    assert math.isclose(ok.vy[0], v_inf, rel_tol=1e-6)  # steady state of the lagged drag is exact
    bad = build(CASE.scene(p, mu=mu, dt=1.25 * 2 * tau, allow=True, name="hv"))
    assert _unstable(bad, 300, v_inf)


def test_adaptive_stride_follows_the_relaxation_time():
    """With a large stride k the coupling still solves often enough: kΔt <= safety·2τ."""
    p = CASE.merged(dict(elements=24))
    sim = build(CASE.scene(p, dt=1e-4, stride=1000, adaptive=True, name="ad"))
    sim.run(200)
    tau = float(sim.fluid._taus(sim, sim.fluid.K0)[0])
    ks = [k for _, k in sim.fluid.strides]
    assert max(ks) * sim.dt <= 0.5 * 2 * tau + 1e-15 and max(ks) >= 1
    v_inf = math.pi * p["g"] * p["r"] ** 2 * (p["rho_s"] - p["rho_l"]) / sim.fluid.K0[0]
    assert math.isclose(sim.vy[0], v_inf, rel_tol=1e-4)


@pytest.mark.slow
def test_near_wall_run_is_stable_at_the_bound_and_not_far_above():
    """A heavy disc released 0.05 cm above the bottom wall (minimum gap 0.02 cm): the lubrication
    resistance at the minimum gap sets the bound; at the bound the disc lands and comes to rest on the
    wall, at 8 × the bound the lagged drag oscillates and grows."""
    p = CASE.merged(dict(elements=24, rho_s=20.0, min_gap=0.02))

    def sc(fac):
        s = CASE.scene(p, dt=1e-4, allow=True, name="nw", adaptive=True, stride=1000)
        s.discs = Discs([0.0], [-20 + 0.5 + 0.05], [0.5], "disc")
        b = build(s).dt_fluid
        s.dt = fac * b
        return s, b

    s, b = sc(8.0)
    assert _unstable(build(s), 2000, 1.0)
    s, b = sc(1.0)
    sim = build(s)
    assert not _unstable(sim, 2000, 1.0)
    assert sim.y[0] - (-20 + 0.5) < 0.0  # in contact with the wall


def test_wall_resistance_meets_both_known_limits():
    """The one-wall resistance 4πμ/(α − tanh α), cosh α = d/R, that raises K near walls and
    neighbours: at a small gap h it tends to the squeeze film 3√2π μ (R/h)^{3/2} with a first-order
    error in h/R, and far away to 4πμ/(ln(2d/R) − 1) with an error below (R/d)² (both limits from
    2D lubrication and the far-field expansion, independent of the closed form)."""
    from demflow.coupling import wall_resistance

    mu, R = 0.7, 2.0
    hs = R * np.array([1e-2, 1e-3, 1e-4, 1e-5])
    near = np.array([wall_resistance(mu, R, R + h) / (3 * math.sqrt(2) * math.pi * mu * (R / h) ** 1.5) - 1 for h in hs])
    assert np.all(np.abs(near) < 2 * hs / R)
    assert np.all((near[:-1] / near[1:] > 8) & (near[:-1] / near[1:] < 12))  # first order in h
    ds = R * np.array([10.0, 100.0, 1000.0])
    far = np.array([wall_resistance(mu, R, d) / (4 * math.pi * mu / (math.log(2 * d / R) - 1)) - 1 for d in ds])
    assert np.all(np.abs(far) < (R / ds) ** 2)
