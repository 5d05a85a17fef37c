"""Fuzz the engine output readers with corrupted files (issue 19).

    python benchmarks/fuzz_readers.py [--n 1000] [--seed 19] [--out benchmarks/results/fuzz_readers.json]
                                      [--code DIR] [--regenerate]

For each reader (LIGGGHTS: log, fix-print table, pair and wall contact dumps, particle dump; YADE:
its JSON output) ``--n`` directories are made from the real engines' outputs in
tests/fixtures/engine_outputs/ with one file corrupted (tests/reader_faults.py: truncated,
lines reordered, swapped, deleted or duplicated, random bytes overwritten or inserted, a number
replaced by NaN, inf, a huge, negative or non-numeric value, the file emptied or replaced by random
bytes, a JSON value replaced by another type or removed), seeded so a run is reproducible.  Each is
read with ``engine.read``: ``refused`` (EngineOutputError), ``accepted`` (tables returned: the
corruption left a well-formed output, e.g. a changed digit), ``other`` (any other exception, the
failure this guards against).  Every 50th case also goes through ``reference.generate`` with an
engine that replays the corrupted files, into a scratch reference directory, which must stay empty;
the repository's reference_runs/ is fingerprinted before and after and must be unchanged.

``--regenerate`` reruns YADE and LIGGGHTS to rewrite the fixtures (both engines needed).
Results: JSON with counts per reader, file and corruption kind, rendered by the report's
robustness page (demflow/report/robustness.py).
"""
from __future__ import annotations

import platform
import random
import shutil
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from fuzz_scenes import parse_args, write_json  # noqa: E402  (the fuzz scripts' common options and output)


def fuzz(engine: str, n: int, seed: int, sim, scratch: Path, generate_every: int = 50):
    """Run ``n`` corrupted outputs through ``engine``'s reader; returns the counts and the failures."""
    import reader_faults as rf
    from demflow.engines import EngineOutputError
    from demflow.engines import reference

    rng = random.Random(f"{engine}-{seed}")
    outcomes, per_file, per_kind = Counter(), defaultdict(Counter), defaultdict(Counter)
    failures, generated, leaked, examples = [], 0, [], {}
    for i in range(n):
        d = scratch / f"{engine}-{i}"
        name, kind = rf.corrupted_dir(engine, d, rng)
        try:
            rf.read(engine, sim, d)
            outcome = "accepted"
        except EngineOutputError as e:
            outcome = "refused"
            examples.setdefault(name, dict(kind=kind, message=str(e)[:300]))
        except Exception as e:  # noqa: BLE001 - any other exception is the failure counted here
            outcome = "other"
            failures.append(dict(i=i, file=name, kind=kind, error=f"{type(e).__name__}: {e}"[:300]))
        outcomes[outcome] += 1
        per_file[name][outcome] += 1
        per_kind[kind][outcome] += 1
        if outcome == "refused" and i % generate_every == 0:
            base = scratch / f"refs-{engine}-{i}"
            try:
                reference.generate("reader-fixture", "fuzz", rf.replay_engine(engine, d), sim.scene, base=base)
                leaked.append(dict(i=i, error="generate stored a reference from a refused output"))
            except EngineOutputError:
                pass
            left = [str(p.relative_to(base)) for p in base.rglob("*") if p.is_file()] if base.exists() else []
            if left:
                leaked.append(dict(i=i, files=left))
            generated += 1
        shutil.rmtree(d, ignore_errors=True)
    return dict(n=n, outcomes=dict(outcomes), files={k: dict(v) for k, v in sorted(per_file.items())},
                kinds={k: dict(v) for k, v in sorted(per_kind.items())}, examples=dict(sorted(examples.items())),
                failures=failures,
                through_generate=generated, written_by_generate=leaked)


def main(argv=None):
    args = parse_args(argv, __doc__, 1000, "fuzz_readers.json",
                      extra=[("--regenerate", "rerun the engines to rewrite the fixtures")])
    import reader_faults as rf
    from demflow import build

    if args.regenerate:
        rf.regenerate()
    refs = ROOT / "reference_runs"
    before = rf.fingerprint(refs)
    sim = build(rf.fixture_scene())
    t0 = time.perf_counter()
    readers = {}
    with tempfile.TemporaryDirectory() as tmp:
        for engine in rf.FILES:
            readers[engine] = fuzz(engine, args.n, args.seed, sim, Path(tmp))
    wall = time.perf_counter() - t0
    unchanged = rf.fingerprint(refs) == before
    import demflow

    out = dict(kind="readers", generated=time.strftime("%Y-%m-%d %H:%M:%S"), python=platform.python_version(),
               code=str(Path(demflow.__file__).resolve().parents[1]), n_per_reader=args.n, seed=args.seed,
               wall_time_s=round(wall, 2), reference_runs_unchanged=unchanged, readers=readers,
               files={e: list(f) for e, f in rf.FILES.items()})
    path = write_json(args.out, out)
    ok = unchanged
    for engine, r in readers.items():
        print(f"{engine}: {r['n']} corrupted outputs in {wall:.0f} s: "
              + ", ".join(f"{k} {v}" for k, v in sorted(r["outcomes"].items()))
              + f"; {r['through_generate']} also through reference.generate, "
              f"{len(r['written_by_generate'])} wrote anything")
        for fail in r["failures"][:10]:
            print(f"   other: {fail}")
        ok = ok and not r["failures"] and not r["written_by_generate"]
    print(f"reference_runs/ unchanged: {unchanged}; written {path}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
