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


def main(argv=None):
    from .cases import CASES, comparison_cases, get_case, reference_cases

    ap = argparse.ArgumentParser(prog="demflow", description="2D DEM after Cundall & Strack and Tan (1990)")
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("cases", help="list the registered cases")
    r = sub.add_parser("run", help="run one case and save its tables")
    r.add_argument("case")
    r.add_argument("--out", default=None, help="output directory (default runs/CASE)")
    r.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a case parameter")
    v = sub.add_parser("validate", help="run every validation case and write the report")
    v.add_argument("--out", default="reports/validation")
    v.add_argument("--case", action="append", help="only these cases")
    v.add_argument("--all", action="store_true", help="include the slow cases (minutes of BEM each)")
    rf = sub.add_parser("reference", help="run a real engine and store its reference run (reference_runs/)")
    rf.add_argument("case", choices=list(reference_cases()))
    rf.add_argument("--engine", required=True, choices=["yade", "liggghts"])
    rf.add_argument("--variant", action="append", help="only these variants (default: all the engine can express)")
    rf.add_argument("--timeout", type=float, default=600.0)
    rf.add_argument("--seal", action="store_true", help="do not run the engine: add meta.sha256 (the hash of meta.json) "
                                                        "to the stored references, after verifying their files")
    cp = sub.add_parser("compare", help="compare engines on a case and write its comparison page")
    cp.add_argument("case", choices=list(comparison_cases()))
    cp.add_argument("--engines", default="demflow,yade,liggghts")
    cp.add_argument("--live", action="store_true", help="run the engines now instead of using stored references")
    cp.add_argument("--out", default="reports/validation")
    args = ap.parse_args(argv)

    if args.cmd == "cases":
        for name, c in CASES.items():
            print(f"{name:24s} {c.title}  [{c.source}]")
            print(f"{'':24s} parameters: {json.dumps(c.params)}")
        return 0
    if args.cmd == "run":
        try:
            case = get_case(args.case)
            p = case.merged(_parse_sets(args.set))
        except KeyError as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        import matplotlib

        matplotlib.use("Agg")
        out = Path(args.out or f"runs/{args.case}")
        run = case.run(p)
        for variant, res in run.results.items():
            res.meta["case"], res.meta["variant"], res.meta["params"] = args.case, variant, p
            res.save(out / variant)
        checks = case.checks(run, p)
        figs = case.figures(run, p, str(out))
        for c in checks:
            mark = "info" if c.informative else "ok  " if c.passed else "FAIL"
            print(f"[{mark}] {c.name}: {c.value:.6g} (reference {c.reference:.6g}, error {c.error:.3g}, tol {c.tolerance:.3g})")
        print(f"tables in {out}/<variant>/*.parquet; figures: {', '.join(figs)}")
        return 0 if all(c.passed for c in checks) else 1
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
        for v in variants:
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
