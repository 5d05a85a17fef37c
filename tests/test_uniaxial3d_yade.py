"""YADE on the miyata-uniaxial-3d protocol (demflow/engines/yade_uniaxial3d.py): a small bed (8 clumps,
two lattice layers) run through the whole protocol, the deck's numbers, and the reader's refusals.

The live tests are marked ``engines`` (the CI's engine stage); the others need no engine."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from demflow.build import build
from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene
from demflow.cases.miyata_uniaxial3d_statistics import run_statistics
from demflow.engines import EngineOutputError, EngineUnsupported
from demflow.engines.uniaxial3d import PLATE_GAP, protocol_numbers, read_uniaxial_output
from demflow.engines.yade_uniaxial3d import YadeUniaxial3DEngine

# 8 clumps on the lattice's first two layers; the plate stops at 450 kPa (snapshots at 400 and 450 kPa)
SMALL = {"n_insert": 8, "stress_max": 450e3, "snapshots": 2, "settle_max": 200000, "plate_z_min": 0.1,
         "band_seeds": 1, "engine_refs": 0}


def small_params():
    return get_case("miyata-uniaxial-3d").merged(SMALL)


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    if shutil.which("yade") is None:
        pytest.skip("yade is not installed (scripts/install-engines.sh)")
    p = small_params()
    sc = insertion_scene(p)
    sim = build(sc)
    work = tmp_path_factory.mktemp("yade-uniaxial")
    run, info = YadeUniaxial3DEngine(p).run(sc, work, timeout=900, sim=sim)
    return p, sim, run, work


def test_the_deck_gets_demflows_members_and_validated_numbers(tmp_path):
    p = small_params()
    sc = insertion_scene(p)
    sim = build(sc)
    YadeUniaxial3DEngine(p).write_deck(sc, sim, tmp_path)
    S = json.loads((tmp_path / "scene.json").read_text())
    members = np.asarray(S["members"]).reshape(-1, 3)
    assert np.array_equal(members, sim.spheres.pos)  # the clumps start where demflow's do, to the bit
    assert S["template"]["mass"] == 191.0
    assert (tmp_path / "deck.py").read_text().startswith("# demflow deck for YADE (2023.02a): miyata-uniaxial-3d")


def test_an_ellipsoid_bed_is_refused_by_the_decks():
    p = get_case("miyata-uniaxial-3d-ellipsoids").merged({"n_insert": 4})
    sc = insertion_scene(p)
    with pytest.raises(EngineUnsupported, match="ellipsoid"):
        protocol_numbers(sc, build(sc), p)


def _fake_output(d, curve="step,plate_z,settlement,plate_stress,floor_stress,plate_contacts,floor_contacts\n"
                          "200,0.4,0.0,0.0,1.0,0,3\n"):
    (d / "uniaxial_out.json").write_text(json.dumps(dict(
        n_inserted=4, n_particles=3, weight=1.0, floor_settled=1.0, settle_steps=[5000, 5000], dt=1e-5,
        plate_start=0.4, clump_mass=191.0, clump_inertia=[1.0, 2.0, 3.0])))
    (d / "curve.csv").write_text(curve)
    (d / "snapshots.csv").write_text("snapshot,stress,wall,force,x,y\n")


def test_the_reader_refuses_missing_truncated_and_non_finite_output(tmp_path):
    with pytest.raises(EngineOutputError, match="uniaxial_out.json"):
        read_uniaxial_output(tmp_path, "yade", 4.0)
    _fake_output(tmp_path)
    assert read_uniaxial_output(tmp_path, "yade", 4.0).meta["n_particles"] == 3
    (tmp_path / "uniaxial_out.json").write_text('{"n_inserted": 4, "n_part')
    with pytest.raises(EngineOutputError, match="not valid JSON"):
        read_uniaxial_output(tmp_path, "yade", 4.0)
    _fake_output(tmp_path, curve="step,plate_z\n1,2\n")
    with pytest.raises(EngineOutputError, match="columns"):
        read_uniaxial_output(tmp_path, "yade", 4.0)
    _fake_output(tmp_path, curve="step,plate_z,settlement,plate_stress,floor_stress,plate_contacts,floor_contacts\n"
                                 "200,0.4,0.0,nan,1.0,0,3\n")
    with pytest.raises(EngineOutputError, match="non-finite"):
        read_uniaxial_output(tmp_path, "yade", 4.0)


@pytest.mark.engines
def test_yade_clumps_carry_demflows_mass_and_inertia(small_run):
    p, sim, run, _ = small_run
    assert run.meta["clump_mass"] == 191.0
    sc = insertion_scene(p)
    assert sorted(run.meta["clump_inertia"]) == sorted(sc.clumps.template.moments.tolist())
    assert run.meta["principal_axis_alignment"] > 0.99


@pytest.mark.engines
def test_yade_bed_at_rest_carries_its_weight_on_the_floor(small_run):
    _, _, run, _ = small_run
    assert run.meta["n_particles"] == 8 and run.meta["settle_steps"][0] > 0 and run.meta["settle_steps"][1] > 0
    assert abs(run.meta["floor_settled"] / run.meta["weight"] - 1.0) < 0.005  # tolerance miyata3d.self-weight


@pytest.mark.engines
def test_yade_plate_meets_the_bed_at_its_top(small_run):
    """The plate's force first turns positive within one record's travel (plus an overlap) of the bed's top:
    without the deck's watchdog YADE's collider missed the top clump until the plate had sunk 23 mm into it."""
    p, _, run, _ = small_run
    c = run.curve
    first = c[c.plate_stress > 0].iloc[0]
    travel = p["plate_speed"] * run.meta["dt"] * p["record_every"]
    top = run.meta["plate_start"] - PLATE_GAP
    assert top - 2 * travel - 1e-4 <= first.plate_z <= top


@pytest.mark.engines
def test_yade_curve_and_snapshots_are_consistent(small_run):
    p, _, run, _ = small_run
    c = run.curve
    assert c.plate_stress.iloc[-1] >= p["stress_max"]
    assert (c.plate_contacts <= run.meta["n_particles"]).all() and (c.floor_contacts <= run.meta["n_particles"]).all()
    plate = run.snapshot_forces("plate")
    assert len(plate) == 2
    for k, f in enumerate(plate):
        stress = run.snapshots[run.snapshots.snapshot == k].stress.iloc[0]
        # per-particle normal forces sum to the plate's force (the plate is horizontal): to round-off
        assert f.sum() / 4.0 == pytest.approx(stress, rel=1e-9)
    st = run_statistics(run)
    assert st["particles after trimming"] == 8 and 0 < st["particles on the plate (mean of snapshots)"] <= 8
    xy = run.snapshots[["x", "y"]].to_numpy(float)  # contact points (Fig. 34 maps): inside the periodic box
    assert np.isfinite(xy).all() and (xy >= 0).all() and (xy < p["box"]).all()


def _synthetic(seed: int, height_shift: float = 0.0, first_touch: float = 0.0):
    """A UniaxialRun with a plate first touched ``first_touch`` above 2.1 m that bites at 2.1 m and stiffens linearly, 78 particles,
    4 on the plate and 12 on the floor at each of two snapshots (forces drawn from a gamma law, N = 3)."""
    import pandas as pd

    from demflow.engines.uniaxial3d import UniaxialRun

    rng = np.random.default_rng(seed)
    z = np.linspace(2.2, 1.9, 301) + height_shift
    bite = 2.1 + height_shift + 0.01 * rng.standard_normal()
    # a lone top particle carries 100 Pa for ``first_touch`` of plate travel before the bed bites
    stress = np.where(z < bite, (bite - z) * 1e7, np.where(z < bite + first_touch, 100.0, 0.0))
    touched = z[np.argmax(stress > 0)]
    curve = pd.DataFrame({"step": np.arange(1, 302) * 200, "plate_z": z,
                          "settlement": np.where(z <= touched, touched - z, 0.0), "plate_stress": stress,
                          "floor_stress": stress + 3.7e4, "plate_contacts": 4, "floor_contacts": 12})
    rows = [(k, 4e5 + k, wall, f, 0.5, 0.5) for k in range(2) for wall, n in (("plate", 4), ("floor", 12))
            for f in rng.gamma(3.0, 1.0 / 3.0, n)]
    snaps = pd.DataFrame(rows, columns=["snapshot", "stress", "wall", "force", "x", "y"])
    return UniaxialRun(curve, snaps, dict(n_particles=78, plate_start=2.215 + height_shift, weight=1.0,
                                          floor_settled=1.0))


def test_cross_code_checks_judge_narrow_bands_and_only_show_wide_ones():
    """An engine's bed 5 cm higher than every seed's is out of the plate-height band (that band is
    narrow); a settlement band wider than the informative limit is shown, never counted."""
    from demflow.cases.base import CaseRun

    case = get_case("miyata-uniaxial-3d")
    p = case.merged()
    band = {s: _synthetic(s, first_touch=0.002 + 0.1 * (s % 3)) for s in range(1, 9)}
    for shift, inside in ((0.0, True), (0.3, False)):
        run = CaseRun({}, {"band": band, "engines": {"yade": _synthetic(99, height_shift=shift)}})
        checks = case._cross_code_checks(run, p)
        height = next(c for c in checks if c.name.startswith("yade: plate height at 400 kPa"))
        assert height.kind == "cross-code" and height.passed is inside
        settle = next(c for c in checks if c.name.startswith("yade: settlement at 400 kPa"))
        assert settle.informative and "too wide" in settle.name  # inside a band too wide to judge: not a pass
    # outside even the wide band: a counted miss, never hidden as informative
    far_run = _synthetic(97)
    far_run.curve["settlement"] *= 30.0  # about 1.2 m at 400 kPa: far above the band's top (~0.4 m)
    run = CaseRun({}, {"band": band, "engines": {"yade": far_run}})
    far = next(c for c in case._cross_code_checks(run, p) if c.name.startswith("yade: settlement at 400 kPa"))
    assert far.kind == "cross-code" and not far.passed
    run = CaseRun({}, {"band": band, "engines": {}})
    missing = case._cross_code_checks(run, p)
    assert all(c.informative for c in missing) and any("no stored run" in c.name for c in missing)


def test_an_engine_without_local_damping_is_counted_against_the_undamped_band():
    """LIGGGHTS cannot express local damping (capabilities row local-damping-uniaxial): its statistics count
    against demflow's band without it; against the damped band they are shown, not counted.  YADE is the
    other way round."""
    from demflow.cases.base import CaseRun

    case = get_case("miyata-uniaxial-3d")
    p = case.merged()
    damped = {s: _synthetic(s) for s in range(1, 9)}
    undamped = {s: _synthetic(s, height_shift=-0.3) for s in range(1, 9)}  # a bed 30 cm lower
    run = CaseRun({}, {"band": damped, "band_undamped": undamped,
                       "engines": {"liggghts": _synthetic(99, height_shift=-0.3), "yade": _synthetic(98)}})
    checks = case._cross_code_checks(run, p)
    lig = [c for c in checks if c.name.startswith("liggghts: plate height at 400 kPa")]
    counted = [c for c in lig if not c.informative]
    assert len(counted) == 1 and "no local damping" in counted[0].name and counted[0].passed
    shown = [c for c in lig if c.informative]
    assert len(shown) == 1 and "OUTSIDE" in shown[0].name
    yade = [c for c in checks if c.name.startswith("yade: plate height at 400 kPa") and not c.informative]
    assert len(yade) == 1 and "no local damping" not in yade[0].name and yade[0].passed


def test_leave_one_out_counts_how_often_a_fair_draw_misses_the_band():
    """Eight seeds of one statistic spread 1.0-1.07 and an outlier (1.2): only the outlier misses the other
    eight's band (1 of 9 judged); a statistic whose band is wider than the informative limit is not judged
    while inside it."""
    from demflow.cases.miyata_uniaxial3d_bands import leave_one_out_misses

    vals = [1.0, 1.01, 1.02, 1.03, 1.04, 1.05, 1.06, 1.07, 1.2]
    per_seed = {k: {"narrow": v, "wide": [0.1, 5.0, 0.2, 4.0, 0.3, 3.0, 0.5, 2.0, 1.0][k]} for k, v in enumerate(vals)}
    assert leave_one_out_misses(per_seed) == (9, 1, 1)


def test_one_band_rule_judges_engine_runs_demflows_seeds_and_the_per_run_lines():
    """A stress never reached (nan) misses the band wherever a run is judged: in judge_value, in a run's miss
    (run_has_miss), in demflow's own leave-one-out count and on an engine's counted line; a statistic that too few
    seeds reach has no band and is judged nowhere (an informative line, not a counted miss)."""
    import math

    from demflow.cases.base import CaseRun
    from demflow.cases.miyata_uniaxial3d_bands import judge_value, leave_one_out_misses, run_has_miss, seed_band

    vals = [1.0, 1.01, 1.02, 1.03, 1.04, 1.05, 1.06, 1.07]
    assert judge_value(math.nan, vals) is False and judge_value(1.03, vals) is True
    assert judge_value(1.03, [1.0, math.nan, math.nan]) is None and seed_band([1.0, math.nan]).wide
    per_seed = {k: {"narrow": v, "rare": math.nan if k else 1.0} for k, v in enumerate(vals)}
    per_seed[8] = {"narrow": math.nan, "rare": math.nan}
    assert run_has_miss(per_seed[8], {q: v for q, v in per_seed.items() if q != 8})
    # seed 8's nan is outside the other eight's band; "rare" has no band for any seed (at most one finite value)
    assert leave_one_out_misses(per_seed) == (9, 1, 1)

    case = get_case("miyata-uniaxial-3d")
    p = case.merged()
    band = {s: _synthetic(s) for s in range(1, 9)}
    never = _synthetic(99)
    never.curve["plate_stress"] = np.minimum(never.curve["plate_stress"], 450e3)  # never reaches 500 and 600 kPa
    checks = case._cross_code_checks(CaseRun({}, {"band": band, "engines": {"yade": never}}), p)
    miss = next(c for c in checks if c.name.startswith("yade: plate height at 600 kPa"))
    assert miss.kind == "cross-code" and not miss.passed
    for s in band.values():  # no seed reaches 600 kPa: no band, a line shown and not counted
        s.curve["plate_stress"] = np.minimum(s.curve["plate_stress"], 550e3)
    checks = case._cross_code_checks(CaseRun({}, {"band": band, "engines": {"yade": never}}), p)
    shown = next(c for c in checks if c.name.startswith("yade: plate height at 600 kPa"))
    assert shown.informative and "no band" in shown.name


def test_an_engine_with_eight_runs_is_judged_as_an_ensemble():
    """With >= 4 stored runs an engine's per-run lines are informative (one draw each) and its runs are judged
    together against demflow's seeds (tolerance miyata3d.engine-ensemble): draws of demflow's own distribution
    pass, beds 5 cm higher fail the plate-height lines and the miss-rate line; the page's negative control
    (10 % more particles) is present and passes (i.e. the test finds that difference).  LIGGGHTS is counted
    against the band without local damping only."""
    from demflow.cases.base import CaseRun

    case = get_case("miyata-uniaxial-3d")
    p = case.merged()
    band = {s: _synthetic(s) for s in range(1, 9)}
    undamped = {s: _synthetic(s + 40) for s in range(1, 9)}
    for shift, ok in ((0.0, True), (0.05, False)):
        engines = {f"{e} seed{s}": _synthetic(100 * k + s, height_shift=shift)
                   for k, e in enumerate(("yade", "liggghts"), 1) for s in range(1, 9)}
        checks = case._cross_code_checks(CaseRun({}, {"band": band, "band_undamped": undamped, "engines": engines}), p)
        per_run = [c for c in checks if c.name.startswith("yade seed")]
        assert per_run and all(c.informative for c in per_run)
        ens = [c for c in checks if c.name.startswith("yade runs as an ensemble") and not c.informative]
        assert ens and all("no local damping" not in c.name for c in ens)
        height = [c for c in ens if "plate height at 400 kPa" in c.name]
        assert len(height) == 1 and height[0].passed is ok
        assert height[0].name.endswith("≥ 0.05" if ok else "< 0.05")  # the name states the outcome
        miss = next(c for c in ens if "runs with a statistic outside the band" in c.name)
        assert miss.passed is ok
        lig = [c for c in checks if c.name.startswith("liggghts runs as an ensemble") and not c.informative]
        assert lig and all("no local damping" in c.name for c in lig)
        assert any(c.name.startswith("liggghts runs as an ensemble") and c.informative and "no local damping" not in c.name
                   for c in checks)
        control = [c for c in checks if c.name.startswith("negative control")]
        assert len(control) == 1 and control[0].passed
