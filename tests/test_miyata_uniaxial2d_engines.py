"""miyata-uniaxial-2d-engines (issue 15 item 3): the 2D decks with a box periodic along x, gravity, a wall law YADE's
series rule cannot give, and the named lever-arm difference.  Engine runs are marked ``engines``."""
import dataclasses
import json

import numpy as np
import pytest

from demflow.build import build
from demflow.cases import miyata_uniaxial2d as m2d
from demflow.cases import miyata_uniaxial2d_engines as E
from demflow.engines import EngineUnsupported, get_engine
from demflow.engines.liggghts import LiggghtsEngine, half_step_start
from demflow.engines.yade import YadeEngine
from demflow.scene import ContactModel, Discs, Material, Outputs, Scene
from demflow.tolerances import tol

R = m2d.SHAPES["C"]["a"]


def _frictionless(sc):
    return dataclasses.replace(sc, laws={k: dataclasses.replace(v, friction=0.0, ks=0.0) for k, v in sc.laws.items()})


def _max_position_difference(a, b, W):
    """max |Δx|, |Δy| over every snapshot, / R (x by minimum image)."""
    worst = 0.0
    for step in sorted(set(a.particles.step) & set(b.particles.step)):
        p = a.particles[a.particles.step == step].sort_values("id")
        q = b.particles[b.particles.step == step].sort_values("id")
        dx = (p.x.to_numpy() - q.x.to_numpy() + 0.5 * W) % W - 0.5 * W
        worst = max(worst, float(np.abs(dx).max()), float(np.abs(p.y.to_numpy() - q.y.to_numpy()).max()))
    return worst / R


def _snap_every(sc, k=100):
    return dataclasses.replace(sc, outputs=dataclasses.replace(sc.outputs, snapshots=tuple(range(0, sc.n_steps + 1, k))))


def test_table2_dashpots_are_eq17_with_the_pair_mass():
    m = 116.6
    laws = E.table2_laws(m)
    z = -np.log(m2d.RESTITUTION) / np.hypot(np.log(m2d.RESTITUTION), np.pi)
    assert laws[("rock", "rock")].cn == pytest.approx(2 * z * np.sqrt(m2d.KN * m / 2), rel=1e-15)
    assert laws[("rock", "wall")].cn == pytest.approx(2 * z * np.sqrt(m2d.KN_WALL * m), rel=1e-15)
    assert laws[("rock", "rock")].cs == laws[("rock", "wall")].cs == 0.0


def test_periodic_decks(tmp_path):
    sc = E.conformance_scene(100)
    sim = build(sc)
    LiggghtsEngine().write_deck(sc, sim, tmp_path)
    deck = (tmp_path / "deck.in").read_text()
    assert "boundary p f p" in deck and "fix grav all gravity 9.81 vector 0.0 -1.0 0.0" in deck
    assert "region box block 0.0 1.3 " in deck
    stl = (tmp_path / "w0.stl").read_text()  # the floor, clipped to the period
    xs = sorted({float(line.split()[1]) for line in stl.splitlines() if line.startswith("vertex")})
    assert xs == [0.0, 1.3]
    YadeEngine().write_deck(sc, sim, tmp_path)
    S = json.loads((tmp_path / "scene.json").read_text())
    assert S["periodic_x"] == [0.0, 1.3]
    # the wall law is 10x the disc law: no series value gives it, so the deck sets it per contact
    assert S["wall_phys"]["wall"]["rock"]["kn"] == m2d.KN_WALL
    assert S["yade_materials"]["rock"]["kn"] == 2 * m2d.KN


def test_liggghts_refuses_a_wall_moving_along_x_in_a_periodic_box(tmp_path):
    sc = E.conformance_scene(100)
    from demflow.scene import Phase

    sliding = dataclasses.replace(sc.walls[1], phases=(Phase(cycles=100, velocity=(0.1, -0.1)),))
    sc = dataclasses.replace(sc, walls=[sc.walls[0], sliding])
    with pytest.raises(EngineUnsupported, match="periodic-2d"):
        LiggghtsEngine().write_deck(sc, build(sc), tmp_path)


def test_half_step_start_is_a0_dt_over_2():
    """Discs falling freely: v(0) = v(-Δt/2) + gΔt/2 exactly.  A bed with contacts at t = 0: the momentum the half
    steps add, Σ m Δv / (Δt/2), is the weight plus the force of the walls, which demflow records at step 0."""
    sc = E.conformance_scene(10)
    free = build(dataclasses.replace(sc, walls=[], discs=dataclasses.replace(sc.discs, y=sc.discs.y + 10 * np.arange(8))))
    h = half_step_start(free)
    assert np.all(h[:, 1] == -0.5 * m2d.G * m2d.DT) and np.all(h[:, 0] == 0.0)
    y = np.array(sc.discs.y)
    y[:4] = R - 1e-4  # the bottom row pressed into the floor at t = 0
    sim = build(dataclasses.replace(sc, discs=dataclasses.replace(sc.discs, y=y)))
    h = half_step_start(sim)
    m = sim.mass
    got = float(np.sum(m * h[:, 1]) / (0.5 * sim.dt))
    sim.run(1)
    wf = sim.results().wall_forces
    walls_on_discs = -float(wf[wf.step == 0].fy.sum())
    assert walls_on_discs > 0.0
    assert got == pytest.approx(walls_on_discs - float(m.sum()) * m2d.G, rel=1e-12)


# ------------------------------------------------------------------------------------------ live engines
@pytest.mark.engines
def test_conformance_frictionless_to_round_off(tmp_path):
    """Periodic box, a disc across the boundary, gravity, contacts at t = 0, a plate, Table 2's stiff walls: every
    engine's trajectory equals demflow's to engines.matching-mode (tangential forces off: the lever-arm row)."""
    sc = _snap_every(_frictionless(E.conformance_scene(3000)))
    sim = build(sc)
    sim.run(sc.n_steps)
    d = sim.results()
    t = tol("engines.matching-mode").value
    for name in ("yade", "liggghts"):
        res, _ = get_engine(name).run(sc, tmp_path / name, timeout=600)
        diff = _max_position_difference(d, res, 1.3)
        assert diff <= t, (name, diff)
    plate = d.wall_forces[d.wall_forces.wall == "plate"]
    assert plate.fy.max() > 1e4  # the plate does load the heap


@pytest.mark.engines
def test_lever_arm_difference_is_isolated(tmp_path):
    """A spinning disc pressed into the floor (δ/R = 0.1, no friction limit, no dashpot): YADE's first shear force is
    demflow's × (R − δ/2)/R to round-off (capabilities row lever-arm-2d); with friction the conformance scene's
    trajectories part by far more than engines.matching-mode (negative control of the frictionless test)."""
    m = m2d.RHO * np.pi * R * R
    delta = 0.1 * R
    laws = {k: dataclasses.replace(v, cn=0.0, friction=10.0) for k, v in E.table2_laws(m).items()}
    sc = Scene(name="lever", discs=Discs(x=[0.5, 0.9], y=[R - delta, 1.0], radius=[R, R], material="rock",
                                         mass=[m, m], angular_velocity=[2.0, 0.0]),
               materials={"rock": Material(density=m2d.RHO), "wall": Material()}, laws=laws, walls=[m2d.floor_wall(1.0)],
               contact_model=ContactModel(normal="overlap"), gravity=(0.0, 0.0), dt=m2d.DT, n_steps=2,
               overlap_tolerance=0.5, outputs=Outputs(every=1, track_pairs=((0, "wall:floor"),)))
    sim = build(sc)
    sim.run(2)
    fs_d = sim.results().tracked.fs.iloc[0]
    res, _ = get_engine("yade").run(sc, tmp_path / "lever", timeout=300)
    fs_y = res.tracked.fs.iloc[0]
    assert abs(fs_y / fs_d - (R - delta / 2) / R) <= 1e-12
    assert abs(fs_y / fs_d - 1.0) > 0.04  # not the same lever
    sc = _snap_every(E.conformance_scene(3000))
    sim = build(sc)
    sim.run(sc.n_steps)
    d = sim.results()
    for name in ("yade", "liggghts"):
        res, _ = get_engine(name).run(sc, tmp_path / name, timeout=600)
        diff = _max_position_difference(d, res, 1.3)
        print(name, "with friction", diff)
        assert diff > 100 * tol("engines.matching-mode").value, (name, diff)


@pytest.mark.engines
@pytest.mark.parametrize("engine", ["yade", "liggghts"])
def test_stored_uniaxial_decks_are_what_the_writer_writes(engine, tmp_path):
    """The stored miyata-uniaxial-2d decks are the ones the harness writes now from seed 1's bed (runs seed 1 of
    the band, ~25 s, checkpointed under tmp_path: the user's runs/ is not written, and a checkpoint made by other
    code is never read)."""
    from demflow.engines import reference

    case = E.MiyataUniaxial2DEngines()
    params = dict(case.params, checkpoint_dir=str(tmp_path / "checkpoints"))
    for v in case.reference_plan().variants(engine):
        sc = case.reference_plan().scene(v, params)
        get_engine(engine).write_deck(sc, build(sc), tmp_path)
        stored = reference.location(E.STORE, v, engine)
        for f in ("deck.py", "deck.in", "scene.json"):
            if (stored / f).exists():
                assert (tmp_path / f).read_text() == (stored / f).read_text(), (v, f)


def test_compare_selects_engines_and_runs_them_live(monkeypatch):
    """`demflow compare miyata-uniaxial-2d-engines --engines demflow,yade --live` compares YADE only, run now;
    LIGGGHTS is named as not compared (an info line, not a pass).  The band and the runs are faked: this checks
    the plumbing, the stored-reference path is the slow page's."""
    import sys

    import demflow.engines as engines_pkg

    demflow_build = sys.modules["demflow.build"]  # the module (the package exports its function under that name)

    calls = []

    class FakeSim:
        def run(self, n):
            pass

        def results(self):
            return "demflow-results"

    class FakeEngine:
        def __init__(self, name):
            self.name = name

        def run(self, scene, workdir, timeout):
            calls.append((self.name, scene, timeout))
            return f"{self.name}-results", type("Made", (), {"wall_time_s": 12.5})()

    monkeypatch.setattr(E, "_band", lambda p: {})
    monkeypatch.setattr(E, "band_params", lambda p: dict(width=2.0, stress_max=9e5))
    monkeypatch.setattr(E, "_engine_start", lambda p, s: (type("Sc", (), {"n_steps": 3})(), None))
    monkeypatch.setattr(demflow_build, "build", lambda sc: FakeSim())
    monkeypatch.setattr(E, "engine_statistics", lambda res, w, smax: ({"who": res}, None, None))
    monkeypatch.setattr(engines_pkg, "get_engine", FakeEngine)
    case = E.MiyataUniaxial2DEngines().comparison_case()
    assert case.engines == ("yade", "liggghts") and case.live is False  # the defaults a plain validate uses
    case.engines, case.live = ("yade",), True
    runs = case.run(case.merged()).extras["runs"]
    assert [c[0] for c in calls] == ["yade"] * len(E.SAMPLES)
    for s in E.SAMPLES:
        assert runs[(s, "yade")] == ({"who": "yade-results"}, None, None, 12.5)
        assert isinstance(runs[(s, "liggghts")], str) and "not compared" in runs[(s, "liggghts")]
        assert runs[(s, "demflow (same start)")][0] == {"who": "demflow-results"}
