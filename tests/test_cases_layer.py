"""The case layer: shared fixtures, informative checks, hooks instead of name branches, CaseRun."""
import ast
import math
from pathlib import Path

import numpy as np
import pytest

import demflow
from demflow.cases import CASES, Case, CaseRun, Check, comparison_cases, reference_cases
from demflow.cases.base import counted
from demflow.cases.fixtures import box_walls, random_sequential_addition, run_until


# -- box_walls
@pytest.mark.parametrize("ccw", [True, False])
def test_box_walls_close_the_box_exactly_by_default(ccw):
    ws = box_walls(1.0, 5.0, -2.0, 1.0, counter_clockwise=ccw)
    assert [w.name for w in ws] == ["bottom", "right", "top", "left"]
    ends = {}
    for w in ws:
        p, e = np.asarray(w.point), np.asarray(w.direction)
        ends[w.name] = {tuple(p + w.h1 * e), tuple(p + w.h2 * e)}
    assert ends["bottom"] == {(1.0, -2.0), (5.0, -2.0)}
    assert ends["right"] == {(5.0, -2.0), (5.0, 1.0)}
    assert ends["top"] == {(1.0, 1.0), (5.0, 1.0)}
    assert ends["left"] == {(1.0, -2.0), (1.0, 1.0)}
    top, left = ws[2].direction, ws[3].direction
    assert (top, left) == (((-1.0, 0.0), (0.0, -1.0)) if ccw else ((1.0, 0.0), (0.0, 1.0)))


def test_box_walls_half_lengths_phases_servos():
    from demflow.scene import Phase, Servo

    ph = {"top": (Phase(10, velocity=(0.0, -1.0)),)}
    sv = {"right": Servo(1.0, (-1.0, 0.0), 0.1, 0.1)}
    ws = box_walls(0.0, 300.0, 0.0, 300.0, half_length=(400.0, 250.0), phases=ph, servos=sv)
    assert [(w.h1, w.h2) for w in ws] == [(-400.0, 400.0), (-250.0, 250.0)] * 2
    assert ws[2].phases == ph["top"] and ws[1].servo is sv["right"] and ws[0].servo is None
    assert {(w.h1, w.h2) for w in box_walls(0.0, 1.0, 0.0, 2.0, half_length=3.0)} == {(-3.0, 3.0)}
    with pytest.raises(ValueError, match="no wall named"):
        box_walls(0.0, 1.0, 0.0, 1.0, phases={"roof": ()})
    with pytest.raises(ValueError, match="empty"):
        box_walls(1.0, 0.0, 0.0, 1.0)


# -- random sequential addition
def _overlap_free(x, y, r, box, gap=0.0):
    x0, x1, y0, y1 = box
    assert np.all(x - r >= x0) and np.all(x + r <= x1) and np.all(y - r >= y0) and np.all(y + r <= y1)
    d = np.hypot(x[:, None] - x[None], y[:, None] - y[None])
    s = r[:, None] + r[None] + gap
    np.fill_diagonal(d, np.inf)
    assert np.all(d >= s * (1 - 1e-12))


def test_rsa_is_deterministic_and_overlap_free():
    r = np.repeat([2.0, 1.5, 1.0], [5, 10, 20])
    box = (0.0, 30.0, 0.0, 20.0)
    a = random_sequential_addition(r, box, np.random.default_rng(3), gap=0.01)
    b = random_sequential_addition(r, box, np.random.default_rng(3), gap=0.01)
    assert all(u.tobytes() == v.tobytes() for u, v in zip(a, b))
    _overlap_free(*a, box, gap=0.01)
    c = random_sequential_addition(r, box, np.random.default_rng(4), gap=0.01)
    assert not np.array_equal(a[0], c[0])


def test_rsa_with_radius_drawn_per_try():
    x, y, r = random_sequential_addition(lambda g: g.uniform(0.5, 1.0), (0.0, 20.0, 0.0, 20.0),
                                         np.random.default_rng(0), n=40)
    assert r.size == 40 and r.min() >= 0.5 and r.max() <= 1.0
    _overlap_free(x, y, r, (0.0, 20.0, 0.0, 20.0))
    with pytest.raises(ValueError, match="give the number of discs n"):
        random_sequential_addition(lambda g: 1.0, (0.0, 1.0, 0.0, 1.0), np.random.default_rng(0))


def test_rsa_jams_with_a_clear_error():
    with pytest.raises(RuntimeError, match="jammed.*larger box"):
        random_sequential_addition(np.full(10, 1.0), (0.0, 4.0, 0.0, 4.0), np.random.default_rng(0), tries=50,
                                   restarts=2)


# -- run_until
class _Counter:
    """A stand-in simulation: ``step`` advances by ``run(n)``."""

    def __init__(self):
        self.step = 0
        self.calls = 0

    def run(self, n):
        self.step += n
        self.calls += 1
        return self


def test_run_until_stops_when_the_condition_holds():
    sim = _Counter()
    assert run_until(sim, lambda s: s.step >= 35, max_step=1000, chunk=10) is True
    assert sim.step == 40 and sim.calls == 4


def test_run_until_at_the_limit_raises_or_returns_false():
    with pytest.raises(RuntimeError, match="never did not hold by step 100"):
        run_until(_Counter(), lambda s: False, max_step=100, chunk=10, what="never")
    sim = _Counter()
    assert run_until(sim, lambda s: False, max_step=100, chunk=7, raise_at_limit=False) is False
    assert sim.step == 105
    with pytest.raises(ValueError, match="chunk = 0"):
        run_until(_Counter(), lambda s: True, max_step=10, chunk=0)


def test_run_until_on_a_real_simulation():
    from demflow import Discs, LinearLaw, Material, Outputs, Scene, build

    sc = Scene(name="fall", discs=Discs([0.5], [5.0], [0.5], "d"), materials={"d": Material(1.0), "wall": Material()},
               laws={("d", "wall"): LinearLaw(kn=1e4)}, walls=box_walls(0.0, 1.0, 0.0, 10.0), gravity=(0.0, -10.0),
               dt=1e-3, outputs=Outputs(every=0))
    sim = build(sc)
    assert run_until(sim, lambda s: s.y[0] < 4.0, max_step=10_000, chunk=10)
    assert sim.y[0] < 4.0 and sim.step % 10 == 0


# -- Check.info and the counts
def test_info_is_reported_but_never_counted():
    ok = Check("a", 1.0, 1.0, 1e-3, "src", "why", kind="exact")
    bad = Check("b", 2.0, 1.0, 1e-3, "src", "why", kind="source")
    i1 = Check.info("c", 5.0, "src", "shown only")
    i2 = Check.info("d", 1.5, "src", "shown only", reference=1.0)
    assert i1.kind == i2.kind == "info" and i1.passed and i2.passed and i1.informative
    assert math.isinf(i1.tolerance) and i1.error == 0.0 and i1.reference == 5.0 and not i1.relative
    assert i2.error == 0.5 and i2.relative
    assert counted([ok, bad, i1, i2]) == [ok, bad]
    from demflow.report import check_counts

    rows = [dict(passed=c.passed, kind=c.kind, tolerance=c.tolerance) for c in (ok, bad, i1, i2)]
    assert check_counts(rows) == "1/2 checks pass, 2 informative"
    assert check_counts(rows[:1]) == "1/1 checks pass"
    # a summary written before kinds existed: infinite tolerance marks an informative line
    assert check_counts([dict(passed=True, tolerance=math.inf), dict(passed=True, tolerance=0.1)]) == \
        "0/0 checks pass, 1/1 unclassified, 1 informative"


def test_report_counts_info_apart(tmp_path):
    from demflow.report import write_report

    checks = [dict(name=c.name, value=c.value, reference=c.reference, error=c.error, tolerance=c.tolerance,
                   passed=c.passed, source=c.source, why=c.why, relative=c.relative, kind=c.kind)
              for c in (Check("a", 1.0, 1.0, 1e-3, "s", "w", kind="exact"), Check.info("i", 2.0, "s", "w"))]
    summary = dict(generated="now", python="3", machine="m", cases={"thesis-one-disc": dict(
        title="t", source="s", params={}, wall_time_s=0.0, passed=True, assumptions=[], figures=[], checks=checks)})
    write_report(summary, tmp_path)
    assert "1/1 checks pass, 1 informative" in (tmp_path / "index.html").read_text()
    assert ">info<" in (tmp_path / "thesis-one-disc" / "index.html").read_text()


def test_report_shows_images_and_links_other_outputs(tmp_path):
    """A case's figure list may hold data files (miyata-uniaxial-3d's bed_end.vtu): linked, not drawn."""
    from demflow.report import write_report

    summary = dict(generated="now", python="3", machine="m", cases={"thesis-one-disc": dict(
        title="t", source="s", params={}, wall_time_s=0.0, passed=True, assumptions=[],
        figures=["a.png", "bed_end.vtu"], checks=[])})
    write_report(summary, tmp_path)
    page = (tmp_path / "thesis-one-disc" / "index.html").read_text()
    assert "<img src='a.png'>" in page and "<img src='bed_end.vtu'>" not in page
    assert "<a href='bed_end.vtu'>" in page


# -- hooks and the typed return
def test_reference_and_compare_choices_come_from_the_registry():
    with_engines = {"cs-nine-disc", "cs-photoelastic", "conformance-3d", "miyata-uniaxial-3d"}
    # not the ellipsoid variant: no engine expresses ellipsoids
    assert set(reference_cases()) == with_engines | {"miyata-uniaxial-2d-engines"}
    assert set(comparison_cases()) == with_engines | {"miyata-uniaxial-2d-engines"}
    plan_u = CASES["miyata-uniaxial-3d"].reference_plan()
    assert plan_u.variants("yade") == tuple(f"seed{s}" for s in range(1, 9)) and plan_u.engine("liggghts", "seed2").params["seed"] == 2
    plan3 = CASES["conformance-3d"].reference_plan()
    assert plan3.engine("yade", "oblique-plane-r2").compensate_walls is False  # the engine object comes from the plan
    plan = CASES["cs-nine-disc"].reference_plan()
    assert plan.store == "cs-nine-disc" and "undamped" in plan.variants("liggghts")
    assert CASES["cs-nine-disc"].comparison_case().name == "cs-nine-disc-engines"
    from demflow.cli import main

    for cmd in ("reference", "compare"):
        with pytest.raises(SystemExit):
            main([cmd, "thesis-one-disc", "--engine", "yade"] if cmd == "reference" else [cmd, "thesis-one-disc"])


def test_page_sections_hook():
    assert [t for t, _ in CASES["cs-nine-disc-engines"].page_sections()] == ["Model-equivalence table"]
    assert Case.page_sections() == []


@pytest.mark.parametrize("module", ["cli.py", "report/validation.py"])
def test_no_branch_on_a_case_name(module):
    """The CLI and the report look cases up through hooks, never by comparing a name string."""
    tree = ast.parse((Path(demflow.__file__).parent / module).read_text())
    names = set(CASES)
    found = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and n.value in names]
    assert not found, f"{module} names cases {found}; give the case a hook (demflow/cases/base.py) instead"


def test_a_case_run_is_a_caserun():
    case = CASES["thesis-impact"]
    p = case.merged()
    run = case.run(p)
    assert isinstance(run, CaseRun) and set(run.results) == {"thesis"} and run.extras == {}
    assert sum(c.kind == "source" for c in case.checks(run, p)) == 4  # Table 2.4 within the thesis's stated 1 %


# -- kinds (issue 18 item 1)
def test_every_check_has_a_kind_and_tolerances_carry_one():
    from demflow.tolerances import KINDS, TOLERANCES

    assert all(t.kind in KINDS for t in TOLERANCES.values())
    assert Check.against("x", 1.0, 1.0, "bem.moving-planes", "s").kind == "calibration"
    with pytest.raises(ValueError, match="kind '' is not one of"):
        Check("x", 1.0, 1.0, 0.1, "s", "w")
    with pytest.raises(TypeError):
        Check.condition("x", True, 1.0, "s", "w")


def test_calibrations_and_info_are_not_validation_and_summary_is_strict_json(tmp_path):
    import json

    from demflow.report import check_counts, write_report

    cs = [Check("a", 1.0, 1.0, 1e-3, "s", "w", kind="source"), Check("b", 1.0, 1.0, 1e-3, "s", "w", kind="exact"),
          Check.condition("c", False, 3.0, "s", "w", kind="calibration"), Check.info("i", 2.0, "s", "w")]
    rows = [dict(name=c.name, value=c.value, reference=c.reference, error=c.error, tolerance=c.tolerance,
                 passed=c.passed, source=c.source, why=c.why, relative=c.relative, kind=c.kind) for c in cs]
    assert check_counts(rows) == "2/2 checks pass, 0/1 calibrations, 1 informative"
    summary = dict(generated="now", python="3", machine="m", cases={"thesis-one-disc": dict(
        title="t", source="s", params={}, wall_time_s=0.0, passed=False, assumptions=[], figures=[], checks=rows)})
    write_report(summary, tmp_path)
    d = json.load(open(tmp_path / "summary.json"), parse_constant=lambda c: 1 / 0)
    assert d["validation"] == {"passed": 2, "total": 2}
    assert d["counts"]["calibration"] == {"passed": 0, "total": 1} and d["counts"]["info"]["total"] == 1
    assert d["cases"]["thesis-one-disc"]["checks"][3]["tolerance"] is None
    index = (tmp_path / "index.html").read_text()
    assert "Validation checks passed: 2/2" in index and "calibration 0/1" in index


def test_every_check_built_in_demflow_names_its_kind():
    """Static: a slow case must not find out at run time that a check lacks its kind."""
    missing = []
    for f in (Path(demflow.__file__).parent / "cases").glob("*.py"):
        for n in ast.walk(ast.parse(f.read_text())):
            if isinstance(n, ast.Call):
                fn = n.func
                direct = isinstance(fn, ast.Name) and fn.id == "Check"
                cond = isinstance(fn, ast.Attribute) and fn.attr == "condition" and getattr(fn.value, "id", "") == "Check"
                if (direct or cond) and "kind" not in {k.arg for k in n.keywords}:
                    missing.append(f"{f.name}:{n.lineno}")
    assert not missing, f"checks without a kind: {missing}; pass kind= (demflow/tolerances.py lists the kinds)"


# -- the validate runner: a case that raises is a failed entry; entries written meanwhile are kept
class _Broken(Case):
    name = "thesis-one-disc"
    title = "broken"
    source = "test"

    def run(self, p):
        raise RuntimeError("boom: the scene could not be built")


class _Writes(Case):
    """A case that, while it runs, has another run store an entry for thesis-impact on disk."""
    name = "thesis-five-discs"
    title = "writes"
    source = "test"

    def __init__(self, outdir):
        self.outdir = outdir

    def run(self, p):
        import json

        f = self.outdir / "summary.json"
        d = json.loads(f.read_text())
        d["cases"]["thesis-impact"] = dict(d["cases"]["thesis-one-disc"], title="stored meanwhile")
        f.write_text(json.dumps(d))
        return CaseRun()

    def checks(self, run, p):
        return [Check("ok", 1.0, 1.0, 1e-3, "s", "w", kind="exact")]


def test_validate_keeps_going_past_a_broken_case_and_keeps_entries_stored_meanwhile(tmp_path):
    from demflow.report import run_validation

    out = tmp_path / "v"
    s = run_validation(["thesis-one-disc", "thesis-five-discs"], str(out),
                       cases={"thesis-one-disc": _Broken(), "thesis-five-discs": _Writes(out)})
    broken = s["cases"]["thesis-one-disc"]
    assert broken["passed"] is False and "boom" in broken["checks"][0]["why"]
    assert s["cases"]["thesis-five-discs"]["passed"] is True
    assert s["cases"]["thesis-impact"]["title"] == "stored meanwhile"
    assert "boom" in (out / "thesis-one-disc" / "index.html").read_text()


def test_validate_removes_a_figure_an_earlier_run_of_the_case_left(tmp_path):
    """A case's folder holds what its page shows: a file left by an earlier run that this run neither wrote
    nor lists is deleted; the figures this run wrote stay."""
    from demflow.report import run_validation

    out = tmp_path / "v"
    first = run_validation(["ch3-impulse-chain"], str(out))["cases"]["ch3-impulse-chain"]["figures"]
    assert first, "the case writes figures"
    stale = out / "ch3-impulse-chain" / "figure_of_an_old_version.png"
    stale.write_bytes(b"old")
    again = run_validation(["ch3-impulse-chain"], str(out))["cases"]["ch3-impulse-chain"]["figures"]
    assert not stale.exists()
    assert all((out / "ch3-impulse-chain" / f).exists() for f in again)
    assert (out / "ch3-impulse-chain" / "index.html").exists()


def test_a_page_kept_from_other_code_is_marked(tmp_path):
    """A page kept from a run with other code (a slow case's, kept from its last run) is marked on the index, on its
    page and in summary.json; a page run with this code is not; the fingerprint follows what the sources run, not
    their comments, docstrings or layout."""
    import json as _json

    from demflow.report.validation import code_fingerprint, write_report

    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    before = code_fingerprint(str(pkg))
    (pkg / "sub" / "b.py").write_text('"""A docstring."""\n# a comment\ny  =  2   # another\n')
    assert code_fingerprint(str(pkg)) == before  # comments, docstrings and layout are not code
    (pkg / "sub" / "b.py").write_text("y = 3\n")
    assert code_fingerprint(str(pkg)) != before and len(before) == 12
    (pkg / "sub" / "b.py").write_text('y = 2\nprint("a message")\n')  # a string that is shown is code
    assert code_fingerprint(str(pkg)) != before
    assert code_fingerprint() == code_fingerprint()

    def entry(code):
        e = dict(physics={}, run_at="2026-01-01 00:00:00", slow=True, title="t", source="s", params={}, wall_time_s=0.0,
                 passed=True, assumptions=[], figures=[], checks=[])
        if code is not None:
            e["code"] = code
        return e

    summary = dict(generated="now", python="3", machine="x", cases={
        "thesis-impact": entry(code_fingerprint()), "cs-nine-disc": entry("0123456789ab"), "thesis-one-disc": entry(None)})
    out = tmp_path / "report"
    write_report(summary, out)
    stored = _json.loads((out / "summary.json").read_text())
    assert stored["code"] == code_fingerprint()
    assert sorted(stored["pages_not_run_with_this_code"]) == ["cs-nine-disc", "thesis-one-disc"]
    index = (out / "index.html").read_text()
    assert "2 of 3 pages were not run with this code" in index
    assert "run with other code (0123456789ab" in (out / "cs-nine-disc" / "index.html").read_text()
    assert "code unknown" in (out / "thesis-one-disc" / "index.html").read_text()
    assert "not this code" not in (out / "thesis-impact" / "index.html").read_text()


@pytest.mark.parametrize("given,expected", [("n_steps=1e3", ("n_steps", 1000)), ("dt=2e-3", ("dt", 0.002)),
                                            ("kn=1", ("kn", 1.0))])
def test_set_values_take_their_defaults_kind(given, expected):
    from demflow.cli import _parse_sets

    p = CASES["thesis-one-disc"].merged(_parse_sets([given]))
    assert p[expected[0]] == expected[1] and type(p[expected[0]]) is type(expected[1])


@pytest.mark.parametrize("case,given", [("thesis-one-disc", "n_steps=1.5"), ("thesis-one-disc", "n_steps=abc"),
                                        ("thesis-one-disc", "dt=True"), ("thesis-one-disc", "dt=[1,2]"),
                                        ("thesis-bem-free-rectangle", "refine=1"),
                                        ("thesis-bem-free-rectangle", "refine=maybe")])
def test_a_set_value_of_another_kind_is_refused_not_converted(case, given):
    """--set n_steps=1.5 ran 1 step, refine=false ran refine=True (bool('false')), n_steps=abc gave a traceback."""
    from demflow.cases.base import ParameterError
    from demflow.cli import _parse_sets

    key = given.split("=")[0]
    with pytest.raises(ParameterError, match=f"parameter {key}=.* is not a"):
        CASES[case].merged(_parse_sets([given]))


def test_flag_words_and_comma_lists_read_as_meant():
    from demflow.cli import _parse_sets

    assert CASES["thesis-bem-free-rectangle"].merged(_parse_sets(["refine=false"]))["refine"] is False
    assert CASES["thesis-bem-free-rectangle"].merged(_parse_sets(["refine=Off"]))["refine"] is False
    assert CASES["miyata-uniaxial-3d-ksweep"].merged(_parse_sets(["Ks=1,3,5"]))["Ks"] == "1,3,5"


@pytest.mark.parametrize("argv,words", [
    (["run", "thesis-one-disc", "--set", "n_steps=abc"], "is not a whole number"),
    (["run", "thesis-one-disc", "--set", "n_steps=1"], "do not reach t = 5 s"),
    (["run", "thesis-one-disc", "--set", "dt=-1"], "scene.dt=-1.0 breaks the rule dt > 0"),
    (["sweep", "thesis-one-disc", "--set", "bogus=1,2", "--scheduler", "serial"], "has no parameter 'bogus'"),
    (["tradeoff", "thesis-impact", "--knob", "dt=abc"], "is not a number"),
])
def test_cli_refuses_a_bad_parameter_in_one_line(argv, words, capsys, tmp_path):
    from demflow.cli import main

    assert main(argv + (["--out", str(tmp_path / "o")] if argv[0] == "run" else [])) == 2
    err = capsys.readouterr().err
    assert err.startswith("demflow: ") and words in err and "Traceback" not in err


def test_a_mesh_index_out_of_range_is_named_where_it_is():
    """The message named the largest index (valid) when the bad one was -1."""
    import demflow as df

    mesh = df.TriangleMesh("m", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[-1, 1, 2]], "g")
    scene = df.Scene3D(name="mesh-index", spheres=df.Spheres(x=[0.2], y=[0.2], z=[0.5], radius=[0.05], material="g"),
                       materials={"g": df.Material(density=2800.0, young=7e9, poisson=0.2)},
                       laws={("g", "g"): df.HertzMindlinLaw(friction=0.3)}, meshes=[mesh])
    with pytest.raises(df.SceneError, match=r"scene.meshes\[0\].triangles\[0, 0\]=-1 is not a vertex index"):
        df.build(scene)


def test_cli_run_says_when_a_case_keeps_no_tables_and_refuses_parameters_without_engine_runs(capsys, tmp_path):
    """ch3-impulse-chain keeps no result tables: run printed 'tables in OUT/<variant>/*.parquet' and ignored --vtk;
    conformance-3d with another dt_fraction raised a ValueError traceback (its stored engine runs use 0.1)."""
    from demflow.cli import main

    main(["run", "ch3-impulse-chain", "--out", str(tmp_path / "c"), "--vtk"])
    out = capsys.readouterr().out
    assert "no tables: case 'ch3-impulse-chain' keeps none" in out and "no VTK either" in out
    assert "tables in" not in out
    assert main(["run", "conformance-3d", "--out", str(tmp_path / "k"), "--set", "dt_fraction=0.05"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("demflow: case 'conformance-3d' compares demflow with engine runs stored with")


def test_validate_takes_the_code_fingerprint_before_any_case_runs(tmp_path):
    """The pages' code is the code the process runs: it is taken when validate starts, not when a case ends (taken
    at the end, a source edited while a long case ran would have been stamped on its page)."""
    from demflow.report import run_validation
    from demflow.report import validation

    seen = {}

    class _Probe(_Broken):
        def run(self, p):
            seen["cached"] = validation._package_fingerprint.cache_info().currsize
            raise RuntimeError("probe")

    validation._package_fingerprint.cache_clear()
    run_validation(["thesis-one-disc"], str(tmp_path / "v"), cases={"thesis-one-disc": _Probe()})
    assert seen["cached"] == 1
