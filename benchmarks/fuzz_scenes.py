"""Fuzz ``build`` with generated invalid scenes, one fault each (issue 19).

    python benchmarks/fuzz_scenes.py [--n 400] [--seed 19] [--out benchmarks/results/fuzz_scenes.json]
                                     [--code DIR] [--3d]

Each scene is a valid base scene (tests/scene_faults.py: dry with phases and a servo wall, periodic,
saturated) with exactly one field broken: a NaN, an infinity, a negative or zero value, a wrong type
(a bool, a string, None, a complex, a list), a non-whole count, a wrong array length or shape, a name
that is not an identifier (a trailing newline included), an undeclared reference, or an inconsistent
combination.  The fault kind is drawn uniformly from the catalogue, then its value, by a seeded
``random.Random``, so a run is reproducible.  ``build`` must refuse every one with a ``SceneError``
whose message names the broken field (its dotted path, e.g. ``scene.walls[2].servo.v_max``).

Outcomes: ``clear`` (SceneError naming the field), ``unnamed`` (SceneError not naming it),
``accepted`` (built without complaint), ``other`` (any other exception).  The JSON holds the
counts overall and per category, and every non-clear case with its message; the robustness page
of the report (demflow/report/robustness.py) renders it.  ``--code DIR`` imports demflow from DIR
(to measure another checkout with the same catalogue).  ``--3d`` draws from the 3D catalogue instead
(tests/scene_faults3d.py: spheres, planes, plates, meshes, clumps, ellipsoids, the Hertz-Mindlin law) and
writes ``fuzz_scenes3d.json`` by default.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import random
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def parse_args(argv, doc: str, n: int, out: str, extra=()):
    """The fuzz scripts' common options (--n, --seed, --out, --code, and ``extra`` (flag, help) switches);
    puts tests/ (the fault catalogues) and the checkout named by --code first on sys.path."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--n", type=int, default=n)
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / out))
    ap.add_argument("--code", default=str(ROOT), help="import demflow from this checkout")
    for flag, text in extra:
        ap.add_argument(flag, action="store_true", help=text)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT / "tests"))
    sys.path.insert(0, str(Path(args.code).resolve()))
    return args


def write_json(path: str | Path, obj) -> Path:
    """Write ``obj`` as JSON to ``path`` atomically (temporary file + rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        json.dump(obj, fh, indent=1, default=str)
    os.replace(tmp, path)
    return path


def main(argv=None):
    args = parse_args(argv, __doc__, 400, "fuzz_scenes.json", extra=[("--3d", "the 3D catalogue (scene_faults3d)")])
    import scene_faults as sf

    three_d = getattr(args, "3d")
    catalogue = sf.FAULTS
    if three_d:
        import scene_faults3d as sf3

        catalogue = sf3.FAULTS3D
        if Path(args.out) == ROOT / "benchmarks" / "results" / "fuzz_scenes.json":
            args.out = str(ROOT / "benchmarks" / "results" / "fuzz_scenes3d.json")
    rng = random.Random(args.seed)
    outcomes = Counter()
    per_cat = defaultdict(Counter)
    per_fault = defaultdict(Counter)
    bad = []
    examples = {}
    t0 = time.perf_counter()
    for i in range(args.n):
        f = rng.choice(catalogue)
        scene, path, value = f.make(rng.choice)
        kind, msg = sf.classify(scene, path)
        outcomes[kind] += 1
        per_cat[f.category][kind] += 1
        per_fault[f"{f.category}: {f.name}"][kind] += 1
        examples.setdefault(f"{f.category}: {f.name}", dict(path=path, value=repr(value)[:80], outcome=kind,
                                                             message=msg[:300]))
        if kind != "clear":
            bad.append(dict(i=i, category=f.category, fault=f.name, path=path, value=repr(value), outcome=kind,
                            message=msg[:400]))
    wall = time.perf_counter() - t0
    import demflow

    out = dict(kind="scenes3d" if three_d else "scenes", generated=time.strftime("%Y-%m-%d %H:%M:%S"),
               python=platform.python_version(),
               code=str(Path(demflow.__file__).resolve().parents[1]), n=args.n, seed=args.seed,
               wall_time_s=round(wall, 2), outcomes=dict(outcomes), clear_fraction=outcomes["clear"] / args.n,
               categories={c: dict(v) for c, v in sorted(per_cat.items())},
               faults={c: dict(v) for c, v in sorted(per_fault.items())},
               catalogue=[dict(category=f.category, fault=f.name) for f in catalogue],
               examples=dict(sorted(examples.items())), not_clear=bad)
    path = write_json(args.out, out)
    what = "3D scenes" if three_d else "scenes"
    print(f"{args.n} invalid {what} ({len(catalogue)} fault kinds, seed {args.seed}) in {wall:.1f} s: "
          + ", ".join(f"{k} {v} ({v / args.n:.1%})" for k, v in outcomes.most_common()))
    for c, v in sorted(per_cat.items()):
        print(f"  {c:16s} " + ", ".join(f"{k} {n}" for k, n in v.most_common()))
    print(f"written {path}")
    return 0 if outcomes["clear"] == args.n else 1


if __name__ == "__main__":
    sys.exit(main())
