"""The `demflow` command: list cases, run one, validate all."""
from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path


def _parse_sets(items):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SystemExit(f"--set {item!r}: write key=value, e.g. --set dt=1e-4")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = ast.literal_eval(v)
        except (ValueError, SyntaxError):
            out[k.strip()] = v
    return out


def _write_vtk(res, outdir: Path) -> None:
    from .vtk import write_results_vtk

    if not hasattr(res, "particles"):
        print(f"no VTK for {outdir.parent.name}: a 3D trajectory has no snapshot tables to write; from Python, "
              "demflow.vtk.write_simulation3d_vtk(sim, dir) writes a 3D simulation's state", file=sys.stderr)
        return
    if res.particles.empty:
        print(f"no VTK for {outdir.parent.name}: the run kept no particle snapshots (add snapshot steps to the "
              "scene's outputs)", file=sys.stderr)
        return
    files = write_results_vtk(res, outdir)
    print(f"VTK: {outdir / 'run.pvd'} ({len(files) - 1} files)")


def build_parser() -> argparse.ArgumentParser:
    """The command line: every command and option with its help text (``demflow --help``)."""
    from .cases import comparison_cases, reference_cases

    fmt = argparse.RawDescriptionHelpFormatter
    ap = argparse.ArgumentParser(
        prog="demflow", formatter_class=fmt,
        description="Discrete element simulation of dry and saturated granular media (2D discs with a BEM "
                    "Stokes fluid, 3D Hertz-Mindlin spheres and clumps), validated against its sources and "
                    "against YADE and LIGGGHTS.",
        epilog="examples:\n"
               "  demflow cases                              list the cases and their parameters\n"
               "  demflow run cs-photoelastic --set n_seeds=2 --vtk\n"
               "  demflow validate                           the validation report (fast cases)\n"
               "  demflow validate --case cs-photoelastic    refresh one case's page\n"
               "  demflow reference cs-nine-disc --engine yade\n"
               "  demflow compare cs-photoelastic --engines demflow,liggghts\n"
               "Run 'demflow COMMAND --help' for a command's options.")
    ap.add_argument("--no-progress", action="store_true",
                    help="never show progress bars (by default a run longer than a few seconds shows one on a "
                         "terminal, never in a log or a pipe)")
    sub = ap.add_subparsers(dest="cmd", required=True, metavar="COMMAND")
    sub.add_parser("cases", help="list the registered cases, their sources and default parameters",
                   description="List every registered case: its name, what it reproduces, its source and its "
                               "default parameters (override them with 'demflow run CASE --set KEY=VALUE').")
    r = sub.add_parser("run", help="run one case, save its tables and figures, print its checks", formatter_class=fmt,
                       description="Run one case with its default parameters (or overrides), save each variant's "
                                   "result tables as parquet under OUT/VARIANT (load a 2D result with "
                                   "demflow.results.Results.load, a 3D trajectory (spheres.parquet) with "
                                   "demflow.engines.base3d.Trajectory3D.load; a case whose checks need no tables "
                                   "saves none and says so), draw its figures into OUT and print its checks. "
                                   "Exit status 0 when every counted check passes, 1 otherwise.")
    r.add_argument("case", help="the case name ('demflow cases' lists them)")
    r.add_argument("--out", default=None, help="output directory (default runs/CASE)")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a case parameter, e.g. --set dt=1e-4 (repeatable; the value must be of the "
                        "default's kind: a whole number, a number, a flag true/false, a text or a list)")
    r.add_argument("--vtk", action="store_true",
                   help="also write each variant's snapshots as VTK for ParaView (OUT/VARIANT/vtk/run.pvd: "
                        "particles as points with radius and velocity, contacts as lines with fn, fs)")
    v = sub.add_parser("validate", help="run the validation cases and write the HTML report",
                       description="Run every validation case (by default those not marked slow) and write the "
                                   "report: OUT/index.html, a page per case, and OUT/summary.json (strict JSON). "
                                   "Checks are classified (source figure, exact, cross-code, self-consistency, "
                                   "calibration, informative); only validation kinds count as passes. Cases not "
                                   "run now keep their previous entry. Exit status 0 when every case passes.")
    v.add_argument("--out", default="reports/validation", help="report directory (default reports/validation)")
    v.add_argument("--case", action="append", metavar="CASE", help="only this case (repeatable)")
    v.add_argument("--all", action="store_true", help="include the slow cases (minutes to hours each)")
    rf = sub.add_parser("reference", help="run a real engine (YADE or LIGGGHTS) and store its reference run",
                        description="Write a case's decks for a real engine, run it, read and check its output, and "
                                    "store the tables with provenance (deck, log, versions, hashes) under "
                                    "reference_runs/CASE/VARIANT/ENGINE/ (atomic: a failed run stores nothing). "
                                    "Needs the engine installed (scripts/install-engines.sh).")
    rf.add_argument("case", choices=list(reference_cases()), help="a case with engine reference runs")
    rf.add_argument("--engine", required=True, choices=["yade", "liggghts"], help="which engine to run")
    rf.add_argument("--variant", action="append", help="only these variants (default: all the engine can express)")
    rf.add_argument("--timeout", type=float, default=600.0, help="seconds one engine run may take (default 600)")
    rf.add_argument("--seal", action="store_true", help="do not run the engine: add meta.sha256 (the hash of meta.json) "
                                                        "to the stored references, after verifying their files")
    cp = sub.add_parser("compare", help="compare engines on a case and write its comparison page",
                        description="Compare demflow with the engines on a cross-code case (from the stored "
                                    "reference runs, or live with --live) and write the case's report page.")
    cp.add_argument("case", choices=list(comparison_cases()), help="a case with a cross-code comparison")
    cp.add_argument("--engines", default="demflow,yade,liggghts",
                    help="comma-separated engines to compare (default demflow,yade,liggghts)")
    cp.add_argument("--live", action="store_true", help="run the engines now instead of using stored references")
    cp.add_argument("--out", default="reports/validation", help="report directory (default reports/validation)")
    sw = sub.add_parser("sweep", help="run a case over a grid of parameters on Dask and gather one table",
                        formatter_class=fmt,
                        description="Run a case once per combination of the given parameter values (a seed "
                                    "ensemble, a parameter study) on a Dask cluster, and write one table with a row "
                                    "per run and check (value, reference, error, pass, kind, wall time). The "
                                    "table is the same on any scheduler.\n\nexample:\n"
                                    "  demflow sweep cs-nine-disc --set dt_fraction=0.06,0.08,0.1 --workers 2")
    sw.add_argument("case", help="the case name ('demflow cases' lists them)")
    sw.add_argument("--set", action="append", metavar="KEY=V1,V2,...", required=True,
                    help="a parameter and its values (repeatable: every combination is run)")
    sw.add_argument("--scheduler", default="local",
                    help="'local' (default: a local cluster of --workers processes), 'serial' (in this process), "
                         "or the address of an existing dask.distributed scheduler, e.g. tcp://10.0.0.5:8786")
    sw.add_argument("--workers", type=int, default=None, help="local cluster size (default: one per core)")
    sw.add_argument("--out", default=None, help="write the table here (.parquet or .csv; default: print it)")
    to = sub.add_parser("tradeoff", help="measure speed against accuracy for one knob at a time",
                        formatter_class=fmt,
                        description="Run a case at a reference setting, at a chaos floor (the reference with an "
                                    "irrelevant change) and once per value of each knob; write the knob table "
                                    "(error of the case's observables vs the reference, wall and simulation time, "
                                    "particle-steps/s of the time compared, "
                                    "Pareto front, recommended setting) and the error-vs-cost figure. Among the "
                                    "settings whose error is within --accept × the floor's, those whose cost is within "
                                    "the larger of two relative differences of the cheapest one's count as equally "
                                    "cheap, and the most accurate of them is recommended (none within: the most "
                                    "accurate); the differences are the reference run's against its repeat (the "
                                    "host's noise) and against the floor run (what an irrelevant change does to the "
                                    "cost).\n\nexample:\n"
                                    "  demflow tradeoff thesis-impact --knob dt=4e-5,2e-5,1e-5 --reference dt=1e-6 "
                                    "--floor kn=1.0001e7")
    to.add_argument("case", help="the case name ('demflow cases' lists them)")
    to.add_argument("--knob", action="append", required=True, metavar="NAME=V1,V2,...",
                    help="a case parameter and the values to try, one knob at a time (repeatable)")
    to.add_argument("--reference", action="append", default=[], metavar="NAME=VALUE",
                    help="overrides of the case's defaults for the reference run (repeatable)")
    to.add_argument("--floor", action="append", default=[], metavar="NAME=VALUE",
                    help="the chaos floor: overrides applied on top of the reference (e.g. a density × 1.0001)")
    to.add_argument("--accept", type=float, default=2.0,
                    help="the recommended setting's error may be this many times the floor's (default 2)")
    to.add_argument("--scheduler", default="serial",
                    help="'serial' (default; timings undisturbed), 'local' (a Dask local cluster) or a scheduler "
                         "address")
    to.add_argument("--out", default=None, help="directory for tradeoff.parquet, tradeoff.txt and tradeoff.png "
                                                "(default runs/tradeoff-CASE)")
    return ap


def _parse_grid(items):
    grid = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--set {item!r}: write key=v1,v2,..., e.g. --set seed=1,2,3")
        k, v = item.split("=", 1)
        grid[k.strip()] = [_parse_sets([f"x={x}"])["x"] for x in v.split(",") if x.strip()]
    return grid


def main(argv=None):
    from .cases import CASES, get_case
    from .cases.base import counted

    args = build_parser().parse_args(argv)
    if args.no_progress:
        from . import progress

        progress.enable(False)

    if args.cmd == "cases":
        for name, c in CASES.items():
            print(f"{name:24s} {c.title}  [{c.source}]")
            print(f"{'':24s} parameters: {json.dumps(c.params)}")
        return 0
    if args.cmd == "run":
        from .cases.base import ParameterError
        from .scene import SceneError

        try:
            case = get_case(args.case)
            p = case.merged(_parse_sets(args.set))
        except (KeyError, ParameterError) as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        import matplotlib

        matplotlib.use("Agg")
        out = Path(args.out or f"runs/{args.case}")
        out.mkdir(parents=True, exist_ok=True)  # (a case without result tables still draws its figures here)
        try:
            run = case.run(p)
        except (SceneError, ParameterError) as e:  # a parameter the case's scenes refuse (the message says why)
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        for variant, res in run.results.items():
            res.meta["case"], res.meta["variant"], res.meta["params"] = args.case, variant, p
            res.save(out / variant)
            if args.vtk:
                _write_vtk(res, out / variant / "vtk")
        checks = case.checks(run, p)
        figs = case.figures(run, p, str(out))
        for c in checks:
            mark = "MISS" if c.kind == "miss" else "info" if c.informative else "ok  " if c.passed else "FAIL"
            print(f"[{mark}] {c.name}: {c.value:.6g} (reference {c.reference:.6g}, error {c.error:.3g}, tol {c.tolerance:.3g})")
        if run.results:
            print(f"tables in {out}/<variant>/*.parquet; figures: {', '.join(figs)}")
        else:
            print(f"no tables: case {args.case!r} keeps none (its checks read its runs directly)"
                  + ("; no VTK either" if args.vtk else "") + f"; figures: {', '.join(figs)}")
        return 0 if all(c.passed for c in counted(checks)) else 1
    if args.cmd == "reference":
        from .engines import EngineError, get_engine
        from .engines import reference

        plan = get_case(args.case).reference_plan()
        if args.seal:
            stored = [v for v, engines in reference.available(plan.store).items() if args.engine in engines]
            for v in args.variant or stored:
                try:
                    done = reference.seal(reference.location(plan.store, v, args.engine))
                except EngineError as e:
                    print(f"demflow: {e}", file=sys.stderr)
                    return 1
                print(f"{'sealed' if done else 'already sealed'} {reference.location(plan.store, v, args.engine)}")
            return 0
        can = list(plan.variants(args.engine))
        variants = args.variant or can
        bad = [v for v in variants if v not in can]
        if bad:
            print(f"demflow: {args.engine} cannot run variant(s) {bad}; it runs {can}", file=sys.stderr)
            return 2
        from . import progress

        for v in progress.iterate(variants, f"reference {args.case} ({args.engine})", "variant"):
            engine = plan.engine(args.engine, v) if plan.engine else get_engine(args.engine)
            try:
                path = reference.generate(plan.store, v, engine, plan.scene(v, plan.params), params=plan.params,
                                          timeout=args.timeout)
            except EngineError as e:
                print(f"demflow: {e}", file=sys.stderr)
                return 1
            print(f"stored {path}")
        return 0
    if args.cmd == "compare":
        from .report import check_counts, run_validation

        engines = [e.strip() for e in args.engines.split(",") if e.strip() and e.strip() != "demflow"]
        case = get_case(args.case).comparison_case()
        case.engines, case.live = tuple(engines), args.live
        summary = run_validation([case.name], args.out, cases={case.name: case})
        c = summary["cases"][case.name]
        print(f"{'PASS' if c['passed'] else 'FAIL'}  {case.name}: {check_counts(c['checks'])}; "
              f"page {Path(args.out) / case.name / 'index.html'}")
        return 0 if c["passed"] else 1
    if args.cmd == "tradeoff":
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from .tradeoff import TradeoffStudy

        try:
            study = TradeoffStudy(args.case, _parse_grid(args.knob), reference=_parse_sets(args.reference),
                                  floor=_parse_sets(args.floor) or None, accept=args.accept, scheduler=args.scheduler)
        except (KeyError, ValueError) as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        study.compute()
        out = Path(args.out or f"runs/tradeoff-{args.case}")
        out.mkdir(parents=True, exist_ok=True)
        t = study.table
        t.to_parquet(out / "tradeoff.parquet.tmp", index=False)
        (out / "tradeoff.parquet.tmp").replace(out / "tradeoff.parquet")
        (out / "tradeoff.txt.tmp").write_text(t.to_string(index=False) + "\n")
        (out / "tradeoff.txt.tmp").replace(out / "tradeoff.txt")
        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        study.plot(ax)
        from .plotting import save_figure

        save_figure(fig, str(out / "tradeoff.png"))
        print(t.to_string(index=False))
        why, tie = study.reason()
        print(f"recommended: {study.recommended['run']} ({why}).{' ' + tie if tie else ''} Table and figure in {out}")
        return 0
    if args.cmd == "sweep":
        from .sweep import case_sweep

        grid = _parse_grid(args.set)
        try:
            case = get_case(args.case)
            for key, values in grid.items():  # every value of the grid, before any run
                for v in values:
                    case.merged({key: v})
        except (KeyError, ValueError) as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        table = case_sweep(args.case, grid, scheduler=args.scheduler, workers=args.workers)
        if args.out:
            out = Path(args.out)
            out.parent.mkdir(parents=True, exist_ok=True)
            tmp = out.with_name(out.name + ".tmp")
            (table.to_csv(tmp, index=False) if out.suffix == ".csv" else table.to_parquet(tmp, index=False))
            tmp.replace(out)
            print(f"{len(table)} rows in {out}")
        else:
            print(table.to_string(index=False))
        return 0
    if args.cmd == "validate":
        from .report import check_counts, run_validation

        try:
            names = [get_case(n).name for n in args.case] if args.case else None
        except KeyError as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        summary = run_validation(names, args.out, include_slow=args.all)
        for name, c in summary["cases"].items():
            print(f"{'PASS' if c['passed'] else 'FAIL'}  {name:24s} {check_counts(c['checks'])}  {c['wall_time_s']} s")
        print(f"report: {Path(args.out) / 'index.html'}  summary: {Path(args.out) / 'summary.json'}")
        return 0 if all(c["passed"] for c in summary["cases"].values()) else 1
    return 2


if __name__ == "__main__":
    sys.exit(main())
