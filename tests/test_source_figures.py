"""The source-figure table and the known misses (issue 18 items 1-2): every quantitative figure of the
sources is reproduced, shown as a miss with its measured cause, or waits for a named issue; a miss is
never counted as a pass.  Run on the committed report (reports/validation/summary.json, what
`demflow validate` wrote) and on hand-made summaries."""
import json
import math
import re
from pathlib import Path

import pytest

from demflow.cases.base import Check, counted, kind_counts, validation_passes
from demflow.report import source_figures as sf
from demflow.report.validation import check_counts, write_report

SUMMARY = Path(__file__).resolve().parents[1] / "reports" / "validation" / "summary.json"


def _summary():
    return json.loads(SUMMARY.read_text(), parse_constant=lambda c: 1 / 0)  # strict JSON (no Infinity, NaN)


def test_a_miss_is_neither_a_pass_nor_a_validation_check():
    m = Check.miss("x vs the source", 1.0, 2.0, "src", "measured cause")
    ok = Check("y", 1.0, 1.0, 0.1, "src", "why", kind="source")
    assert not m.passed and m.kind == "miss" and m.why.startswith("NOT REPRODUCED") and m.error == 0.5
    assert counted([m, ok]) == [ok]
    assert validation_passes([m, ok]) == (1, 1)
    assert kind_counts([m, ok])["miss"] == {"passed": 0, "total": 1}
    assert "1 source figures not reproduced" in check_counts([m, ok])


def test_the_report_lists_misses_apart_and_writes_the_sources_page(tmp_path):
    checks = [Check.miss("a figure", 1.0, 2.0, "src", "cause"), Check("b", 1.0, 1.0, 0.1, "src", "why", kind="source")]
    rows = [dict(name=c.name, value=c.value, reference=c.reference, error=c.error, tolerance=c.tolerance,
                 passed=c.passed, source=c.source, why=c.why, relative=c.relative, kind=c.kind) for c in checks]
    summary = dict(generated="now", python="3", machine="m", cases={"thesis-one-disc": dict(
        title="t", source="s", params={}, wall_time_s=0.0, passed=True, assumptions=[], figures=[], checks=rows)})
    write_report(summary, tmp_path)
    index = (tmp_path / "index.html").read_text()
    assert "Validation checks passed: 1/1" in index and "miss 1" in index and "sources.html" in index
    page = (tmp_path / "thesis-one-disc" / "index.html").read_text()
    assert "MISS" in page and "NOT REPRODUCED. cause" in page
    assert "Table 2.1" in (tmp_path / "sources.html").read_text()
    json.loads((tmp_path / "summary.json").read_text(), parse_constant=lambda c: 1 / 0)


def test_every_figure_of_the_committed_report_has_a_status_from_its_checks():
    s = _summary()
    for r in sf.rows(s):
        assert "defect" not in r["status"], r
        if r["status"].startswith(("reproduced", "not reproduced", "calibration", "shown")):
            assert r["checks"], r
    # the page and summary carry the same table
    assert s["source_figures"]["counts"] == sf.counts(s)


def test_every_source_miss_and_calibration_check_is_claimed_by_a_figure():
    s = _summary()
    claimed = {(case, ch["name"]) for fig in sf.FIGURES for case, ch in sf.matched(fig, s)[0]}
    for case, c in s["cases"].items():
        for ch in c["checks"]:
            if ch.get("kind") in ("source", "miss", "calibration"):
                assert (case, ch["name"]) in claimed, (case, ch["name"])


@pytest.mark.parametrize("case, pattern", [
    ("cs-nine-disc", r"peak Fn at C in distortion \(C&S Fig\. 9b ≈ 25\.6e8\)"),
    ("cs-photoelastic", r"stage B / stage A vertical wall force"),
    ("cs-photoelastic", r"F_H/F_V falls from stage A to stage B"),
    ("cs-photoelastic", r"servo, stage A: the assembly's F_H/F_V"),
    ("thesis-simple-shear", r"loose specimen void ratio"),
    ("thesis-simple-shear", r"dense specimen void ratio"),
    ("thesis-simple-shear", r"loose-dry: peak S/F_y"),
    ("thesis-simple-shear", r"dense-dry: peak S/F_y"),
])
def test_the_misses_named_in_issue_18_are_on_the_report_as_misses(case, pattern):
    s = _summary()
    hits = [ch for ch in s["cases"][case]["checks"] if re.search(pattern, ch["name"])]
    assert hits, f"{case}: no check matches {pattern!r}"
    for ch in hits:
        assert ch["kind"] == "miss" and ch["passed"] is False and ch["why"].startswith("NOT REPRODUCED")
        assert ch["value"] is not None and math.isfinite(ch["value"])  # a measured value, not a placeholder
    fig = next(f for f in sf.FIGURES if any(c == case and re.search(p, hits[0]["name"]) for c, p in f.checks))
    assert sf.status(fig, s) == "not reproduced"


def test_calibrations_are_labelled_so():
    s = _summary()
    st = {f.where: sf.status(f, s) for f in sf.FIGURES}
    assert st["§4.4.2"] == "calibration" and st["§4.4.3"] == "calibration"
    assert st["nine-disc, Fig. 6"] == "reproduced (with calibrations)"


def test_a_figure_without_its_case_is_said_to_wait_for_its_issue():
    fig = sf.Figure("Miyata", "x", "y", (("no-such-case", "."),), pending="issue 15: superquadrics")
    assert sf.status(fig, dict(cases={})) == "no case yet: issue 15: superquadrics"
    fig = sf.Figure("thesis", "x", "y", (("thesis-sedimentation", "."),))
    assert sf.status(fig, dict(cases={})).startswith("not run on this report")


def test_the_readme_carries_the_generated_table():
    import sys

    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root / "scripts"))
    import update_readme_tables as u

    readme = (root / "README.md").read_text()
    inside = readme[readme.index(u.BEGIN) + len(u.BEGIN):readme.index(u.END)].strip()
    assert inside == u.block(), "README's source-figure table is stale: run scripts/update_readme_tables.py"
    assert sf.markdown(_summary()).strip() == u.block(), "reports/validation/source_figures.md is stale"
