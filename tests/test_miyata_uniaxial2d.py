"""miyata-uniaxial-2d (issue 15 item 2; Miyata §3.2, Tables 1-2, Figs 26, 29, 30) and the periodic box
of the superquadric cycle it needs.

Default tests: the periodic superquadric pair against the same pair inside the box, the case's scenes
(Table 1-2 values, eq 60), its analysis helpers on hand-made curves, a short run of the reduced
variant (a shallow bed, loaded to 300 kPa) whose checks are well-formed, and negative controls (a
wrong particle size fails the equal-mass check; an inertial plate speed fails the quasi-static
check).  The reduced variant itself and the full variant are ``slow``."""
from __future__ import annotations

import inspect
import math

import numpy as np
import pandas as pd
import pytest

from demflow import Box, ContactModel, LinearLaw, Material, Outputs, Scene, build
from demflow.cases import CASES
from demflow.cases import miyata_uniaxial2d as m
from demflow.cases.base import INFO, MISS
from demflow.scene import Superquadrics
from demflow.tolerances import KINDS, TOLERANCES


# ----------------------------------------------------------------------------- the periodic superquadric box
def _pair_scene(x, box):
    return Scene(name="pair", discs=Superquadrics(x=x, y=[1.0, 1.05], a=[0.195, 0.195], b=[0.0976, 0.0976],
                                                  n=[4.0, 4.0], theta=[0.3, 1.2], material="r"),
                 materials={"r": Material(density=1650.0)}, laws={("r", "r"): LinearLaw(kn=1e7, ks=1e7, friction=0.5)},
                 contact_model=ContactModel(normal="overlap"), dt=1e-4, box=box, overlap_tolerance=0.5,
                 outputs=Outputs(every=0))


def test_a_pair_across_the_periodic_boundary_feels_what_it_feels_inside_the_box():
    inside = build(_pair_scene([1.0, 1.29], Box(periodic_x=(0.0, 2.0)))).run(5)
    across = build(_pair_scene([1.85, 0.14], Box(periodic_x=(0.0, 2.0)))).run(5)  # 0.14 + 2 - 1.85 = 0.29 apart
    open_ = build(_pair_scene([1.0, 1.29], Box())).run(5)
    ci, ca, co = inside.contacts(), across.contacts(), open_.contacts()
    assert ci["fn"].size == 1 and ca["fn"].size == 1 and ci["fn"][0] > 0
    assert ca["fn"][0] == pytest.approx(ci["fn"][0], rel=1e-9) and co["fn"][0] == ci["fn"][0]
    ua, ui = across.unwrapped_positions(), inside.unwrapped_positions()
    assert ua[0][0] - 0.85 == pytest.approx(ui[0][0] - 0.0, abs=1e-9)  # the same motion, shifted by 0.85
    assert (ua[0][1] + 2.0 * (ua[0][1] < 1.0)) - ua[0][0] == pytest.approx(ui[0][1] - ui[0][0], abs=1e-9)


def test_a_periodic_box_narrower_than_twice_the_reach_is_refused():
    from demflow import SceneError

    with pytest.raises(SceneError, match="periodic_x"):
        build(_pair_scene([0.2, 0.5], Box(periodic_x=(0.0, 0.6))))


# ----------------------------------------------------------------------------- scenes and parameters
def test_the_case_is_registered_with_its_reduced_variant_by_default():
    c = CASES["miyata-uniaxial-2d"]
    assert c.params["variant"] == "reduced" and not c.slow
    q = c.resolved(c.merged())
    assert (q["width"], q["n_seeds"], q["plate_speed"]) == (2.0, 1, 0.1)
    q = c.resolved(c.merged({"variant": "full"}))
    assert (q["width"], q["n_seeds"], q["plate_speed"]) == (10.0, 8, 0.01)
    with pytest.raises(ValueError, match="wavelength"):
        c.resolved(c.merged({"width": 3.0}))


def test_scenes_carry_tables_1_and_2():
    p = m.MiyataUniaxial2D.resolved(m.MiyataUniaxial2D().merged())
    for shape, (a, b, n) in (("C", (0.15, 0.15, 2.0)), ("S", (0.195, 0.0976, 4.0))):
        sc = m.insertion_scene(shape, 2.0, 1, p)
        d = sc.discs
        assert len(d) == m.particle_count(2.0, p) and np.all(np.asarray(d.a) == a) and np.all(np.asarray(d.b) == b)
        assert np.all(np.asarray(d.n) == n) and d.restitution == 0.01 and sc.dt == 1.7078e-4
        assert sc.materials["rock"].density == 1650.0 and sc.box.periodic_x == (0.0, 2.0)
        pp, pw = sc.laws[("rock", "rock")], sc.laws[("rock", "wall")]
        assert (pp.kn, pp.ks, pw.kn, pw.ks, pw.friction) == (1e7, 1e7, 1e8, 1e8, 0.51)
        assert pp.friction == (p["mu_deposit_circles"] if shape == "C" else 0.51)
        sim = build(sc)  # no overlaps, inside the box
        assert sim.n == len(d) and np.all(sim.bodies.y > 0)


def test_eq_60_surface():
    x = np.array([0.0, 0.5, 1.0, 1.5])
    assert np.allclose(m.surface(x, False), 2.7)
    assert np.allclose(m.surface(x, True), [2.7, 3.0, 2.7, 2.4])


# ----------------------------------------------------------------------------- analysis on hand-made curves
def _curve(settlement, stress):
    return pd.DataFrame({"settlement": settlement, "stress": stress})


def test_stress_drops_are_found_above_250_kPa_only_beyond_the_threshold():
    s = np.linspace(0, 1, 101)
    sig = 1e6 * s
    sig[60:63] = [0.62e6, 0.55e6, 0.57e6]  # a 10 % drop after 600 kPa
    sig[80] = 0.80e6 * 0.99                # a 1 % dip
    sig[10:12] = [0.05e6, 0.01e6]          # a drop below 250 kPa
    d = m.stress_drops(_curve(s, sig), 0.03)
    assert len(d) == 1 and d[0][1] == pytest.approx(0.62e6) and d[0][2] == pytest.approx(0.55e6)
    assert m.stress_drops(_curve(s, 1e6 * s), 0.03) == []


def test_regime_stiffness_of_a_piecewise_linear_curve():
    s = np.array([0.0, 0.1, 0.2, 0.4, 0.6])
    sig = np.array([0.0, 50e3, 250e3, 650e3, 1050e3])
    k1, k2, k3a, k3b = m.regime_stiffness(_curve(s, sig))
    assert (k1, k2) == (pytest.approx(5e5), pytest.approx(2e6)) and k3a == pytest.approx(2e6)
    assert k3b == pytest.approx(2e6)
    assert m.at_stress(_curve(s, sig), 450e3) == pytest.approx(0.3)


# ----------------------------------------------------------------------------- a short run of the case
SHORT = dict(fill_height=1.0, stress_max=300e3, deposit_max=30000, settle_max=20000, settle_ke=1e-4, plate_speed=0.2)


@pytest.fixture(scope="module")
def short_run():
    c = CASES["miyata-uniaxial-2d"]
    p = c.merged(SHORT)
    return c, p, c.run(p)


def test_a_short_run_gives_well_formed_checks_and_figures(short_run, tmp_path):
    c, p, run = short_run
    S = run.extras["samples"]
    assert set(S) == {"CS", "CR", "SS", "SR"}
    for s, by_seed in S.items():
        r = by_seed[1]
        cv = r["curve"]
        assert cv.stress.iloc[-1] >= 300e3 and np.all(np.isfinite(cv.stress)) and r["plate_contacts_final"] >= 1
        assert sum(r["shares"]) == pytest.approx(1.0) and cv.settlement.iloc[-1] > 0
    checks = c.checks(run, p)
    names = [ch.name for ch in checks]
    assert len(names) == len(set(names))
    for ch in checks:
        assert ch.kind in KINDS and ch.source.startswith("Miyata §3.2") and ch.why
        if ch.kind not in (INFO, MISS):
            assert isinstance(ch.passed, bool)
    statements = [ch for ch in checks if ch.kind != INFO]
    assert len(statements) == 4 * 8 + 2 * 2 + 2 * 4 + 1  # per sample (+2 superquadrics), per smooth/rough pair, Table 1
    src = inspect.getsource(m)
    for tname in [k for k in TOLERANCES if k.startswith("miyata2d.")]:
        assert f'"{tname}"' in src, tname  # every tolerance is used
    for ch in checks:
        if ch.kind == MISS:  # the shallow bed resolves few contacts: a miss names its count, never a pass
            assert not ch.passed and ("Not resolved by this variant" in ch.why or (ch.name.startswith("Fig. 26 C")))
    paths = c.figures(run, p, tmp_path)
    assert len(paths) == 4 and all((tmp_path / p_.split("/")[-1]).stat().st_size > 1000 for p_ in paths)
    tabs = c.tables(run, p)
    assert len(tabs[0][1]) == 4


def test_the_quasi_static_check_passes_at_the_variant_speed(short_run):
    c, p, run = short_run
    bal = [ch for ch in c.checks(run, p) if "quasi-static" in ch.name]
    assert len(bal) == 4 and all(ch.passed for ch in bal), [(ch.name, ch.value) for ch in bal]


# ----------------------------------------------------------------------------- negative controls
def test_negative_control_a_wrong_superquadric_size_fails_the_equal_mass_check(monkeypatch):
    run = type("R", (), {"extras": {"samples": {}, "params": {}}})()
    c = CASES["miyata-uniaxial-2d"]
    ok = [ch for ch in c.checks(run, {}) if ch.name.startswith("Table 1")]
    assert len(ok) == 1 and ok[0].passed
    monkeypatch.setitem(m.SHAPES, "S", dict(a=0.195, b=0.0876, n=4.0))  # b 1 cm short: 10 % less mass
    bad = [ch for ch in c.checks(run, {}) if ch.name.startswith("Table 1")]
    assert not bad[0].passed and bad[0].error == pytest.approx(0.1, abs=0.01)


def test_negative_control_an_inertial_plate_speed_fails_the_quasi_static_check():
    """The plate at 3 m/s (300 × Table 2's) drives the bed dynamically: the force balance check fails."""
    c = CASES["miyata-uniaxial-2d"]
    p = c.merged(dict(SHORT, samples="CS", plate_speed=3.0, record_every=10))
    run = c.run(p)
    bal = [ch for ch in c.checks(run, p) if "quasi-static" in ch.name]
    assert len(bal) == 1 and not bal[0].passed, (bal[0].value, bal[0].tolerance)


# ----------------------------------------------------------------------------- the variants themselves
@pytest.mark.slow
def test_reduced_variant_runs_and_every_counted_check_has_a_verdict():
    c = CASES["miyata-uniaxial-2d"]
    p = c.merged()
    run = c.run(p)
    checks = c.checks(run, p)
    assert all(isinstance(ch.passed, bool) and ch.kind in KINDS for ch in checks)
    assert all(math.isfinite(ch.value) for ch in checks if ch.kind == "self-consistency")


@pytest.mark.slow
def test_full_variant_one_seed_of_the_circles():
    c = CASES["miyata-uniaxial-2d"]
    p = c.merged(dict(variant="full", n_seeds=1, samples="CS,CR"))
    run = c.run(p)
    assert run.extras["params"]["width"] == 10.0
    assert all(ch.kind in KINDS for ch in c.checks(run, p))


def test_a_periodic_superquadric_checkpoint_resumes_the_uninterrupted_run_to_the_bit(tmp_path):
    """The state I/O carries the periodic shifts and image counters: resumed = uninterrupted."""
    p = m.MiyataUniaxial2D.resolved(m.MiyataUniaxial2D().merged())
    whole = build(m.insertion_scene("S", 2.0, 3, p)).run(1500)
    half = build(m.insertion_scene("S", 2.0, 3, p)).run(700)
    path = half.save_checkpoint(tmp_path / "sq.npz")
    resumed = build(m.insertion_scene("S", 2.0, 3, p)).load_checkpoint(path).run(800)
    for k in ("x", "y", "th", "vx", "vy", "om"):
        assert np.array_equal(getattr(whole.bodies, k), getattr(resumed.bodies, k)), k
    assert np.array_equal(whole.ix, resumed.ix) and np.array_equal(whole.sx, resumed.sx)
