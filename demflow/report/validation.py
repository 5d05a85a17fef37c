"""`demflow validate`: run every registered case, check it, write reports/validation/.

Pages are plain HTML with PNG figures (matplotlib, Agg); the machine-readable summary is
``summary.json``.  Every file is written atomically.
"""
from __future__ import annotations

import ast
import functools
import hashlib
import html
import json
import math
import platform
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from .. import progress
from ..manifest import describe
from ..cases import CASES  # noqa: E402
from ..cases.base import INFO, MISS, counted, kind_counts, kind_of, validation_passes  # noqa: E402
from ..atomic import write_text_atomic

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".svg", ".gif")  # a case's other outputs (e.g. .vtu) are linked, not shown


def check_counts(checks) -> str:
    """"n/m checks pass[, c/d calibrations][, k informative]" for a case's checks (Check objects or
    summary dicts): n/m counts the validation checks only (source, exact, cross-code,
    self-consistency); calibrations and informative lines are counted apart."""
    n, m = validation_passes(checks)
    counts = kind_counts(checks)
    text = f"{n}/{m} checks pass"
    if "calibration" in counts:
        text += f", {counts['calibration']['passed']}/{counts['calibration']['total']} calibrations"
    if "unclassified" in counts:
        text += f", {counts['unclassified']['passed']}/{counts['unclassified']['total']} unclassified"
    if MISS in counts:
        text += f", {counts[MISS]['total']} source figures not reproduced"
    if INFO in counts:
        text += f", {counts[INFO]['total']} informative"
    return text


def _kind_cell(checks) -> str:
    """Passes per kind, e.g. "source 3/3 · exact 2/2 · info 4"."""
    return " · ".join(f"{k} {v['total']}" if k in (INFO, MISS) else f"{k} {v['passed']}/{v['total']}"
                      for k, v in kind_counts(checks).items())


class _DropDocstrings(ast.NodeTransformer):
    """Remove statements that are a bare string (docstrings, and string comments): they never run."""

    def visit_Expr(self, node):
        if isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            return None
        return node


def source_digest(text: str) -> bytes:
    """What of a Python source can change a result: its syntax tree without comments, docstrings, line numbers or
    layout (``ast.dump``).  A string a page shows (a check's message) is an expression, not a bare statement, so
    it stays in."""
    return ast.dump(_DropDocstrings().visit(ast.parse(text))).encode()


def code_fingerprint(root: str | None = None) -> str:
    """The code a case page was run with: the first 12 hex digits of the sha256 of every Python source of the
    demflow package (its path and :func:`source_digest`, in path order; ``root`` the package folder, default
    this one).  Comments, docstrings and layout are left out, so editing them does not mark a kept page as
    other code; any change of what runs does.  ``ast.dump`` may differ between Python minor versions: a report
    written under another Python shows its kept pages as other code.  An installed copy of a commit and its
    working tree give the same fingerprint.  The report marks a page kept from a run with other code (a slow
    case's page is kept from its last run): its numbers are not this code's until it is run again."""
    if root is None:
        return _package_fingerprint()
    base = Path(root)
    h = hashlib.sha256()
    for f in sorted(base.rglob("*.py"), key=lambda q: q.relative_to(base).as_posix()):
        if "__pycache__" in f.parts:
            continue
        h.update(f.relative_to(base).as_posix().encode() + b"\0")
        h.update(source_digest(f.read_text(encoding="utf-8")) + b"\0")
    return h.hexdigest()[:12]


@functools.lru_cache(maxsize=None)
def _package_fingerprint() -> str:
    """This package's fingerprint, computed once per process (the code that process runs)."""
    return code_fingerprint(str(Path(__file__).resolve().parents[1]))


def other_code(entry: dict, current: str) -> str:
    """Why a summary entry's page is not this code's result ('' when it was run with ``current``)."""
    made = entry.get("code")
    if made == current:
        return ""
    if made is None:
        return ("run before pages recorded their code (code unknown): its numbers may not be this code's; "
                "re-run it to refresh")
    return f"run with other code ({made}; this report's is {current}): its numbers may not be this code's; re-run it"


def _strict(obj):
    """``obj`` with every non-finite float (an informative line's tolerance ∞, a failed condition's
    error ∞, a NaN) written as null, so that summary.json is strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    return obj


def run_validation(names=None, outdir="reports/validation", overrides=None, cases=None, include_slow=False):
    """Run the named cases (by default every case not marked ``slow``, or all with
    ``include_slow``); return the summary dict after writing the report.

    ``cases`` may supply configured case objects by name (``demflow compare``).  An existing
    summary in ``outdir`` is kept for the cases not run now, so one page can be refreshed alone.
    """
    outdir = Path(outdir)
    code_fingerprint()  # taken now, before any case runs: a source edited during the run does not become the pages' code
    names = list(names or [n for n, c in CASES.items() if include_slow or not c.slow])
    cases = dict(CASES, **(cases or {}))
    summary = dict(generated=time.strftime("%Y-%m-%d %H:%M:%S"), python=platform.python_version(),
                   machine=platform.machine(), cases={})
    done = {}
    for name in progress.iterate(names, "validate", "case"):
        case = cases[name]
        p = case.merged((overrides or {}).get(name))
        try:
            done[name] = _run_case(case, p, outdir / name)
        except Exception as e:  # one case that cannot run is a failed entry, not a lost report
            done[name] = _failed_entry(case, p, e)
        # the cases not run now keep the entry the summary on disk has at this moment (another run may
        # have refreshed some), and the report is written after every case: nothing done is lost
        summary["cases"] = {k: v for k, v in _stored_cases(outdir).items() if k in CASES and k not in done}
        summary["cases"].update(done)
        write_report(summary, outdir)
    return summary


def _stored_cases(outdir: Path) -> dict:
    if (outdir / "summary.json").exists():
        try:
            return json.loads((outdir / "summary.json").read_text()).get("cases", {})
        except json.JSONDecodeError:
            return {}
    return {}


def _run_case(case, p, casedir: Path) -> dict:
    """Run one case and return its summary entry (figures written to ``casedir``)."""
    t0 = time.perf_counter()
    run = case.run(p)
    wall = time.perf_counter() - t0
    checks = case.checks(run, p)
    casedir.mkdir(parents=True, exist_ok=True)
    before = {f.name: f.stat().st_mtime_ns for f in casedir.iterdir() if f.is_file()}
    figs = [Path(f).name for f in case.figures(run, p, str(casedir))]
    _remove_stale(casedir, before, keep={"index.html", *figs})
    tables = [dict(title=t, html=df.to_html(float_format=lambda v: f"{v:.4g}", border=0))
              for t, df in case.tables(run, p)]
    physics = {v: describe(r.meta["physics"]) for v, r in run.results.items()
               if isinstance(getattr(r, "meta", None), dict) and r.meta.get("physics")}
    return dict(physics=physics, code=code_fingerprint(),
                run_at=time.strftime("%Y-%m-%d %H:%M:%S"), slow=bool(case.slow), title=case.title, source=case.source,
                params=p, wall_time_s=round(wall, 3), tables=tables,
                passed=all(c.passed for c in counted(checks)), assumptions=list(case.assumptions), figures=figs,
                counts=kind_counts(checks),
                checks=[dict(name=c.name, value=c.value, reference=c.reference, error=c.error,
                             tolerance=c.tolerance, passed=c.passed, source=c.source, why=c.why,
                             relative=c.relative, kind=c.kind) for c in checks])


def _remove_stale(casedir: Path, before: dict, keep: set) -> None:
    """Delete the files an earlier run of the case left in ``casedir`` that this run neither wrote nor
    lists (a figure the page no longer has), so the folder holds what the page shows."""
    for f in casedir.iterdir():
        if f.is_file() and f.name not in keep and before.get(f.name) == f.stat().st_mtime_ns:
            f.unlink()


def _failed_entry(case, p, err: Exception) -> dict:
    """The entry of a case whose run raised: one failed check that names the error."""
    why = f"{type(err).__name__}: {err}"
    check = dict(name="the case runs to completion", value=0.0, reference=1.0, error=1.0, tolerance=0.0,
                 passed=False, source=case.source, why=why[:2000], relative=False, kind="self-consistency")
    return dict(physics={}, code=code_fingerprint(), run_at=time.strftime("%Y-%m-%d %H:%M:%S"), slow=bool(case.slow),
                title=case.title,
                source=case.source, params=p, wall_time_s=0.0, tables=[], passed=False,
                assumptions=list(case.assumptions), figures=[], counts=kind_counts([check]), checks=[check])


def _fmt(v):
    if v is None:  # a non-finite value in a strict-JSON summary
        return "—"
    if isinstance(v, float):
        if math.isinf(v):
            return "—"
        return f"{v:.6g}"
    return html.escape(str(v))


CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;text-align:left}
.pass{color:#070;font-weight:bold}.fail{color:#b00;font-weight:bold}img{max-width:100%;border:1px solid #eee}
.small{font-size:12px;color:#555}"""


def _not_run(summary):
    missing = [n for n, c in CASES.items() if c.slow and n not in summary["cases"]]
    if not missing:
        return ""
    return ("<p>Slow cases not on this report yet (run <code>demflow validate --case NAME</code> or "
            f"<code>demflow validate --all</code>): {html.escape(', '.join(missing))}</p>")


def _mark(ch):
    """(CSS class, text) of a check's verdict cell."""
    if kind_of(ch) == INFO:
        return "small", "info"
    if kind_of(ch) == MISS:
        return "fail", "MISS"
    return ("pass", "pass") if ch["passed"] else ("fail", "FAIL")


def write_report(summary, outdir="reports/validation"):
    outdir = Path(outdir)
    current = code_fingerprint()
    summary["code"] = current
    rows = []
    stale = []
    for name, c in sorted(summary["cases"].items(), key=lambda kv: list(CASES).index(kv[0])):
        other = other_code(c, current)
        if other:
            stale.append(name)
        rows.append(f"<tr><td><a href='{name}/index.html'>{name}</a></td><td>{html.escape(c['title'])}</td>"
                    f"<td>{html.escape(c['source'])}</td><td>{check_counts(c['checks'])}</td>"
                    f"<td class='small'>{html.escape(_kind_cell(c['checks']))}</td>"
                    f"<td class='{'pass' if c['passed'] else 'fail'}'>{'PASS' if c['passed'] else 'FAIL'}</td>"
                    f"<td>{c['wall_time_s']}</td><td class='small'>{c.get('run_at', summary['generated'])}"
                    f"{' (slow: runs with --all or --case; otherwise kept from its last run)' if c.get('slow') else ''}"
                    f"{f' <span class=fail>{html.escape(other)}</span>' if other else ''}</td></tr>")
        checks = "".join(
            f"<tr><td>{html.escape(ch['name'])}</td><td>{_fmt(ch['value'])}</td><td>{_fmt(ch['reference'])}</td>"
            f"<td>{_fmt(ch['error'])}</td><td>{_fmt(ch['tolerance'])}</td>"
            f"<td class='{_mark(ch)[0]}'>{_mark(ch)[1]}</td>"
            f"<td class='small'>{html.escape(kind_of(ch))}</td>"
            f"<td class='small'>{html.escape(ch['source'])}</td><td class='small'>{html.escape(ch['why'])}</td></tr>"
            for ch in c["checks"])
        assumptions = "".join(f"<li>{html.escape(a)}</li>" for a in c["assumptions"])
        extra = "".join(f"<h2>{html.escape(title)}</h2>{body}"
                        for title, body in (CASES[name].page_sections() if name in CASES else []))
        for t in c.get("tables", []):  # pandas' to_html escapes the cells
            extra += f"<h2>{html.escape(t['title'])}</h2>{t['html']}"
        figs = "".join(f"<p><img src='{html.escape(f)}'></p>" if f.lower().endswith(IMAGE_SUFFIXES) else
                       f"<p class='small'>data file for other tools: <a href='{html.escape(f)}'>{html.escape(f)}</a></p>"
                       for f in c["figures"])
        if c.get("physics"):
            extra += ("<h2>What was built (physics manifest, meta.json 'physics')</h2><table><tr><th>variant</th>"
                      "<th>kernels, history, fluid, damping, state</th></tr>" + "".join(
                          f"<tr><td>{html.escape(v)}</td><td class='small'>{html.escape(d)}</td></tr>"
                          for v, d in c["physics"].items()) + "</table>")
        params = html.escape(json.dumps(c["params"]))
        page = (f"<!doctype html><html><head><meta charset='utf-8'><title>{name}</title><style>{CSS}</style></head>"
                f"<body><p><a href='../index.html'>← all cases</a></p><h1>{html.escape(c['title'])}</h1>"
                f"<p>Case <code>{name}</code>, source: {html.escape(c['source'])}. Parameters: <code>{params}</code>. "
                f"Wall time {c['wall_time_s']} s, run at {html.escape(str(c.get('run_at', '')))}, code "
                f"{html.escape(str(c.get('code', 'unknown')))}. Run it: <code>demflow run {name}</code>.</p>"
                f"{f'<p class=fail>This page was {html.escape(other)} (demflow validate --case {name}).</p>' if other else ''}"
                f"<h2>Assumptions (what the sources leave open)</h2><ul>{assumptions}</ul>"
                f"<h2>Checks</h2><p class='small'>error is relative unless the reference is 0; the tolerance and why "
                f"come from <code>demflow/tolerances.py</code>; 'info' marks an informative row (tolerance '—'), "
                f"never counted as a pass or a failure: {check_counts(c['checks'])}.</p>"
                f"<table><tr><th>check</th><th>demflow</th><th>reference</th><th>error</th><th>tolerance</th>"
                f"<th></th><th>kind</th><th>source</th><th>why this tolerance</th></tr>{checks}</table>{extra}"
                f"<h2>Figures</h2>{figs}"
                f"</body></html>")
        write_text_atomic(outdir / name / "index.html", page)
    from .robustness import PAGE, render, results_dir, summary_line

    robustness = render(results_dir())  # the fuzz scripts' last run (issue 19), if there is one
    if robustness:
        write_text_atomic(outdir / PAGE, robustness)
    from . import source_figures

    summary["source_figures"] = dict(counts=source_figures.counts(summary), rows=source_figures.rows(summary))
    write_text_atomic(outdir / "sources.html",
                      f"<!doctype html><html><head><meta charset='utf-8'><title>demflow: source figures</title>"
                      f"<style>{CSS}</style></head><body><p><a href='index.html'>← all cases</a></p>"
                      f"<h1>The sources' figures: reproduced or not</h1>{source_figures.render(summary)}</body></html>")
    write_text_atomic(outdir / "source_figures.md", source_figures.markdown(summary) + "\n")
    sf = " · ".join(f"{k} {v}" for k, v in sorted(summary["source_figures"]["counts"].items()))
    all_ok = all(c["passed"] for c in summary["cases"].values())
    every = [ch for c in summary["cases"].values() for ch in c["checks"]]
    summary["counts"] = kind_counts(every)
    n_val, m_val = validation_passes(every)
    summary["validation"] = {"passed": n_val, "total": m_val}
    summary["pages_not_run_with_this_code"] = stale
    index = (f"<!doctype html><html><head><meta charset='utf-8'><title>demflow validation</title><style>{CSS}</style>"
             f"</head><body><h1>demflow validation report</h1><p>Generated {summary['generated']} "
             f"(Python {summary['python']}, {summary['machine']}). Overall: "
             f"<span class='{'pass' if all_ok else 'fail'}'>{'PASS' if all_ok else 'FAIL'}</span></p>"
             f"<p>Validation checks passed: {n_val}/{m_val} (source figures, exact solutions, other codes, "
             f"self-consistency); per kind: {html.escape(_kind_cell(every))}. Calibrations (a lost parameter fitted "
             f"to the very figure checked), known misses (a source figure not reproduced, with its measured cause) "
             f"and informative lines are never counted as validation.</p>"
             f"<p>Source figures (<a href='sources.html'>table</a>): {html.escape(sf)}.</p>"
             f"<p>Code {current} (sha256 of demflow's Python sources). "
             + (f"<span class='fail'>{len(stale)} of {len(summary['cases'])} pages were not run with this code</span> "
                f"(kept from earlier runs, marked below; their checks are counted above as they were run): "
                f"{html.escape(', '.join(stale))}.</p>" if stale else "Every page was run with this code.</p>") +
             f"<table><tr><th>case</th><th>what</th><th>source</th><th>checks passed</th><th>per kind</th><th></th>"
             f"<th>wall time [s]</th>"
             f"<th>run at</th></tr>{''.join(rows)}</table>{_not_run(summary)}"
             f"{summary_line(results_dir()) if robustness else ''}</body></html>")
    write_text_atomic(outdir / "index.html", index)
    write_text_atomic(outdir / "summary.json", json.dumps(_strict(summary), indent=2, default=str, allow_nan=False))
