"""The uniaxial compression case's particles (issue 14, issue 16 item 2): clumps of the seed's ellipsoid or the
ellipsoid itself, each 191 kg; a particle's top (where the plate starts) and a clear error for an unknown shape.
The case itself is slow (``demflow validate --case miyata-uniaxial-3d``)."""
import math
import warnings

import numpy as np
import pytest

import demflow as df
from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d_protocol import insertion_scene, particle_tops
from demflow.shapes.clump import MIYATA_AXES, MIYATA_MASS


def _built(shape, n_insert=4):
    p = get_case("miyata-uniaxial-3d").merged({"shape": shape, "n_insert": n_insert})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", df.UnsafeTimeStepWarning)
        return df.build(insertion_scene(p))


@pytest.mark.parametrize("shape", ["clumps", "ellipsoids"])
def test_every_particle_weighs_191_kg(shape):
    sim = _built(shape)
    np.testing.assert_allclose(sim.bodies.mass, MIYATA_MASS, rtol=1e-12)


def test_an_ellipsoids_top_is_its_support_along_z():
    """Identity orientation: the top is z + a3; turned 90° about x (body y along world z): z + a2; a clump's top
    is its highest member's."""
    sim = _built("ellipsoids", n_insert=2)
    s = math.sqrt(0.5)
    sim.bodies.quat[:] = [[1.0, 0.0, 0.0, 0.0], [s, s, 0.0, 0.0]]
    from demflow.shapes.ellipsoid import rotations
    rotations(sim.bodies.quat, sim.ell.rot)
    z = sim.spheres.pos[:, 2]
    np.testing.assert_allclose(particle_tops(sim) - z, [MIYATA_AXES[2], MIYATA_AXES[1]], rtol=1e-12)
    c = _built("clumps", n_insert=2)
    assert np.all(particle_tops(c) <= c.spheres.pos[:, 2].max() + c.spheres.r.max())


def test_an_unknown_shape_is_refused_naming_it():
    case = get_case("miyata-uniaxial-3d")
    with pytest.raises(df.SceneError, match=r"shape='spheres'.*'clumps'.*'ellipsoids'"):
        case.run(case.merged({"shape": "spheres"}))


def test_bed_figures_write_a_vtk_bed_and_a_plate_force_map(tmp_path):
    """The figure page's bed picture (matplotlib), its VTK file (member centres with radius and body) and
    the plate force map of the last snapshot."""
    from demflow.cases.miyata_uniaxial3d_figures import bed_figures

    rng = np.random.default_rng(0)
    pos = rng.uniform(0.0, 2.0, (16, 3))
    bed = {"pos": pos, "r": np.full(16, 0.15), "body": np.repeat(np.arange(2), 8), "plate_z": 2.1, "box": 2.0}
    snaps = [{"stress": 4e5, "plate": np.array([1e5, 2e5]), "floor": np.array([1e5]),
              "plate_xy": np.array([[0.5, 0.5], [2.5, 1.0]])}]  # an unwrapped centre is drawn inside the box
    paths = bed_figures({"bed": bed, "snapshots": snaps}, tmp_path)
    vtu = (tmp_path / "bed_end.vtu").read_text(errors="replace")
    assert str(tmp_path / "bed_end.vtu") in paths and 'NumberOfPoints="16"' in vtu and "radius" in vtu and "body" in vtu
    assert (tmp_path / "bed_and_plate_map.png").stat().st_size > 10000


# a small protocol (4 clumps after trimming, fast plate) for the resume and micro-state tests: ~3 s
SMALL = dict(box=1.6, n_insert=12, trim=1.0, settle_max=20000, stress_max=450e3, snapshots=3, plate_speed=0.2,
             record_every=200)


def _small(**kw):
    return get_case("miyata-uniaxial-3d").merged(dict(SMALL, **kw))


def _protocol(p):
    from demflow.cases.miyata_uniaxial3d_protocol import protocol_run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", df.UnsafeTimeStepWarning)
        return protocol_run(p)


# calls of Simulation3D.run: 4 settling chunks per stage, then one per record of the loading (11 records)
@pytest.mark.parametrize("stop_after", [2, 6, 16])  # in the first settling, in the second, in the loading
def test_an_interrupted_protocol_resumes_from_its_checkpoints_to_the_bit(tmp_path, monkeypatch, stop_after):
    import demflow.cases.miyata_uniaxial3d_protocol as m
    from demflow.simulation3d import Simulation3D

    monkeypatch.setattr(m, "CHECKPOINT_STEPS", 1000)  # a checkpoint at every settling chunk and every 5 records
    whole = _protocol(_small())
    real = Simulation3D.run
    calls = {"n": 0}

    def interrupted(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == stop_after:
            raise KeyboardInterrupt
        return real(self, *a, **k)

    monkeypatch.setattr(Simulation3D, "run", interrupted)
    p = _small(checkpoint_dir=str(tmp_path))
    with pytest.raises(KeyboardInterrupt):
        _protocol(p)
    saved = list(tmp_path.glob("seed1-*/*"))
    assert {f.name for f in saved if f.suffix == ".npz"} == \
        ({"settle1.npz"} if stop_after == 2 else {"settle1.npz", "settle2.npz"} if stop_after == 6 else
         {"settle1.npz", "settle2.npz", "loading.npz"}), saved
    monkeypatch.setattr(Simulation3D, "run", real)
    resumed = _protocol(p)
    assert resumed["settle_steps"] == whole["settle_steps"]
    assert resumed["particle_steps"] == whole["particle_steps"]  # the work of every stage, resumed or not
    cols = [c for c in whole["curve"].columns]
    np.testing.assert_array_equal(resumed["curve"][cols].to_numpy(), whole["curve"][cols].to_numpy())
    np.testing.assert_array_equal(resumed["bed"]["pos"], whole["bed"]["pos"])
    assert len(resumed["snapshots"]) == len(whole["snapshots"])
    calls["n"] = 0
    monkeypatch.setattr(Simulation3D, "run", interrupted)  # a completed run is not run again: the same result
    again = _protocol(p)
    assert calls["n"] == 0
    np.testing.assert_array_equal(again["curve"][cols].to_numpy(), whole["curve"][cols].to_numpy())
    # reloading a finished run is not computing it: its compute time is the stored one, whatever the reload took
    # (it grew by the reload's time at every rendering of a page, e.g. the K-sweep's cost ratios)
    # and the run that computed it states the stored time too (it stated a time taken after its last checkpoint,
    # 1e-4 apart from what a re-rendered page then showed)
    stored = m.ProtocolCheckpoints(str(tmp_path), p).load("compute_s")
    assert again["compute_s"] == stored == _protocol(p)["compute_s"] == resumed["compute_s"] and stored > 0.0


def test_the_protocol_counts_the_particle_steps_of_every_stage(monkeypatch):
    """The trade-off study's particle-steps/s of this case: the clumps × steps of each stage (the trimmed bed has fewer
    clumps than the inserted one), counted here at every call of the step loop."""
    from demflow.simulation3d import Simulation3D

    real = Simulation3D.run
    done = {"particle_steps": 0, "stages": set()}

    def counting(self, n_steps, *a, **k):
        done["particle_steps"] += len(self.bodies.mass) * int(n_steps)
        done["stages"].add(len(self.bodies.mass))
        return real(self, n_steps, *a, **k)

    monkeypatch.setattr(Simulation3D, "run", counting)
    out = _protocol(_small())
    assert len(done["stages"]) == 2  # 12 inserted, fewer after trimming
    assert out["particle_steps"] == done["particle_steps"] > 0


def test_checkpoints_of_other_parameters_are_not_resumed(tmp_path):
    from demflow.cases.miyata_uniaxial3d_protocol import ProtocolCheckpoints

    a = ProtocolCheckpoints(tmp_path, _small())
    assert a.dir == ProtocolCheckpoints(tmp_path, _small(progress=True, band_seeds=3)).dir  # not physics
    for change in ({"seed": 2}, {"plate_speed": 0.1}, {"local_damping": 0.0}, {"box": 2.0}):
        assert ProtocolCheckpoints(tmp_path, _small(**change)).dir != a.dir, change


def test_the_beds_average_stress_meets_the_statics_of_a_bed_between_floor_and_plate():
    """σ_zz (ch3 eq 3.17 over the bed) against σ_plate + (W/A) Z̄/H, which holds exactly for a bed at rest
    (demflow.analysis.micro3d): the loading at 0.2 m/s is near enough rest for 1 %; coordination and fabric
    are those of the listed contacts (fabric trace 1)."""
    r = _protocol(_small())
    c = r["curve"]
    late = c[c.plate_stress > 200e3]
    assert len(late) >= 2
    np.testing.assert_allclose(late.stress_zz, late.stress_zz_statics, rtol=1e-2)
    np.testing.assert_allclose(late.fabric_xx + late.fabric_yy + late.fabric_zz, 1.0, rtol=1e-12)
    assert (late.fabric_zz > 1 / 3).all()  # loaded along z: contact normals lean towards z
    assert (c.coordination_walls >= c.coordination).all()


def _seed_like_run(final_kink=1.0, floor=257.0, floor_drift=0.0, contacts=None, snapshots=()):
    """A synthetic run with the seed's Fig. 32/33 statements built in: 100 kPa at 0.1 m, 400 kPa at 0.2 m,
    linear to 600 kPa at 0.3 m (the second half ``final_kink`` × stiffer), plate contacts rising ever more
    slowly, ``floor`` floor contacts drifting by ``floor_drift`` over the run, on 100 m²."""
    import pandas as pd

    s = np.linspace(0.0, 0.3, 301)
    k3a = 100e3 / 0.05
    sig = np.where(s <= 0.1, 1e6 * s, np.where(s <= 0.2, 100e3 + 3e6 * (s - 0.1),
                   np.where(s <= 0.25, 400e3 + k3a * (s - 0.2), 500e3 + final_kink * k3a * (s - 0.25))))
    plate = 60 * (1 - np.exp(-sig / 150e3)) if contacts is None else contacts(sig)
    fl = floor * (1 + floor_drift * s / 0.3)
    c = pd.DataFrame({"settlement": s + 1e-9, "plate_stress": sig, "plate_contacts": plate, "floor_contacts": fl})
    return {"curve": c, "area": 100.0, "snapshots": list(snapshots)}


def _by_name(checks, start):
    return next(c for c in checks if c.name.startswith(start))


def test_the_seeds_curve_statements_pass_on_a_curve_that_has_them():
    from demflow.cases.miyata_uniaxial3d import seed_statement_checks

    checks = seed_statement_checks(_seed_like_run())
    assert len(checks) == 5 and all(c.passed for c in checks), [(c.name, c.passed) for c in checks]


@pytest.mark.parametrize("change,which", [
    (dict(final_kink=1.5), "Fig. 32: almost linear"),  # negative control of miyata3d.final-linear (±25 %)
    (dict(floor=257 * 1.2), "Fig. 33: floor contacts during"),  # of miyata3d.floor-contacts-257 (15 %)
    (dict(floor_drift=0.15), "Fig. 33: floor contacts almost constant"),  # of miyata3d.floor-constant (10 %)
    (dict(contacts=lambda sig: 60 * sig / 600e3), "Fig. 33: plate contacts rise"),  # a constant rate
])
def test_each_seed_statement_fails_on_a_curve_without_it(change, which):
    from demflow.cases.miyata_uniaxial3d import seed_statement_checks

    checks = seed_statement_checks(_seed_like_run(**change))
    assert not _by_name(checks, which).passed
    assert sum(not c.passed for c in checks) == 1


def _mueth_sample(rng, n, b=0.75):
    """Draws of Miyata eq 61 with the seed's b and <f> = 1 (β = 1.46; the printed β = 1.5 gives <f> = 0.977)."""
    from demflow.analysis.forces import mueth_pdf
    from demflow.cases.miyata_uniaxial3d import mueth_beta_for_mean_one

    beta = mueth_beta_for_mean_one(b)
    top = mueth_pdf(np.linspace(0, 3, 301), b, beta).max()
    out = []
    while len(out) < n:
        f = rng.uniform(0, 12, 4 * n)
        out += list(f[rng.uniform(0, top, f.size) < mueth_pdf(f, b, beta)])
    return np.asarray(out[:n])


@pytest.mark.parametrize("N,b,ok", [(3.0, 0.75, True), (8.0, 0.0, False)])
def test_the_force_pdf_statements_follow_the_forces(N, b, ok):
    """Plate forces drawn from the q-model with N = 3 pass Fig. 35's check, with N = 8 fail it; floor forces drawn
    from Mueth's law with the seed's b pass, with b = 0 (an exponential) fail (80 and 250 particles, 10
    independent snapshots)."""
    from demflow.cases.miyata_uniaxial3d import seed_statement_checks

    rng = np.random.default_rng(5)
    snaps = [{"stress": 4e5, "plate": rng.gamma(N, 1.0 / N, 80), "plate_ids": np.arange(80),
              "floor": _mueth_sample(rng, 250, b), "floor_ids": np.arange(250)} for _ in range(10)]
    checks = seed_statement_checks(_seed_like_run(snapshots=snaps), n_resamples=200)
    assert _by_name(checks, "Fig. 35: plate").passed is ok
    assert _by_name(checks, "Fig. 35: floor").passed is ok
    # Fig. 37: N = 8 is so narrow that forces above 2<F> carry almost nothing (fails); an exponential floor passes
    assert _by_name(checks, "Fig. 37, plate").passed is ok
    assert _by_name(checks, "Fig. 37, floor").passed


def test_a_particles_contact_point_is_its_members_force_weighted_centre_across_the_periodic_seam():
    """Two members of body 0 touch the plate on either side of x = 0 (x = 1.9 and 0.1 in a 2 m box, forces 1 and
    3): the point is 1.9 + (0.2 × 3/4) = 2.05 → 0.05; body 1's single member is itself; ascending body order."""
    from types import SimpleNamespace

    from demflow.cases.miyata_uniaxial3d_protocol import per_particle_forces, wall_contact_points

    n = 4
    sp = SimpleNamespace(pos=np.array([[1.9, 1.0, 0.1], [0.1, 1.2, 0.1], [0.7, 0.3, 0.1], [1.0, 1.0, 1.0]]),
                         body=np.array([1, 1, 0, 0]))
    pairs = SimpleNamespace(i=np.array([0, 1, 2, 3]), j=np.array([n + 1, n + 1, n + 1, n + 0]),
                            fn=np.array([1.0, 3.0, 2.0, 5.0]))
    sim = SimpleNamespace(n=n, spheres=sp, pairs=pairs, bodies=SimpleNamespace(mass=np.ones(2)))
    pts = wall_contact_points(sim, 1, 2.0)
    np.testing.assert_allclose(pts, [[0.7, 0.3], [0.05, 1.15]], atol=1e-12)
    np.testing.assert_allclose(per_particle_forces(sim, 1), [2.0, 4.0])


def test_the_ellipsoid_full_variant_is_the_full_protocol_with_the_seeds_particle(tmp_path):
    """miyata-uniaxial-3d-ellipsoids-full differs from miyata-uniaxial-3d-full only in the particle and where its
    checkpoints live, and its checkpoints are never the clumps' (the shape is part of their key)."""
    from demflow.cases import get_case
    from demflow.cases.miyata_uniaxial3d_protocol import ProtocolCheckpoints

    full, ell = get_case("miyata-uniaxial-3d-full"), get_case("miyata-uniaxial-3d-ellipsoids-full")
    differ = {k for k in full.params if full.params[k] != ell.params[k]}
    assert differ == {"shape", "checkpoint_dir"} and ell.params["shape"] == "ellipsoids" and ell.slow
    assert ell.params["box"] == 10.0 and ell.params["n_insert"] == 1500
    assert ProtocolCheckpoints(tmp_path, full.merged()).dir != ProtocolCheckpoints(tmp_path, ell.merged()).dir
    assert any(a.startswith("Δt = 0.2 × the Rayleigh step of the smallest semi-axis") for a in ell.assumptions)


def test_monotone_steps_and_stress_falls_on_a_hand_made_curve():
    """The monotone check's samples and the falls below the running maximum, on a curve worked by hand."""
    import pandas as pd

    from demflow.cases.miyata_uniaxial3d_statistics import monotone_steps, stress_falls

    c = pd.DataFrame({"settlement": [0.0, 1.0, 2.0, 3.0, 4.0, 5.0], "plate_stress": [0.0, 10.0, 20.0, 15.0, 30.0, 5.0]})
    # settlements 1..5 sampled at 5 points: the records themselves
    assert monotone_steps(c, samples=5).tolist() == [10.0, -5.0, 15.0, -25.0]
    d = stress_falls(c, deep=0.05, past=25.0)
    assert (d["fall"], d["i_from"], d["i_to"]) == (25.0, 4, 5)
    assert d["rel"] == 25.0 / 30.0
    assert d["n_deep"] == 2  # 20 -> 15 and 30 -> 5
    assert d["n_deep_past"] == 1  # only the second starts from a maximum >= 25
    rising = c.assign(plate_stress=[0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    assert stress_falls(rising)["n_deep"] == 0 and (monotone_steps(rising) >= 0).all()


def test_the_reduced_variant_runs_in_the_default_validate_and_the_others_do_not():
    """Issue 14 item 2: the reduced variant is a default case of `demflow validate`; the full run, the ellipsoid
    variants, the K-sweep and the trade-off study stay slow (minutes to an hour each)."""
    from demflow.cases import CASES

    assert not CASES["miyata-uniaxial-3d"].slow
    for name in ("miyata-uniaxial-3d-full", "miyata-uniaxial-3d-ellipsoids", "miyata-uniaxial-3d-ellipsoids-full",
                 "miyata-uniaxial-3d-ksweep", "tradeoff-miyata-uniaxial-3d"):
        assert CASES[name].slow, name


def test_random_insertion_follows_the_liggghts_decks_rule():
    """random_insertion (the LIGGGHTS deck's insert/pack, all_in yes): n bounding spheres wholly inside the region,
    none overlapping, in a region as tall as the deck's; the same seed gives the same points; no room is an error."""
    import math

    from demflow.cases.miyata_uniaxial3d_protocol import bounding_radius, random_insertion
    from demflow.engines.liggghts_uniaxial3d import PACKING

    p = get_case("miyata-uniaxial-3d").merged()
    rb = bounding_radius(p)
    # the K = 8 cover is inscribed in the ellipsoid (semi-axes 37.1, 26.0, 18.2 cm): its bounding sphere about the
    # centre of mass reaches past the middle semi-axis and stays inside the longest
    assert 0.26 < rb < 0.371
    n, L = 80, 2.0
    pos = random_insertion(n, L, rb, np.random.default_rng(3))
    H = n * (4.0 / 3.0 * math.pi * rb ** 3) / (PACKING * L * L) + 2.0 * rb
    assert pos.shape == (n, 3)
    assert np.all(pos[:, :2] >= rb) and np.all(pos[:, :2] <= L - rb)
    assert np.all(pos[:, 2] >= 0.05 + rb) and np.all(pos[:, 2] <= 0.05 + rb + H)
    d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2) + np.eye(n) * 1e9
    assert d.min() >= 2.0 * rb
    assert np.array_equal(pos, random_insertion(n, L, rb, np.random.default_rng(3)))
    assert not np.array_equal(pos, random_insertion(n, L, rb, np.random.default_rng(4)))
    with pytest.raises(ValueError, match="no room"):
        random_insertion(20, L, rb, np.random.default_rng(0), packing=5.0, max_tries=50)


def test_insertion_option_leaves_the_lattice_and_its_checkpoints_alone(tmp_path):
    """insertion='lattice' (the default) is the case's lattice, its checkpoint key unchanged by the option's
    existence; 'random' moves the particles and keys its checkpoints apart; anything else is refused."""
    from demflow.cases.miyata_uniaxial3d_protocol import ProtocolCheckpoints, insertion_scene
    from demflow.scene import SceneError

    p = get_case("miyata-uniaxial-3d").merged({"n_insert": 8})
    lat = insertion_scene(p)
    no_key = {k: v for k, v in p.items() if k != "insertion"}
    assert np.array_equal(lat.clumps.x, insertion_scene(no_key).clumps.x)
    assert ProtocolCheckpoints(tmp_path, p).dir == ProtocolCheckpoints(tmp_path, no_key).dir
    rnd = dict(p, insertion="random")
    assert not np.array_equal(lat.clumps.z, insertion_scene(rnd).clumps.z)
    assert ProtocolCheckpoints(tmp_path, rnd).dir != ProtocolCheckpoints(tmp_path, p).dir
    with pytest.raises(SceneError, match="insertion='grid'"):
        insertion_scene(dict(p, insertion="grid"))


def test_shear_spring_option_sets_the_law_and_keys_checkpoints_apart(tmp_path):
    """shear_spring='total' (LIGGGHTS's Mindlin spring, capabilities row shear-spring-uniaxial) reaches every law of
    the protocol's scenes; the default keeps the incremental spring and its checkpoint key."""
    from demflow.cases.miyata_uniaxial3d_protocol import ProtocolCheckpoints

    p = get_case("miyata-uniaxial-3d").merged({"n_insert": 8})
    assert {law.shear_spring for law in insertion_scene(p).laws.values()} == {"incremental"}
    tot = dict(p, shear_spring="total")
    assert {law.shear_spring for law in insertion_scene(tot).laws.values()} == {"total"}
    assert ProtocolCheckpoints(tmp_path, tot).dir != ProtocolCheckpoints(tmp_path, p).dir
    no_key = {k: v for k, v in p.items() if k != "shear_spring"}
    assert ProtocolCheckpoints(tmp_path, p).dir == ProtocolCheckpoints(tmp_path, no_key).dir


def _synthetic_seeds(rng, n, shift=0.0, prefix="s"):
    """{label: statistics} of n runs: three statistics drawn independently, N(100, 10), N(2.0, 0.05), N(50, 5),
    the first shifted by ``shift`` standard deviations."""
    return {f"{prefix}{k}": {"a": float(rng.normal(100.0 + 10.0 * shift, 10.0)), "b": float(rng.normal(2.0, 0.05)),
                             "c": float(rng.normal(50.0, 5.0))} for k in range(n)}


def test_holm_adjustment_matches_its_definition():
    from demflow.cases.miyata_uniaxial3d_bands import holm

    # p sorted: 0.01, 0.02, 0.04 (m = 3): 3 × 0.01, max(0.03, 2 × 0.02), max(0.04, 1 × 0.04); nan kept out and as is
    out = holm({"x": 0.04, "y": 0.01, "z": 0.02, "w": math.nan})
    assert out["y"] == pytest.approx(0.03) and out["z"] == pytest.approx(0.04) and out["x"] == pytest.approx(0.04)
    assert math.isnan(out["w"])
    assert holm({"x": 0.6, "y": 0.5})["x"] == 1.0  # capped at 1


def test_engine_ensemble_passes_draws_of_demflows_distribution_and_fails_a_shift():
    """miyata3d.engine-ensemble's negative control on synthetic seeds: 8 + 8 runs from one distribution pass the
    Holm-adjusted Welch lines in at least 90 of 100 draws (family-wise level 5 %); a shift of 3 s.d. in one
    statistic fails in at least 90 of 100 (Welch's power at 8 + 8 and 3 s.d. is about 0.99)."""
    from demflow.cases.miyata_uniaxial3d_bands import ENSEMBLE_ALPHA, ensemble_comparison

    rng = np.random.default_rng(20261128)
    same = shifted = 0
    for _ in range(100):
        d = _synthetic_seeds(rng, 8)
        same += all(r["holm p"] >= ENSEMBLE_ALPHA for r in ensemble_comparison(d, _synthetic_seeds(rng, 8, 0.0, "e")).values())
        rows = ensemble_comparison(d, _synthetic_seeds(rng, 8, 3.0, "e"))
        shifted += rows["a"]["holm p"] < ENSEMBLE_ALPHA
    assert same >= 90 and shifted >= 90


def test_engine_ensemble_negative_control_fails_ten_percent_more_particles():
    from demflow.cases.miyata_uniaxial3d import ensemble_negative_control

    rng = np.random.default_rng(7)
    per_seed = {s: {"particles after trimming": float(76 + rng.integers(0, 5)), "bed top before loading [m]":
                    float(rng.normal(2.1, 0.03))} for s in range(1, 9)}
    c = ensemble_negative_control(per_seed)
    assert c.passed and c.value < 0.05
    assert not ensemble_negative_control(per_seed, factor=1.0).passed  # the unchanged seeds are not "different"


def test_miss_rate_test_is_one_sided_fisher():
    from demflow.cases.miyata_uniaxial3d_bands import miss_rate_test

    # 2 misses among 16 runs, 8 of them the engine's: P(X >= 1) = 1 - C(14, 8)/C(16, 8) (hypergeometric)
    assert miss_rate_test(1, 8, 1, 8) == pytest.approx(1.0 - math.comb(14, 8) / math.comb(16, 8), rel=1e-12)
    assert miss_rate_test(7, 8, 1, 8) < 0.01
    assert miss_rate_test(0, 8, 5, 8) == 1.0
