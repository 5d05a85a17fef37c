"""3D engine conformance (issue 13 item 4): the same small Hertz-Mindlin scenes in demflow, YADE and LIGGGHTS.

``TestConformance3D`` is one class that every engine passes on every scene: demflow run now, YADE
and LIGGGHTS from their stored reference runs (``reference_runs/conformance-3d``, sha256-verified).
Each engine's trajectory must equal, to round-off, the one-contact reference model
(``tests/reference_contact.py``, plain Python) in that engine's conventions, and demflow in the
engine's matching mode.  The named differences of the capabilities table (``FEATURES_3D``) are then
each isolated by flipping one convention of the model, and their sizes are measured against
``MEASURED_3D``.  Live-engine tests (``-m engines``) rerun the engines and compare with the stored runs.
"""
from __future__ import annotations

import dataclasses
import functools
import json
import math
import os
import re
import shutil

import numpy as np
import pytest

import reference_contact as rc
from helpers import json_leaves
from demflow import Ellipsoids, GlobalDamping, LinearLaw, PlateServo, SceneError, build
from demflow.cases.conformance_3d import (CASE, CONFORMANCE, LIFT_STEP, PARAMS, VARIANTS, conformance_tolerance,
                                         engine_for, scene)
from demflow.engines import EngineUnsupported, get_engine3d, reference
from demflow.engines.base3d import Trajectory3D, demflow_trajectory
from demflow.engines.base3d import trajectory_difference as diff
from demflow.engines.capabilities import CANNOT, ENGINE_NAMES, FEATURES_3D, MATCHING, MEASURED_3D, VERDICTS, as_html
from demflow.engines.liggghts3d import Liggghts3DEngine, restitution_for_zeta
from demflow.engines.yade3d import Yade3DEngine, wall_material, yade_moduli
from demflow.laws.restitution import zeta_liggghts
from demflow.tolerances import tol

ROUND_OFF = tol("engines3d.round-off").value
SCENES = ("head-on", "oblique-plane", "periodic-pair", "moving-plate")
ENGINES = ("demflow", "yade", "liggghts")


def variant_of(engine: str, scene_name: str) -> str:
    """The variant an engine runs a scene in: LIGGGHTS's shear-spring mode is 'total' (head-on has no
    tangential force: one variant); demflow runs YADE's mode here (its other mode is LIGGGHTS's row)."""
    return scene_name + "-total" if engine == "liggghts" and scene_name != "head-on" else scene_name


@functools.lru_cache(maxsize=None)
def demflow_run(variant: str) -> Trajectory3D:
    return demflow_trajectory(build(scene(variant, PARAMS)))


@functools.lru_cache(maxsize=None)
def stored(variant: str, engine: str) -> Trajectory3D:
    return reference.load(CASE, variant, engine, loader=Trajectory3D.load)


@functools.lru_cache(maxsize=None)
def model(variant: str, conv: rc.Conventions) -> Trajectory3D:
    return rc.run(scene(variant, PARAMS), conv)


def trajectory(engine: str, variant: str) -> Trajectory3D:
    return demflow_run(variant) if engine == "demflow" else stored(variant, engine)


@pytest.fixture(params=[(e, s) for e in ENGINES for s in SCENES], ids=lambda p: f"{p[0]}-{p[1]}")
def conf(request):
    engine, scene_name = request.param
    return engine, variant_of(engine, scene_name)


class TestConformance3D:
    """Every engine × every conformance scene (the scene in the engine's matching mode)."""

    def test_equals_the_reference_model_in_its_own_conventions(self, conf):
        engine, v = conf
        d = diff(model(v, rc.conventions_for(engine, v)), trajectory(engine, v))
        assert d["steps"] > 100
        assert d["max"] <= ROUND_OFF, d

    def test_equals_demflow_in_its_matching_mode(self, conf):
        """YADE and LIGGGHTS against demflow: round-off, except where the contact normal turns (the named
        history-rotation difference bounds it); demflow: the trajectory recorder does not perturb the run
        (the state after the run equals a single uninterrupted run's, bit for bit)."""
        engine, v = conf
        if engine == "demflow":
            sim = build(scene(v, PARAMS)).run()
            steps, a = demflow_run(v).sphere_array(("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz"))
            assert steps[-1] == sim.step
            got = np.concatenate([sim.unwrapped_positions(), sim.spheres.vel, sim.spheres.angvel], axis=1)
            np.testing.assert_array_equal(a[-1], got)
            return
        assert diff(demflow_run(v), trajectory(engine, v))["max"] <= tol(conformance_tolerance(v)).value

    def test_the_bodies_interacted(self, conf):
        """Not a vacuous comparison: the contact changed the velocities by more than 10 % of the largest
        speed, and the plane (if any) carried force."""
        engine, v = conf
        steps, a = trajectory(engine, v).sphere_array(("vx", "vy", "vz"))
        V = np.max(np.linalg.norm(a, axis=2))
        assert np.max(np.linalg.norm(a[-1] - a[0], axis=1)) > 0.1 * V
        _, f = trajectory(engine, v).plane_array()
        if f.size:
            assert np.max(np.abs(f)) > 0

    def test_stored_run_is_verified_and_its_deck_is_rewritten_byte_for_byte(self, conf, tmp_path):
        engine, v = conf
        if engine == "demflow":
            pytest.skip("demflow runs now: no stored run")
        path = reference.location(CASE, v, engine)
        meta = reference.verify(path)
        assert meta["engine"] == engine and meta["engine_version"]
        sc = scene(v, PARAMS)
        written = engine_for(engine, v).write_deck(sc, build(sc), tmp_path)
        for p in written:
            assert p.read_bytes() == (path / p.name).read_bytes(), (f"{p.name} differs from the deck the stored run used: if the change is meant, "
                                                               f"regenerate it (demflow reference {CASE} --engine {engine})")


# ------------------------------------------------------------------------------ named differences
def test_every_conformance_variant_is_stored_for_its_engines():
    stored_now = reference.available(CASE)
    for v, engines in VARIANTS.items():
        assert sorted(stored_now.get(v, [])) == sorted(engines), v
    assert set(CONFORMANCE) <= set(VARIANTS)


@pytest.mark.parametrize("variant, engine", [(v, e) for v in CONFORMANCE for e in VARIANTS[v]])
def test_every_stored_conformance_run_equals_the_model_in_the_engines_conventions(variant, engine):
    """Beyond the four scenes: no-shear-damping, Δt/2, plate velocity switches, the plane lift (YADE)."""
    assert diff(model(variant, rc.conventions_for(engine, variant)), stored(variant, engine))["max"] <= ROUND_OFF


def test_the_model_equals_demflow_on_every_variant():
    """The reference model in demflow's conventions is demflow (an independent implementation of the law)."""
    for v in VARIANTS:
        if v in ("oblique-plane-r2", "periodic-pair-ratcheting"):
            continue  # the same scenes as oblique-plane and periodic-pair
        assert diff(demflow_run(v), model(v, rc.DEMFLOW))["max"] <= ROUND_OFF, v


def _size(a, b):
    return diff(a, b)["max"]


def _measured(key, value):
    """The size recomputed now equals the one the capabilities table records (2 significant digits)."""
    assert value == pytest.approx(MEASURED_3D[key], rel=0.02), (key, value)


@pytest.mark.parametrize("base", ["oblique-plane", "periodic-pair"])
def test_shear_spring_total_vs_incremental(base):
    """LIGGGHTS's total spring vs YADE's incremental one: each engine equals the model only with its own
    mode; the size equals demflow's mode difference and LIGGGHTS vs YADE."""
    yade, lig = stored(base, "yade"), stored(base + "-total", "liggghts")
    assert _size(model(base, rc.YADE), yade) <= ROUND_OFF
    assert _size(model(base, dataclasses.replace(rc.YADE, shear_spring="total")), yade) > 1e6 * ROUND_OFF
    assert _size(model(base + "-total", dataclasses.replace(rc.LIGGGHTS, shear_spring="incremental")), lig) > 1e6 * ROUND_OFF
    size = _size(demflow_run(base), demflow_run(base + "-total"))
    _measured(f"shear-spring-3d/{base}", size)
    assert _size(yade, lig) == pytest.approx(size, rel=1e-6)


@pytest.mark.parametrize("engine, variant", [("yade", "periodic-pair"), ("liggghts", "periodic-pair-total")])
def test_history_rotation(engine, variant):
    """The normal turns (periodic pair): each engine equals the model with its own rotation rule to round-off
    and differs from demflow's rule by the measured size, which halves with Δt (first order)."""
    conv = rc.conventions_for(engine, variant)
    run = stored(variant, engine)
    assert _size(model(variant, conv), run) <= ROUND_OFF
    size = _size(model(variant, dataclasses.replace(conv, rotation="demflow")), run)
    # above the round-off tolerance (3.0e-10 and 5.1e-10 against 1e-10), and first order in Δt (the ratio
    # below), which round-off is not.  This asked 3x the tolerance until 2026-11-25: YADE's 3.0e-10 sat on
    # that line, failing or passing with the last bits of ζ.
    assert size > ROUND_OFF
    _measured(f"history-rotation/{engine}", _size(demflow_run(variant), run))
    dt2 = variant + "-dt2"
    ratio = _size(demflow_run(dt2), stored(dt2, engine)) / _size(demflow_run(variant), run)
    assert ratio == pytest.approx(0.5, abs=tol("engines3d.first-order").value)


def _projected(variant: str):
    """The variant's scene with HertzMindlinLaw(history_rotation='project'): LIGGGHTS's rotation rule in demflow."""
    sc = scene(variant, PARAMS)
    return dataclasses.replace(sc, laws={k: dataclasses.replace(v, history_rotation="project") for k, v in sc.laws.items()})


@pytest.mark.parametrize("variant", ["periodic-pair-total", "periodic-pair-total-dt2"])
def test_history_rotation_project_is_liggghts_rule(variant):
    """demflow's history_rotation='project' (increment, then project onto the tangent plane, no rescale) is
    LIGGGHTS's rule: where the normal turns it equals the stored LIGGGHTS run and the reference model in
    LIGGGHTS's conventions to round-off, where demflow's default rule differs by the named difference (the
    negative control: the same comparison with the default fails the round-off tolerance)."""
    run = stored(variant, "liggghts")
    projected = demflow_trajectory(build(_projected(variant)))
    assert _size(projected, run) <= ROUND_OFF
    assert _size(projected, model(variant, rc.LIGGGHTS)) <= ROUND_OFF
    assert _size(demflow_run(variant), run) > ROUND_OFF


def test_history_rotation_project_changes_nothing_where_the_normal_keeps_its_direction():
    """On a plane (the normal fixed) the two rules are one: 'project' equals the default to round-off."""
    for v in ("oblique-plane-total", "moving-plate-total"):
        assert _size(demflow_trajectory(build(_projected(v))), demflow_run(v)) <= ROUND_OFF, v


def test_history_rotation_is_checked():
    law = scene("periodic-pair", PARAMS).laws
    sc = scene("periodic-pair", PARAMS)
    bad = dataclasses.replace(sc, laws={k: dataclasses.replace(v, history_rotation="rotate") for k, v in law.items()})
    with pytest.raises(SceneError, match=r"history_rotation='rotate' is not one of \('rescale', 'project'\)"):
        build(bad)
    md = dataclasses.replace(sc, laws={k: dataclasses.replace(v, tangential="mindlin-deresiewicz",
                                                              history_rotation="project") for k, v in law.items()})
    with pytest.raises(SceneError, match="give history_rotation='rescale'"):
        build(md)


def test_plane_velocity_timing_liggghts():
    """LIGGGHTS sees a normal velocity switch of a plane one step late: equal to demflow up to the switch,
    equal to the model with the 'behind' timing throughout, and the size measured after it."""
    v = "oblique-plane-lift-total"
    lig = stored(v, "liggghts")
    assert _size(model(v, rc.LIGGGHTS), lig) <= ROUND_OFF
    assert diff(demflow_run(v), lig, until=LIFT_STEP)["max"] <= ROUND_OFF
    _measured("plane-velocity-timing", _size(demflow_run(v), lig))
    assert _size(model(v, dataclasses.replace(rc.LIGGGHTS, plane_normal_velocity="ahead")), lig) > 1e6 * ROUND_OFF
    # YADE's deck sets the velocity before the InteractionLoop: demflow's timing
    assert _size(demflow_run("oblique-plane-lift"), stored("oblique-plane-lift", "yade")) <= ROUND_OFF


def test_r2_wall_yade():
    """YADE's own box (compensate_walls=False) is the model with R* = R/2 against the plane; the deck's
    compensation removes it (oblique-plane conforms); size measured."""
    y = stored("oblique-plane-r2", "yade")
    assert _size(model("oblique-plane-r2", dataclasses.replace(rc.YADE, plane_radius=0.5)), y) <= ROUND_OFF
    assert _size(demflow_run("oblique-plane-r2-emulated"), y) <= ROUND_OFF
    _measured("r2-wall", _size(demflow_run("oblique-plane"), y))


def test_friction_cap_total_vs_elastic():
    """Both engines cap with the total normal force: each equals the model with 'total' and not with
    'elastic'; size measured on demflow's two caps."""
    for engine, v in (("yade", "oblique-plane"), ("liggghts", "oblique-plane-total")):
        conv = rc.conventions_for(engine, v)
        assert _size(model(v, conv), stored(v, engine)) <= ROUND_OFF
        assert _size(model(v, dataclasses.replace(conv, friction_cap="elastic")), stored(v, engine)) > 1e6 * ROUND_OFF
    _measured("friction-cap-3d", _size(demflow_run("oblique-plane"), demflow_run("oblique-plane-elastic-cap")))


def test_shear_damping_ratio(tmp_path):
    """ζ_t = 0 (e_t = 1) is expressed by both engines (YADE betas = 0; LIGGGHTS tangential_damping off) and
    ζ_t = ζ_n by both; LIGGGHTS refuses any other ζ_t, YADE takes it.  Size of e_t = 1 vs e_t = e_n measured."""
    _measured("shear-damping-ratio", _size(demflow_run("oblique-plane"), demflow_run("oblique-plane-no-shear-damping")))
    for engine, v in (("yade", "oblique-plane-no-shear-damping"), ("liggghts", "oblique-plane-no-shear-damping-total")):
        assert _size(demflow_run(v), stored(v, engine)) <= ROUND_OFF
        assert _size(demflow_run(v.replace("-no-shear-damping", "")), stored(v, engine)) > 1e6 * ROUND_OFF
    sc = _with_law(scene("oblique-plane-total", PARAMS), restitution_tangential=0.8)
    with pytest.raises(EngineUnsupported, match="shear-damping-ratio"):
        Liggghts3DEngine().write_deck(sc, build(sc), None)
    sc = _with_law(scene("oblique-plane", PARAMS), restitution_tangential=0.8)
    sim = build(sc)
    Yade3DEngine().write_deck(sc, sim, tmp_path)
    pair = next(q for q in json.loads((tmp_path / "scene.json").read_text())["yade_pairs"] if q["b"] == "wall0")
    assert pair["betas"] == sim.law_params.zt[0, 1] != pair["betan"] == sim.law_params.zn[0, 1]


def test_dashpot_mass_of_spheres_is_the_reduced_mass(tmp_path):
    """For spheres YADE's member mass is the body mass: the deck gives each body demflow's mass and the
    damped head-on pair of unlike masses conforms in both engines; a dashpot with the larger mass would not."""
    sc = scene("head-on", PARAMS)
    Yade3DEngine().write_deck(sc, build(sc), tmp_path)
    S = json.loads((tmp_path / "scene.json").read_text())
    assert S["spheres"]["mass"] == build(sc).spheres.mass.tolist()
    assert S["spheres"]["mass"][0] > 2 * S["spheres"]["mass"][1]
    for engine in ("yade", "liggghts"):
        run = stored("head-on", engine)
        assert _size(model("head-on", rc.conventions_for(engine, "head-on")), run) <= ROUND_OFF
        # the same model with the dashpot on one sphere's own mass (a clump member's, or a wall contact's rule)
        for other in ("first", "second"):
            conv = dataclasses.replace(rc.conventions_for(engine, "head-on"), dashpot_mass=other)
            assert _size(model("head-on", conv), run) > 1e6 * ROUND_OFF


def test_avoid_ratcheting_yade():
    """YADE's default avoidGranularRatcheting changes the contact velocity: measured; the deck's False conforms."""
    y = stored("periodic-pair-ratcheting", "yade")
    _measured("avoid-ratcheting", _size(demflow_run("periodic-pair"), y))
    assert _size(model("periodic-pair", rc.YADE), stored("periodic-pair", "yade")) <= ROUND_OFF


def test_initial_velocity_convention(tmp_path):
    """LIGGGHTS starts from v(0): its deck gives v(-Δt/2) + gΔt/2 (no contact at t = 0), and the stored run
    conforms; ignoring it would cost the measured size."""
    sc = scene("moving-plate-total", PARAMS)
    sim = build(sc)
    Liggghts3DEngine().write_deck(sc, sim, tmp_path)
    deck = (tmp_path / "deck.in").read_text()
    vz = float(re.search(r"set atom 1 .* vz (\S+)", deck).group(1))
    assert vz == 0.5 * sim.dt * -9.81
    shifted = dataclasses.replace(sc, spheres=dataclasses.replace(sc.spheres, velocity=[[0.0, 0.0, vz]]))
    _measured("initial-velocity-3d", _size(demflow_run("moving-plate-total"), demflow_trajectory(build(shifted))))
    # a sphere resting in contact at t = 0: the contact force is not known before LIGGGHTS's setup, so the deck
    # gives v(-Δt/2) unchanged and records that the convention differs (capabilities 'initial-velocity-3d')
    resting = dataclasses.replace(sc, spheres=dataclasses.replace(sc.spheres, z=[0.999 * sc.spheres.radius[0]]))
    Liggghts3DEngine().write_deck(resting, build(resting), tmp_path)
    assert float(re.search(r"set atom 1 .* vz (\S+)", (tmp_path / "deck.in").read_text()).group(1)) == 0.0
    assert json.loads((tmp_path / "scene.json").read_text())["liggghts"]["touching_at_start"] is True
    assert _size(demflow_run("moving-plate-total"), stored("moving-plate-total", "liggghts")) <= ROUND_OFF


def test_round_off_floor_is_recorded():
    """The largest engine-vs-demflow difference where the models are equivalent is the recorded floor."""
    worst = max(_size(demflow_run(v), stored(v, e)) for v in CONFORMANCE for e in VARIANTS[v]
                if not v.startswith("periodic-pair"))
    _measured("round-off", worst)


# ------------------------------------------------------------------------------ decks and refusals
def _with_law(sc, **kw):
    return dataclasses.replace(sc, laws={k: dataclasses.replace(law, **kw) for k, law in sc.laws.items()})


def test_wall_material_compensates_yades_r2():
    """The compensating box material gives YADE's moduli √2 × demflow's, for a glass and a rigid plane
    (ENGINES.md: E/(√2 − 1) with the same ν for a plane of the sphere's own material)."""
    E, nu = 4.8e10, 0.2
    for Ep in (E, math.inf):
        Es = 1 / ((1 - nu ** 2) / E + (1 - nu ** 2) / Ep)
        Gs = 1 / (2 * (2 - nu) * (1 + nu) / E + 2 * (2 - nu) * (1 + nu) / Ep)
        Ew, nuw = wall_material(E, nu, Es, Gs)
        Ey, Gy = yade_moduli(E, nu, Ew, nuw)
        assert Ey == pytest.approx(math.sqrt(2) * Es, rel=1e-14) and Gy == pytest.approx(math.sqrt(2) * Gs, rel=1e-14)
    assert wall_material(E, nu, E / (2 * (1 - nu ** 2)), E / (4 * (1 + nu) * (2 - nu)))[0] == pytest.approx(
        E / (math.sqrt(2) - 1), rel=1e-13)


def test_liggghts_restitution_reproduces_demflows_damping_ratio():
    for zeta in (0.0, 0.1, 0.2330248576834424, 0.6):
        e = restitution_for_zeta(zeta)
        le = math.log(e)
        assert math.sqrt(5 / 6) * abs(le) / math.sqrt(le * le + math.pi ** 2) == pytest.approx(zeta, rel=1e-14, abs=0)
    assert restitution_for_zeta(zeta_liggghts(0.5)) == pytest.approx(0.5, rel=1e-14)
    with pytest.raises(EngineUnsupported, match="damping-3d"):
        restitution_for_zeta(0.95)


def test_yade_deck_is_the_fixed_program_and_data_is_numbers(tmp_path):
    from importlib import resources

    sc = scene("moving-plate", PARAMS)
    Yade3DEngine().write_deck(sc, build(sc), tmp_path)
    assert (tmp_path / "deck.py").read_text() == resources.files("demflow.engines.decks").joinpath(
        "yade_spheres3d.py").read_text()

    for v in json_leaves(json.loads((tmp_path / "scene.json").read_text())):
        assert v is None or isinstance(v, (int, float, bool)) or re.fullmatch(r"[A-Za-z][A-Za-z0-9_\-|]*", v), v


@pytest.mark.parametrize("bad", ['x"; import os #', "a\nb", "name with spaces"])
def test_names_that_are_not_identifiers_never_reach_a_3d_deck(bad, tmp_path):
    sc = scene("oblique-plane", PARAMS)
    sim = build(sc)
    sc.name = bad
    for engine in (Yade3DEngine(), Liggghts3DEngine()):
        with pytest.raises(SceneError, match="not an identifier"):
            engine.write_deck(sc, sim, tmp_path)


def _servo(sc):
    return dataclasses.replace(sc, planes=[dataclasses.replace(sc.planes[0], servo=PlateServo(1.0, 1e-3, 1e-3))])


USING_3D = {  # feature key -> an oblique-plane scene (incremental for YADE, total for LIGGGHTS) that uses it
    "linear-law-3d": lambda sc: dataclasses.replace(sc, laws={k: LinearLaw(kn=1e6) for k in sc.laws}),
    "shear-spring-3d": lambda sc: _with_law(sc, shear_spring="total" if sc.laws[("glass", "plate")].shear_spring
                                                 == "incremental" else "incremental"),
    "mindlin-deresiewicz": lambda sc: _with_law(sc, tangential="mindlin-deresiewicz", shear_spring="incremental"),
    "friction-cap-3d": lambda sc: _with_law(sc, friction_cap="elastic"),
    "global-damping-3d": lambda sc: dataclasses.replace(sc, damping=GlobalDamping(alpha=1.0)),
    "local-damping-3d": lambda sc: dataclasses.replace(sc, local_damping=0.2),
    "servo-plates": _servo,
    "fixed-spheres": lambda sc: dataclasses.replace(sc, spheres=dataclasses.replace(sc.spheres, fixed=[True])),
    "ellipsoids-3d": lambda sc: dataclasses.replace(sc, spheres=None, ellipsoids=Ellipsoids(
        axes=[[r, 0.8 * r, 0.6 * r] for r in sc.spheres.radius], x=sc.spheres.x, y=sc.spheres.y, z=sc.spheres.z,
        material=sc.spheres.material)),
}
REFUSED_3D = [(f.key, e) for f in FEATURES_3D for e in ENGINE_NAMES
              if f.expression(e).verdict in (CANNOT, MATCHING) and (f.expression(e).uses or f.uses)]


def test_every_refusable_3d_feature_has_a_test_scene():
    assert {k for k, _ in REFUSED_3D} == set(USING_3D)


@pytest.mark.parametrize("key, engine", REFUSED_3D, ids=[f"{k}-{e}" for k, e in REFUSED_3D])
def test_3d_deck_writer_refuses_what_the_engine_cannot_express(key, engine, tmp_path):
    base = scene("oblique-plane-total" if engine == "liggghts" else "oblique-plane", PARAMS)
    sc = USING_3D[key](base)
    f = next(f for f in FEATURES_3D if f.key == key)
    e = f.expression(engine)
    assert (e.uses or f.uses)(sc) and not (e.uses or f.uses)(base)
    with pytest.raises(EngineUnsupported) as err:
        get_engine3d(engine).write_deck(sc, None, tmp_path)  # refused before anything is built or written
    msg = str(err.value)
    assert ENGINE_NAMES[engine] in msg and f.item in msg and repr(key) in msg and (e.remedy or f.remedy) in msg
    assert not any(tmp_path.iterdir())


def test_value_dependent_3d_refusals_name_the_feature(tmp_path):
    sc = scene("periodic-pair", PARAMS)
    one_axis = dataclasses.replace(sc, box=dataclasses.replace(sc.box, periodic_y=None))
    with pytest.raises(EngineUnsupported, match="periodic-3d"):
        Yade3DEngine().write_deck(one_axis, build(one_axis), tmp_path)
    plate = scene("moving-plate", PARAMS)
    with pytest.raises(EngineUnsupported, match="rigid"):
        Yade3DEngine(compensate_walls=False).write_deck(plate, build(plate), tmp_path)
    plate = scene("moving-plate-total", PARAMS)
    two = dataclasses.replace(plate, box=dataclasses.replace(plate.box, periodic_x=(-0.05, 0.05), periodic_y=(-0.05, 0.05)))
    with pytest.raises(EngineUnsupported, match="walls-3d"):
        Liggghts3DEngine().write_deck(two, build(two), tmp_path)


def test_every_3d_feature_row_renders():
    page = as_html(FEATURES_3D)
    assert page.count("<tr>") == len(FEATURES_3D) + 1
    import html

    for f in FEATURES_3D:
        assert html.escape(f.item) in page and html.escape(f.measured) in page
        for e in ENGINE_NAMES:
            assert f.expression(e).verdict in VERDICTS
    assert len({f.key for f in FEATURES_3D}) == len(FEATURES_3D)
    for key in MEASURED_3D:  # every measured size appears in some row
        assert any(key.split("/")[0] in (f.key, "round-off") for f in FEATURES_3D), key


def test_tampered_3d_reference_is_refused(tmp_path):
    src = reference.location(CASE, "head-on", "yade")
    dst = tmp_path / CASE / "head-on" / "yade"
    shutil.copytree(src, dst)
    reference.load(CASE, "head-on", "yade", base=tmp_path, loader=Trajectory3D.load)
    f = dst / "spheres.parquet"
    os.chmod(f, 0o644)
    data = bytearray(f.read_bytes())
    data[len(data) // 2] ^= 0xFF
    f.write_bytes(bytes(data))
    with pytest.raises(Exception, match="hash check"):
        reference.load(CASE, "head-on", "yade", base=tmp_path, loader=Trajectory3D.load)


# ------------------------------------------------------------------------------ live engines
@pytest.mark.engines
@pytest.mark.parametrize("variant, engine", [("head-on", "yade"), ("oblique-plane", "yade"), ("periodic-pair", "yade"),
                                             ("head-on", "liggghts"), ("oblique-plane-total", "liggghts"),
                                             ("periodic-pair-total", "liggghts"), ("oblique-plane-lift-total", "liggghts")])
def test_live_3d_engine_reproduces_its_stored_reference(variant, engine, tmp_path):
    """Regenerate the deck, run the real engine, compare with the stored reference (deck identical,
    trajectory equal to round-off)."""
    stored_dir = reference.location(CASE, variant, engine)
    res, run = engine_for(engine, variant).run(scene(variant, PARAMS), tmp_path, timeout=600)
    for deck in ("deck.py", "deck.in", "scene.json", "w0.stl"):
        if (stored_dir / deck).exists():
            assert (tmp_path / deck).read_bytes() == (stored_dir / deck).read_bytes(), f"{deck} changed"
    assert diff(stored(variant, engine), res)["max"] <= ROUND_OFF
    assert diff(model(variant, rc.conventions_for(engine, variant)), res)["max"] <= ROUND_OFF


@pytest.mark.engines
def test_live_conformance_case_passes():
    from demflow.cases.conformance_3d import Conformance3D

    case = Conformance3D()
    case.live = True
    p = case.merged()
    checks = case.checks(case.run(p), p)
    assert all(c.passed for c in checks), [(c.name, c.value) for c in checks if not c.passed]


def test_benchmark_decks_record_nothing_and_read_atoms_from_a_data_file(tmp_path):
    """Speed-run decks (benchmarks/bench_engines3d.py): YADE's fixed benchmark program with the conformance
    deck's scene.json numbers and no PyRunner; LIGGGHTS above READ_DATA_ABOVE spheres reads a data file
    (densities giving demflow's masses), the static floor of a periodic box is a primitive wall, nothing is
    dumped; moving planes are refused by both benchmark decks."""
    import sys
    from importlib import resources
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from packing3d import dense_fcc

    from demflow.engines.liggghts import READ_DATA_ABOVE

    sc = dense_fcc(READ_DATA_ABOVE + 100)
    sim = build(sc)
    (tmp_path / "y").mkdir()
    (tmp_path / "c").mkdir()
    Yade3DEngine(benchmark=True).write_deck(sc, sim, tmp_path / "y")
    Yade3DEngine().write_deck(sc, sim, tmp_path / "c")
    program = (tmp_path / "y" / "deck.py").read_text()
    assert program == resources.files("demflow.engines.decks").joinpath("yade_spheres3d_bench.py").read_text()
    assert "PyRunner" not in program.split("O.engines")[1]
    assert (tmp_path / "y" / "scene.json").read_bytes() == (tmp_path / "c" / "scene.json").read_bytes()
    for v in json_leaves(json.loads((tmp_path / "y" / "scene.json").read_text())):
        assert v is None or isinstance(v, (int, float, bool)) or re.fullmatch(r"[A-Za-z][A-Za-z0-9_\-|]*", v), v

    lsc = _with_law(sc, shear_spring="total")
    files = Liggghts3DEngine(benchmark=True).write_deck(lsc, build(lsc), tmp_path)
    deck = (tmp_path / "deck.in").read_text()
    assert "read_data spheres.data" in deck and "create_atoms" not in deck and "dump" not in deck
    assert "primitive type 2 zplane 0.0" in deck and "boundary p p f" in deck
    assert tmp_path / "spheres.data" in files
    lines = (tmp_path / "spheres.data").read_text().splitlines()
    atoms = np.array([[float(c) for c in ln.split()] for ln in lines[lines.index("Atoms") + 2:][:sim.n]])
    mass = atoms[:, 3] * 4 / 3 * math.pi * (atoms[:, 2] / 2) ** 3
    assert np.allclose(mass, sim.spheres.mass, rtol=1e-14, atol=0)
    assert np.allclose(atoms[:, 4:7], sim.spheres.pos, rtol=0, atol=1e-18)

    moving = scene("moving-plate", PARAMS)
    with pytest.raises(EngineUnsupported, match="static"):
        Yade3DEngine(benchmark=True).write_deck(moving, build(moving), tmp_path / "y")
    with pytest.raises(EngineUnsupported, match="static"):
        mv = _with_law(moving, shear_spring="total")
        Liggghts3DEngine(benchmark=True).write_deck(mv, build(mv), tmp_path)
