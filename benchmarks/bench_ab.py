"""A/B throughput of the calculation cycle: this working tree against a base commit, side by side.

    python benchmarks/bench_ab.py --base a607ddf [--sizes 10000 100000] [--threads 1 2] [--rounds 3]

The base commit is checked out in a temporary git worktree; each round runs ``benchmarks/bench_dem.py``
of the base and of this tree (same benchmark, same packing, each its own demflow) in fresh
processes, alternating which goes first, every invocation taking the best of its own repeats.
Reported per (N, threads): the best particle-steps/s of each side over all rounds, their ratio, and
the spread of the per-round ratios.  Run it on a quiet machine (nothing else running).
Results: benchmarks/results/<tag>.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


def _run(root: Path, n: int, threads: int, repeats: int, out: Path, tag: str) -> float:
    cmd = [sys.executable, str(root / "benchmarks" / "bench_dem.py"), "--sizes", str(n), "--threads", str(threads),
           "--repeats", str(repeats), "--out", str(out), "--tag", tag]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=root)
    if p.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{p.stderr[-3000:]}")
    rows = json.loads((out / f"{tag}.json").read_text())["rows"]
    return float(rows[0]["particle_steps_per_s"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the commit to compare against")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tag", default="core_ab")
    a = ap.parse_args(argv)
    base_sha = subprocess.run(["git", "rev-parse", a.base], capture_output=True, text=True, cwd=HERE,
                              check=True).stdout.strip()
    head_sha = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=HERE,
                              check=True).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "demflow"], capture_output=True, text=True,
                                cwd=HERE).stdout.strip())
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base_root = Path(tmp) / "base"
        subprocess.run(["git", "worktree", "add", "--detach", str(base_root), base_sha], cwd=HERE, check=True,
                       capture_output=True)
        try:
            out = Path(tmp) / "out"
            for n in a.sizes:
                for t in a.threads:
                    got = {"base": [], "head": []}
                    for k in range(a.rounds):
                        order = ("base", "head") if k % 2 == 0 else ("head", "base")
                        for side in order:
                            root = base_root if side == "base" else HERE
                            got[side].append(_run(root, n, t, a.repeats, out, f"{side}-{n}-{t}-{k}"))
                    ratios = [h / b for h, b in zip(got["head"], got["base"])]
                    row = dict(n=n, threads=t, base=max(got["base"]), head=max(got["head"]),
                               ratio=max(got["head"]) / max(got["base"]), ratio_min=min(ratios),
                               ratio_max=max(ratios), base_all=got["base"], head_all=got["head"])
                    rows.append(row)
                    print(f"N={n} threads={t}: base {row['base']:.3e}, head {row['head']:.3e} p-steps/s, "
                          f"ratio {row['ratio']:.3f} (rounds {row['ratio_min']:.3f}-{row['ratio_max']:.3f})",
                          flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base_root)], cwd=HERE, capture_output=True)
    info = dict(date=time.strftime("%Y-%m-%d %H:%M:%S"), base=base_sha, head=head_sha, head_dirty=dirty,
                rounds=a.rounds, repeats=a.repeats, cores=os.cpu_count(), loadavg_after=os.getloadavg())
    res = HERE / "benchmarks" / "results"
    res.mkdir(parents=True, exist_ok=True)
    (res / f"{a.tag}.json").write_text(json.dumps(dict(info=info, rows=rows), indent=2))
    lines = [f"# Calculation cycle, this tree vs {base_sha[:7]} ({info['date']}; head {head_sha[:7]}"
             f"{' + uncommitted' if dirty else ''}; best of {a.rounds} rounds × {a.repeats} repeats, "
             "alternating order)", "",
             "| N | threads | base p-steps/s | head p-steps/s | head/base (best) | per-round head/base |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']:,} | {r['threads']} | {r['base']:.3e} | {r['head']:.3e} | {r['ratio']:.3f} | "
                     f"{r['ratio_min']:.3f}–{r['ratio_max']:.3f} |")
    (res / f"{a.tag}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
