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


def _reference_plan(case: str):
    """(stored case name, parameters, variants(engine), scene(variant, p)) of a case with engine references."""
    if case == "cs-nine-disc":
        from .cases.cs_nine_disc import NineDisc
        from .cases.cs_nine_disc_engines import CASE, engine_scene, engine_variants

        return CASE, NineDisc().merged(), engine_variants, engine_scene
    from .cases.cs_photoelastic import Photoelastic, reference_scene, reference_variants

    return Photoelastic.name, Photoelastic().merged(), reference_variants, reference_scene


def _comparison_case(case: str):
    """A fresh case object whose engines and live flag the `compare` command sets."""
    if case == "cs-nine-disc":
        from .cases.cs_nine_disc_engines import NineDiscEngines

        return NineDiscEngines()
    from .cases.cs_photoelastic import Photoelastic

    return Photoelastic()


def main(argv=None):
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
    rf.add_argument("case", choices=["cs-nine-disc", "cs-photoelastic"])
    rf.add_argument("--engine", required=True, choices=["yade", "liggghts"])
    rf.add_argument("--variant", action="append", help="only these variants (default: all the engine can express)")
    rf.add_argument("--timeout", type=float, default=600.0)
    cp = sub.add_parser("compare", help="compare engines on a case and write its comparison page")
    cp.add_argument("case", choices=["cs-nine-disc", "cs-photoelastic"])
    cp.add_argument("--engines", default="demflow,yade,liggghts")
    cp.add_argument("--live", action="store_true", help="run the engines now instead of using stored references")
    cp.add_argument("--out", default="reports/validation")
    args = ap.parse_args(argv)

    from .cases import CASES, get_case

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
        results = case.run(p)
        from .results import Results

        for variant, res in results.items():
            if isinstance(res, Results):  # some cases return extra data beside their tables
                res.meta["case"], res.meta["variant"], res.meta["params"] = args.case, variant, p
                res.save(out / variant)
        checks = case.checks(results, p)
        figs = case.figures(results, p, str(out))
        for c in checks:
            mark = "ok " if c.passed else "FAIL"
            print(f"[{mark}] {c.name}: {c.value:.6g} (reference {c.reference:.6g}, error {c.error:.3g}, tol {c.tolerance:.3g})")
        print(f"tables in {out}/<variant>/*.parquet; figures: {', '.join(figs)}")
        return 0 if all(c.passed for c in checks) else 1
    if args.cmd == "reference":
        from .engines import EngineError, get_engine
        from .engines import reference

        store, p, engine_variants, engine_scene = _reference_plan(args.case)
        variants = args.variant or list(engine_variants(args.engine))
        bad = [v for v in variants if v not in engine_variants(args.engine)]
        if bad:
            print(f"demflow: {args.engine} cannot run variant(s) {bad}; it runs {list(engine_variants(args.engine))}",
                  file=sys.stderr)
            return 2
        engine = get_engine(args.engine)
        for v in variants:
            try:
                path = reference.generate(store, v, engine, engine_scene(v, p), params=p, timeout=args.timeout)
            except EngineError as e:
                print(f"demflow: {e}", file=sys.stderr)
                return 1
            print(f"stored {path}")
        return 0
    if args.cmd == "compare":
        from .report import run_validation

        engines = [e.strip() for e in args.engines.split(",") if e.strip() and e.strip() != "demflow"]
        case = _comparison_case(args.case)
        case.engines, case.live = tuple(engines), args.live
        summary = run_validation([case.name], args.out, cases={case.name: case})
        c = summary["cases"][case.name]
        print(f"{'PASS' if c['passed'] else 'FAIL'}  {case.name}: {sum(ch['passed'] for ch in c['checks'])}/"
              f"{len(c['checks'])} checks; page {Path(args.out) / case.name / 'index.html'}")
        return 0 if c["passed"] else 1
    if args.cmd == "validate":
        from .report import run_validation

        try:
            names = [get_case(n).name for n in args.case] if args.case else None
        except KeyError as e:
            print(f"demflow: {e.args[0]}", file=sys.stderr)
            return 2
        summary = run_validation(names, args.out, include_slow=args.all)
        for name, c in summary["cases"].items():
            n_ok = sum(ch["passed"] for ch in c["checks"])
            print(f"{'PASS' if c['passed'] else 'FAIL'}  {name:24s} {n_ok}/{len(c['checks'])} checks  {c['wall_time_s']} s")
        print(f"report: {Path(args.out) / 'index.html'}  summary: {Path(args.out) / 'summary.json'}")
        return 0 if all(c["passed"] for c in summary["cases"].values()) else 1
    return 2


if __name__ == "__main__":
    sys.exit(main())
