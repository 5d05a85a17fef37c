"""In-process A/B of the calculation cycle: this working tree's demflow against a base commit's, one process.

    python benchmarks/bench_ab_inprocess.py --base 0ee02e7 [--sizes 10000 100000] [--chunk 500] [--rounds 40]
    python benchmarks/bench_ab_inprocess.py --base 0ee02e7 --dim 3 [--sizes 10000 100000]   # the 3D sphere cycle

Why one process: on a shared (virtual) host the speed of the machine drifts by up to 2x within minutes, so two
processes timed one after the other compare the host's states more than the code (benchmarks/results/
engines_speed.md: spreads of 8-38 % between rounds).  Here the base commit's ``demflow`` package is copied
into a temporary directory under the name ``demflow_base`` and imported beside this tree's ``demflow``; both
build the same scene (bench_engines.py's relaxed, agitated, undamped packing under the overlap law, one
thread) and run it in alternating chunks of ``--chunk`` steps, the order swapped every round, so both see
the same host states.  With ``--dim 3`` the scene is bench_engines3d.py's, packing3d.py's dense FCC Hertz sphere
packing (``dense_fcc(n)``, one thread).  Reported per size: per-particle-step time of each (min, 10th percentile, median over
the rounds), the per-round ratio head/base (min, median, max) and the ratio of the minima, and whether the
two runs ended with the same bits (they must: the refactors this measures keep every result to the bit).
Results: benchmarks/results/<tag>.{json,md}.
"""
from __future__ import annotations

import argparse
import importlib
import io
import json
import os
import pickle
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "benchmarks"))


def _base_package(commit: str, where: Path) -> str:
    """Copy the base commit's demflow/ to where/demflow_base; returns the resolved commit."""
    sha = subprocess.run(["git", "rev-parse", commit], capture_output=True, text=True, cwd=HERE, check=True).stdout.strip()
    arch = subprocess.run(["git", "archive", sha, "demflow"], capture_output=True, cwd=HERE, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=arch, check=True)
    shutil.move(str(where / "demflow"), str(where / "demflow_base"))
    return sha


def _load_as(raw: bytes, package: str):
    """Unpickle a scene written with ``demflow`` classes as the classes of ``package``."""
    class Renamed(pickle.Unpickler):
        def find_class(self, module, name):
            if module == "demflow" or module.startswith("demflow."):
                module = package + module[len("demflow"):]
            return super().find_class(module, name)
    return Renamed(io.BytesIO(raw)).load()


def _state(sim, dim: int) -> tuple:
    if dim == 3:
        sp = sim.spheres
        return sp.pos, sp.vel, sp.angvel, sim.pairs.hist
    return tuple(getattr(sim, f) for f in ("x", "y", "vx", "vy", "om"))


def measure(n: int, chunk: int, rounds: int, warm: int, dim: int = 2) -> dict:
    import numba

    import demflow

    numba.set_num_threads(1)
    base = importlib.import_module("demflow_base")
    if dim == 3:
        from packing3d import dense_fcc

        scene = dense_fcc(n)
        kw = {}
    else:
        from bench_engines import engine_scene

        scene, _ = engine_scene(n, threads=1)
        kw = dict(threads=1)
    raw = pickle.dumps(scene)
    sims = {"base": base.build(_load_as(raw, "demflow_base")), "head": demflow.build(_load_as(raw, "demflow"))}
    ts = alternate(sims, chunk, rounds, warm, **kw)
    a, b = sims["base"], sims["head"]
    same = all(np.array_equal(u, v) for u, v in zip(_state(a, dim), _state(b, dim)))
    reb = "n_rebuilds" if dim == 3 else "rebuilds"
    row = dict(n=n, dim=dim, chunk=chunk, rounds=rounds, steps=int(b.step), rebuilds_base=int(getattr(a, reb)),
               rebuilds_head=int(getattr(b, reb)), same_bits=bool(same))
    row.update(timing_summary(ts, chunk, n, "base", "head"))
    return row


def per_size(ap, a, work: float, measure_one) -> list:
    """``measure_one(n, chunk)`` for each of ``a.sizes``, with ``a.chunk`` or the default chunk work/N steps (at
    least 20; a wrong count of ``--chunk`` values is refused through ``ap``), each row's ratios printed."""
    chunks = a.chunk or [max(20, int(round(work / n))) for n in a.sizes]
    if len(chunks) != len(a.sizes):
        ap.error(f"--chunk takes one value per size ({len(a.sizes)}), got {len(chunks)}")
    rows = []
    for n, c in zip(a.sizes, chunks):
        print(f"N = {n}: {a.rounds} rounds of {c} steps each ...", flush=True)
        rows.append(measure_one(n, c))
        r = rows[-1]
        print(f"  ratio of minima {r['ratio_of_minima']:.3f}, per-round median {r['ratio_rounds']['median']:.3f}, "
              f"same bits {r['same_bits']}", flush=True)
    return rows


def alternate(sims: dict, chunk: int, rounds: int, warm: int, **kw) -> dict:
    """Run each simulation ``warm`` steps untimed, then ``rounds`` rounds of ``chunk`` steps each, the order of the
    simulations swapped every round; returns {key: [seconds per round]}."""
    for s in sims.values():
        s.run(warm, **kw)
    ts = {k: [] for k in sims}
    for r in range(rounds):
        order = list(sims) if r % 2 == 0 else list(reversed(list(sims)))
        for k in order:
            t0 = time.perf_counter()
            sims[k].run(chunk, **kw)
            ts[k].append(time.perf_counter() - t0)
    return ts


def timing_summary(ts: dict, chunk: int, n: int, a: str, b: str) -> dict:
    """ns per particle-step of each run (min, p10, median, rounds), the per-round ratio b/a and the ratio of the
    minima."""
    row = {}
    for k, v in ts.items():
        ns = np.array(v) / chunk / n * 1e9
        row[k] = dict(min=float(ns.min()), p10=float(np.percentile(ns, 10)), median=float(np.median(ns)),
                      rounds=[float(x) for x in ns])
    ratio = np.array(ts[b]) / np.array(ts[a])
    row["ratio_rounds"] = dict(min=float(ratio.min()), median=float(np.median(ratio)), max=float(ratio.max()))
    row["ratio_of_minima"] = row[b]["min"] / row[a]["min"]
    return row


def table_rows(rows: list, a: str, b: str, rebuilds: str) -> list:
    """The markdown rows of :func:`markdown`'s table (a, b the two runs' keys; ``rebuilds`` the rebuild count's key)."""
    out = []
    for r in rows:
        x, y, q = r[a], r[b], r["ratio_rounds"]
        out.append(f"| {r['n']:,} | {r['chunk']} × {r['rounds']} | {x['min']:.1f} | {x['p10']:.1f} | {x['median']:.1f} | "
                   f"{y['min']:.1f} | {y['p10']:.1f} | {y['median']:.1f} | {q['min']:.3f} / {q['median']:.3f} / "
                   f"{q['max']:.3f} | {r['ratio_of_minima']:.3f} | {'yes' if r['same_bits'] else 'NO'} | "
                   f"{r[rebuilds]} |")
    return out


def run_info(script: str, argv, notes: str, **extra) -> dict:
    """Date, code, command and machine of a run of ``script`` (the results' header)."""
    import numba

    head = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "demflow"], capture_output=True, text=True,
                                cwd=HERE).stdout.strip())
    return dict(date=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), **extra, head=head, dirty=dirty,
                command=f"python benchmarks/{script} " + " ".join(sys.argv[1:] if argv is None else argv),
                notes=notes, cores=os.cpu_count(), cpu=platform.processor() or platform.machine(),
                numba=numba.__version__)


def write_results(out: str, tag: str, data: dict, text: str) -> None:
    """<out>/<tag>.json and .md, written atomically; the markdown printed."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    from demflow.atomic import write_text_atomic

    for path, body in ((out / f"{tag}.json", json.dumps(data, indent=2)), (out / f"{tag}.md", text)):
        write_text_atomic(path, body)
    print(text)


def markdown(data: dict) -> str:
    i = data["info"]
    dim = data["rows"][0].get("dim", 2) if data["rows"] else 2
    scene = ("packing3d.py's dense FCC Hertz sphere packing (periodic x/y, floor, gravity)" if dim == 3 else
             "bench_engines.py's relaxed, agitated, undamped packing (overlap law)")
    out = [f"# {dim}D cycle, this tree vs {i['base'][:7]} in one process ({i['date']})", "",
           f"Head {i['head'][:7]}{' + working tree changes' if i['dirty'] else ''}; command `{i['command']}`; "
           f"{i['cores']} cores, {i['cpu']}, numba {i['numba']}, one thread.  {i['notes']}", "",
           f"Scene: {scene}, the same in both; chunks "
           "of the given steps alternate between base and head, the order swapped each round.  ns per "
           "particle-step (wall clock), over the rounds.", "",
           "| N | chunk × rounds | base min | base p10 | base median | head min | head p10 | head median | "
           "head/base per round (min / median / max) | ratio of minima | same bits | rebuilds |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    out += table_rows(data["rows"], "base", "head", "rebuilds_head")
    return "\n".join(out) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the commit to compare against")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--chunk", type=int, nargs="+", default=None,
                    help="steps per timed chunk, one per size (default 1e7/N: 1000 at 1e4, 100 at 1e5)")
    ap.add_argument("--rounds", type=int, default=40)
    ap.add_argument("--dim", type=int, choices=(2, 3), default=2, help="the 2D disc cycle or the 3D sphere cycle")
    ap.add_argument("--warm", type=int, default=200, help="untimed steps first (compilation, first rebuilds)")
    ap.add_argument("--notes", default="")
    ap.add_argument("--tag", default="speed2d_inprocess_ab")
    ap.add_argument("--out", default=str(HERE / "benchmarks" / "results"))
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        sha = _base_package(a.base, Path(tmp))
        sys.path.insert(0, tmp)
        rows = per_size(ap, a, 1e7, lambda n, c: measure(n, c, a.rounds, a.warm, a.dim))
    info = run_info("bench_ab_inprocess.py", argv, a.notes, base=sha)
    data = dict(info=info, rows=rows)
    write_results(a.out, a.tag, data, markdown(data))


if __name__ == "__main__":
    main()
