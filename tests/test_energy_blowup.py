"""Blow-up detection by energy (issue 17 item 4): each chunk's energy balance closes in a stable run and
does not in an unstable one, even when friction keeps every overlap small.

created = Δ(kinetic + elastic) + dissipated (dashpots, friction, global damping) - work of walls,
gravity and external forces (:meth:`demflow.simulation.Simulation._balance_close`).
"""
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from demflow import (BlowUpError, Discs, GlobalDamping, LinearLaw, Material, Phase, Scene, Servo,
                     UnsafeTimeStepWarning, Wall, build)

import critical_dt as cd

UNIT = math.sqrt(np.pi * cd.DENSITY / cd.KN)
HEX_CRITICAL = 2.0 / math.sqrt(24.0) * UNIT  # every disc spinning: ω² = 24 kS/m (measured in test_time_step)


def _hexagonal(fraction):
    sc = cd.scene(cd.hexagonal(), fraction * HEX_CRITICAL, n_steps=5000)
    sc.allow_supercritical, sc.allow_unsafe_dt = False, fraction > 0.8  # past the build check only when asked
    return sc


def test_hexagonal_packing_above_its_critical_step_is_stopped(tmp_path, monkeypatch):
    """At 1.05× the true critical Δt the spin mode grows until the shear springs slide: overlaps stay near
    their 1 % (the overlap, step-length and non-finite tests stay silent), but the energy the steps create
    is dissipated by friction far faster than anything supplies it: BlowUpError, last good state saved."""
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    with pytest.warns(UnsafeTimeStepWarning):
        sim = build(_hexagonal(1.05))
    with pytest.raises(BlowUpError) as e:
        sim.run()
    assert "energy balance" in str(e.value)
    assert Path(e.value.path).exists()
    z = np.load(e.value.path)
    assert int(str(z["meta"]).split('"step": ')[1].split(",")[0]) == 0  # the chunk's start: the last good state
    # the state it stopped in had no overlap beyond 2 % of a radius: only the energy saw it
    assert sim.step == 0 and np.all(np.isfinite(z["x"]))


def test_hexagonal_packing_overlaps_stay_small_while_it_blows_up():
    """The same run, stepped in 2-step pieces (the spin mode grows about 1.6× per step): kinetic energy
    grows by orders of magnitude while the largest overlap stays below 2 % of the radius (the overlap test
    fires at 50 %), until the balance stops it."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnsafeTimeStepWarning)
        sim = build(_hexagonal(1.05))
    e0 = cd.kinetic(sim)
    grown, worst = 0.0, 0.0
    with pytest.raises(BlowUpError):
        for _ in range(100):
            sim.run(2)  # a 2-step chunk: the balance is checked at its end
            grown = max(grown, cd.kinetic(sim) / e0)
            worst = max(worst, float(sim.contact_table_arrays()["overlap"].max()))
    assert grown > 100.0 and worst < 0.02, (grown, worst)


@pytest.mark.parametrize("fraction", [0.5, 0.95])
def test_stable_hexagonal_packing_runs_and_its_balance_closes(fraction):
    """Negative control: below the critical Δt (0.95× is above the safe estimate: build warns) the run
    completes; with no dissipation and no work the balance closes to round-off (measured ≤ 1.4e-14)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnsafeTimeStepWarning)
        sim = build(_hexagonal(fraction))
    for _ in range(5):
        sim.run(1000)
        b = sim.energy_balance
        assert abs(b["created"]) <= 1e-10 * b["supplied"], b


def _floor_scene(name, disc, walls, **kw):
    law = LinearLaw(kn=1e5, ks=0.8e5, cn=50.0, cs=20.0, friction=0.5)
    return Scene(name=name, discs=disc, materials={"g": Material(density=2.0), "w": Material()},
                 laws={("g", "w"): law}, walls=walls, gravity=(0.0, -10.0), dt=1e-3, **kw)


FLOOR = Wall("floor", (0.0, 0.0), (1.0, 0.0), -100.0, 100.0, "w")


@pytest.mark.parametrize("name, disc, walls, kw", [
    ("sliding", Discs(x=[0.0], y=[1.0], radius=[1.0], material="g", velocity=[[3.0, 0.0]]), [FLOOR], {}),
    ("bouncing", Discs(x=[0.0], y=[1.5], radius=[1.0], material="g", velocity=[[2.0, -1.0]], angular_velocity=[5.0]),
     [FLOOR], dict(damping=GlobalDamping(C=0.5, C_rot=0.1))),
    ("shaken", Discs(x=[0.0], y=[1.0], radius=[1.0], material="g"),
     [Wall("floor", (0.0, 0.0), (1.0, 0.0), -100.0, 100.0, "w",
           phases=tuple(Phase(1, velocity=(0.2, 0.3 * (-1) ** k)) for k in range(2000)))], {}),
    ("servo", Discs(x=[0.0], y=[1.0], radius=[1.0], material="g"),
     [FLOOR, Wall("lid", (0.0, 2.0), (-1.0, 0.0), -100.0, 100.0, "w",
                   servo=Servo(force=2e3, direction=(0.0, -1.0), gain=20.0, v_max=8.0))], {}),
])
def test_dissipation_and_work_are_accounted(name, disc, walls, kw):
    """Friction slip, dashpots, global damping, gravity, a wall shaken every step and a servo wall: the
    energy each 200-step chunk creates is below 5 % of what it started with and was given (measured: 2.4 %
    bouncing, the incremental normal spring's start at a contact; 0.19 % sliding, 0.76 % shaken, 0.76 % the
    servo lid, whose gain moves it by its whole force error each step), a fifth of the blow-up tolerance,
    and the accounts are not empty (dissipation and work happened)."""
    sim = build(_floor_scene(name, disc, walls, **kw))
    moved = 0.0
    for _ in range(10):
        sim.run(200)
        b = sim.energy_balance
        assert abs(b["created"]) <= 0.05 * b["supplied"], b
        moved += b["dissipated_contacts"] + b["dissipated_damping"] + abs(b["work_walls"])
    assert moved > 0.0


def test_energy_check_warn_lets_the_run_go_on():
    """energy_check="warn" (a shipped case kept as it is until its owner decides): the same unstable run
    warns and completes."""
    from demflow import EnergyBalanceWarning

    sc = _hexagonal(1.05)
    sc.energy_check, sc.n_steps = "warn", 300
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnsafeTimeStepWarning)
        sim = build(sc)
    with pytest.warns(EnergyBalanceWarning, match="energy balance"):
        sim.run()
    assert sim.step == 300
