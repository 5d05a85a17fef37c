"""Blow-up detection by energy in 3D (issue 17 item 4): a window's energy balance shows the energy an
unstable step created, even when friction keeps every overlap small (before it: the packing below grew its
kinetic energy 6.6e12-fold at 1.05× its critical step and no test fired).

created = Δ(kinetic + elastic) + dissipated by the contacts - work of the planes, fixed spheres and gravity
(:meth:`demflow.simulation3d.Simulation3D._balance_close`); the laws report their dashpot and slip dissipation
(:func:`demflow.laws.base.law_force3`), checked here against an impact and a sliding ball.
The face-centred cubic packing of :mod:`critical_dt3d` has a measured critical time step (nothing here
reads demflow's estimate); above it the spin mode grows until the contacts slide.
"""
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import demflow as df
from demflow.tolerances import tol

import critical_dt3d as cd


@pytest.fixture(scope="module")
def critical():
    est = df.build(cd.fcc(dt=1e-12, allow_supercritical=True)).dt_safe
    return cd.measured_critical_dt(est, 4.0 * est, rel=1e-2)


def _fcc(dt, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return df.build(cd.fcc(dt=dt, allow_supercritical=True, n_steps=5000, **kw))


def _max_overlap(sim):
    return float(sim.pairs.ovl.max() / cd.R)


def test_fcc_above_its_critical_step_is_stopped(critical, tmp_path, monkeypatch):
    """At 1.05× the measured critical Δt the kinetic energy grows by twelve orders of magnitude while the
    largest overlap stays below 2 % of the radius (the overlap test fires at 50 %): BlowUpError by the energy
    balance, with the last good state (the window's start) saved."""
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    sim = _fcc(1.05 * critical)
    with pytest.raises(df.BlowUpError) as e:
        sim.run()
    assert "energy balance" in str(e.value)
    assert Path(e.value.path).exists()
    assert sim.step == 0 and np.all(np.isfinite(sim.spheres.pos))
    eb = sim.energy_balance
    assert eb["created"] > tol("energy.blow-up-3d").value * eb["supplied"]


def test_fcc_overlaps_stay_small_while_it_blows_up(critical):
    """The same run with the check set to warn: the overlaps stay small (so only the energy sees it) and
    the kinetic energy grows by orders of magnitude."""
    sim = _fcc(1.05 * critical, energy_check="warn")
    e0 = cd.kinetic(sim)
    with pytest.warns(df.EnergyBalanceWarning, match="energy balance"):
        sim.run()
    assert cd.kinetic(sim) / e0 > 1e6 and _max_overlap(sim) < 0.02, (cd.kinetic(sim) / e0, _max_overlap(sim))


def test_fcc_below_its_critical_step_runs_and_the_balance_closes(critical):
    sim = _fcc(0.95 * critical)
    sim.run()
    eb = sim.energy_balance
    assert eb["end"] == 5000
    assert abs(eb["created"]) <= 1e-9 * eb["supplied"], eb


def test_a_run_in_short_pieces_is_stopped_too(critical):
    """The balance window carries over from one run() to the next while nothing else changes the state,
    so 25-step pieces are checked as one run and stopped."""
    sim = _fcc(1.05 * critical)
    with pytest.raises(df.BlowUpError, match="energy balance"):
        for _ in range(200):
            sim.run(25)


def test_a_state_changed_between_runs_opens_a_new_window():
    """Energy a user puts in between runs (here: every sphere set moving) is not created by the steps."""
    sim = df.build(cd.fcc(n_steps=400, dt_fraction=0.05))
    sim.run(200)
    assert sim.energy_balance["start"] == 0
    sim.spheres.vel[:] += np.array([0.0, 0.0, 0.5])  # a kick far larger than the energy stored
    sim.run(200)
    eb = sim.energy_balance
    assert eb["start"] == 200 and eb["end"] == 400
    assert eb["created"] <= tol("energy.blow-up-3d").value * eb["supplied"]


def test_work_of_a_fixed_sphere_is_counted():
    """A fixed sphere driven at 1 m/s into a free one of the same mass (elastic, no gravity): the free sphere
    leaves at about 2 m/s, four times the kinetic energy in the scene before; the fixed sphere's work supplies
    it, so nothing is created.  Without that work the balance would show created ≈ 4 × supplied."""
    law = df.HertzMindlinLaw(friction=0.0, restitution=1.0)
    sc = df.Scene3D(name="push", spheres=df.Spheres(x=[0.0, 0.025], y=[0.0, 0.0], z=[0.0, 0.0], radius=[0.01, 0.01],
                                                    material="m", velocity=[[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
                                                    fixed=[True, False]),
                    materials={"m": df.Material(density=2650.0, young=7e9, poisson=0.2)}, laws={("m", "m"): law},
                    dt_fraction=0.05, n_steps=20000)
    sim = df.build(sc).run()
    assert sim.spheres.vel[1, 0] > 1.9  # it was pushed away
    eb = sim.energy_balance
    m = sim.spheres.mass[1]
    assert eb["work_walls"] == pytest.approx(0.5 * m * sim.spheres.vel[1, 0] ** 2, rel=1e-2)
    assert abs(eb["created"]) < 1e-2 * eb["supplied"], eb


def test_the_tolerance_separates_stable_from_unstable(critical):
    """Negative control of 'energy.blow-up-3d': the stable run's created energy is far below it, the unstable
    one's above it (both measured, not assumed)."""
    limit = tol("energy.blow-up-3d").value
    stable = _fcc(0.95 * critical)
    stable.run(2500)
    unstable = _fcc(1.05 * critical, energy_check="warn")
    with pytest.warns(df.EnergyBalanceWarning):
        unstable.run(2500)
    r_stable = stable.energy_balance["created"] / stable.energy_balance["supplied"]
    r_unstable = unstable.energy_balance["created"] / unstable.energy_balance["supplied"]
    assert r_stable < limit / 100 and r_unstable > limit, (r_stable, r_unstable)
    assert math.isfinite(r_unstable)


def _ball_on_floor(name, velocity, friction=0.0, restitution=1.0, n_steps=20000, z=0.0101, dt_fraction=0.05, **kw):
    law = df.HertzMindlinLaw(friction=friction, restitution=restitution)
    return df.Scene3D(name=name, spheres=df.Spheres(x=[0.0], y=[0.0], z=[z], radius=[0.01], material="m",
                                                    velocity=[velocity]),
                      materials={"m": df.Material(density=2650.0, young=7e9, poisson=0.2)}, laws={("m", "m"): law},
                      planes=[df.Plane("floor", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "m")], gravity=(0.0, 0.0, -9.81),
                      dt_fraction=dt_fraction, n_steps=n_steps, **kw)


def _drop(dt_fraction):
    sc = _ball_on_floor("drop", [0.0, 0.0, -1.0], restitution=0.5, dt_fraction=dt_fraction,
                        n_steps=int(round(200 / dt_fraction)))
    return df.build(sc).run().energy_balance


def test_the_dashpot_dissipation_is_the_energy_an_impact_loses():
    """A ball falling onto the floor at 1 m/s, e = 0.5: the contacts report dissipated the mechanical energy
    lost (about 3/4 of ½mv²), and what the balance leaves over is first-order discretisation: it halves with
    Δt (measured 2026-11-24: 4.8e-3, 2.4e-3, 1.2e-3 of the supplied energy at Δt fractions 0.05, 0.025,
    0.0125), where a wrong dissipation would leave a fixed fraction of ½mv²."""
    coarse, fine = _drop(0.05), _drop(0.025)
    m = 2650.0 * 4.0 / 3.0 * math.pi * 1e-6
    assert coarse["dissipated_contacts"] > 0.5 * 0.5 * m * 1.0
    r = [abs(e["created"]) / e["supplied"] for e in (coarse, fine)]
    assert r[1] / r[0] == pytest.approx(0.5, abs=0.05), r  # first order: halves with Δt


def test_the_slip_dissipation_is_the_work_of_friction():
    """A ball launched along the floor at 0.3 m/s with μ = 0.5 slides for 2v/(7μg) = 17 ms, then rolls: the
    slip the law reports dissipated equals the kinetic energy lost (2/7 of ½mv² for a ball that ends rolling),
    and the balance closes to round-off.  It starts resting on the floor: Hertz's static overlap
    (m g / (4/3 E* √R))^(2/3) = 0.37 µm.  20000 steps (33 ms): one window.  Tolerance, a priori: sliding stops
    within one step, so the slip energy is off by at most μ m g v Δt against 2/7 · ½ m v², a relative
    7 μ g Δt / v = 1.9e-4 at Δt = 0.05 × the Rayleigh step (1.65 µs); 1e-3 leaves 5× for the vertical
    contact oscillation."""
    m = 2650.0 * 4.0 / 3.0 * math.pi * 1e-6
    estar = 7e9 / (2.0 * (1.0 - 0.2 ** 2))
    rest = (m * 9.81 / (4.0 / 3.0 * estar * math.sqrt(0.01))) ** (2.0 / 3.0)
    sim = df.build(_ball_on_floor("slide", [0.3, 0.0, 0.0], friction=0.5, n_steps=20000, z=0.01 - rest)).run()
    assert sim.spheres.vel[0, 0] == pytest.approx(5.0 / 7.0 * 0.3, rel=1e-2)  # rolling
    eb = sim.energy_balance
    assert eb["start"] == 0 and eb["end"] == 20000
    assert eb["dissipated_contacts"] == pytest.approx(2.0 / 7.0 * 0.5 * m * 0.3 ** 2, rel=1e-3)
    assert abs(eb["created"]) < 1e-9 * eb["supplied"], eb


def _damped_drop(dt_fraction, **damping):
    """The 1 m/s drop of :func:`_drop` (e = 0.5) with a damping; long enough for the ball to come to rest."""
    sc = _ball_on_floor("damped-drop", [0.0, 0.0, -1.0], restitution=0.5, dt_fraction=dt_fraction,
                        n_steps=int(round(400 / dt_fraction)), **damping)
    return df.build(sc).run().energy_balance


@pytest.mark.parametrize("damping", [dict(local_damping=0.3), dict(damping=df.GlobalDamping(alpha=20.0)),
                                     dict(damping=df.GlobalDamping(C=0.2, C_rot=1e-6))],
                         ids=["local", "alpha", "absolute"])
def test_a_damped_runs_balance_closes_with_the_damping_work(damping):
    """The damping's work (the running sum of every step, ``work_damping`` ≤ 0) enters the balance: a damped
    drop closes as an undamped one, to first order in Δt (the residual halves with Δt, as the undamped
    drop's), where leaving the damping out would leave its whole work over, a fixed fraction of the
    supplied energy (the negative control below)."""
    coarse, fine = _damped_drop(0.05, **damping), _damped_drop(0.025, **damping)
    for eb in (coarse, fine):
        assert eb["work_damping"] < -0.05 * eb["supplied"], eb  # the damping took a real share
        left_out = eb["created"] + eb["work_damping"]  # the balance without the damping's work
        assert abs(left_out) > 0.05 * eb["supplied"], eb  # negative control: it would not close
    r = [abs(e["created"]) / e["supplied"] for e in (coarse, fine)]
    assert r[0] < 1e-2 and r[1] / r[0] == pytest.approx(0.5, abs=0.1), r
