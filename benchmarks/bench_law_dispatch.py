"""How the compiled cycle selects a contact law: three Numba dispatch techniques measured.

    python benchmarks/bench_law_dispatch.py [--pairs 2000000] [--rounds 7]

A pair loop (prange) evaluates one of two laws (linear, Hertz) from (nm × nm) parameter tables and
a history row, the shape of demflow's pair pass.  Techniques:

- ``overload``: the law's params are a namedtuple whose *type* selects the implementation
  (numba.extending.overload, inline="always") when the loop is compiled — what demflow uses;
- ``switch``: an integer law id in the params and an if/elif per pair;
- ``function``: the law's kernel, a jitted function, passed to the loop as an argument
  (first-class function).

Reported: ns per pair (best of ``rounds``, with the spread), whether the result is identical to
the bit across techniques, and whether a second process finds every variant in Numba's on-disk
cache (compiles nothing).  Results: benchmarks/results/law_dispatch.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

OUT = Path(__file__).resolve().parent / "results"

MODULE = textwrap.dedent('''
    from collections import namedtuple
    import numpy as np
    import numba
    from numba import prange
    from numba.extending import overload

    Lin = namedtuple("Lin", "kn mu")
    Hz = namedtuple("Hz", "kn mu")
    Sw = namedtuple("Sw", "law kn mu")

    def force(p, h, k, a, b, d):
        raise NotImplementedError

    @overload(force, inline="always")
    def _force(p, h, k, a, b, d):
        if getattr(p, "instance_class", None) is Lin:
            def impl(p, h, k, a, b, d):
                f = p.kn[a, b] * d
                h[k, 0] = min(h[k, 0] + 0.1 * f, p.mu[a, b] * f)
                return f
            return impl
        if getattr(p, "instance_class", None) is Hz:
            def impl(p, h, k, a, b, d):
                f = p.kn[a, b] * d * np.sqrt(d)
                h[k, 0] = min(h[k, 0] + 0.1 * f, p.mu[a, b] * f)
                return f
            return impl

    @numba.njit(parallel=True, cache=True)
    def loop_overload(p, h, mat, d, out):
        for k in prange(d.shape[0]):
            out[k] = force(p, h, k, mat[k], mat[k + 1], d[k])

    @numba.njit(parallel=True, cache=True)
    def loop_switch(p, h, mat, d, out):
        for k in prange(d.shape[0]):
            a = mat[k]
            b = mat[k + 1]
            if p.law == 0:
                f = p.kn[a, b] * d[k]
            else:
                f = p.kn[a, b] * d[k] * np.sqrt(d[k])
            h[k, 0] = min(h[k, 0] + 0.1 * f, p.mu[a, b] * f)
            out[k] = f

    @numba.njit(cache=True)
    def lin_kernel(kn, mu, hk, d):
        f = kn * d
        return f, min(hk + 0.1 * f, mu * f)

    @numba.njit(cache=True)
    def hz_kernel(kn, mu, hk, d):
        f = kn * d * np.sqrt(d)
        return f, min(hk + 0.1 * f, mu * f)

    @numba.njit(parallel=True, cache=True)
    def loop_function(kernel, kn, mu, h, mat, d, out):
        for k in prange(d.shape[0]):
            a = mat[k]
            b = mat[k + 1]
            f, hk = kernel(kn[a, b], mu[a, b], h[k, 0], d[k])
            h[k, 0] = hk
            out[k] = f
''')

DRIVER = textwrap.dedent('''
    import sys, time, json
    import numpy as np
    sys.path.insert(0, {mod_dir!r})
    from numba.core import event
    import numba
    import lawdispatch as m
    numba.set_num_threads(1)
    n, rounds = {pairs}, {rounds}
    rng = np.random.default_rng(1)
    kn = rng.uniform(1.0, 2.0, (3, 3)); mu = rng.uniform(0.2, 0.6, (3, 3))
    mat = rng.integers(0, 3, n + 1); d = rng.uniform(1e-4, 1e-2, n)
    res = {{}}
    with event.install_recorder("numba:compile") as rec:
        for law in ("linear", "hertz"):
            cases = dict(
                overload=lambda h, o: m.loop_overload((m.Lin if law == "linear" else m.Hz)(kn, mu), h, mat, d, o),
                switch=lambda h, o: m.loop_switch(m.Sw(0 if law == "linear" else 1, kn, mu), h, mat, d, o),
                function=lambda h, o: m.loop_function(m.lin_kernel if law == "linear" else m.hz_kernel,
                                                      kn, mu, h, mat, d, o))
            outs = {{}}
            for name, call in cases.items():
                h = np.zeros((n, 1)); o = np.zeros(n)
                call(h, o)
                ts = []
                for _ in range(rounds):
                    h[:] = 0.0
                    t0 = time.perf_counter(); call(h, o); ts.append(time.perf_counter() - t0)
                outs[name] = (o.copy(), h.copy())
                res[f"{{law}}/{{name}}"] = [t / n * 1e9 for t in ts]
            ref = outs["overload"]
            res[f"{{law}}/identical"] = {{k: bool(np.array_equal(v[0], ref[0]) and np.array_equal(v[1], ref[1]))
                                         for k, v in outs.items()}}
    res["compiled"] = sorted({{ev.data["dispatcher"].py_func.__name__ for _, ev in rec.buffer if ev.is_start}})
    print(json.dumps(res))
''')


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=2_000_000)
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "lawdispatch.py").write_text(MODULE)
        code = DRIVER.format(mod_dir=tmp, pairs=a.pairs, rounds=a.rounds)
        env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        runs = []
        for _ in range(2):  # the first compiles and fills the cache, the second should compile nothing
            p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
            if p.returncode:
                raise SystemExit(p.stderr[-3000:])
            runs.append(json.loads(p.stdout.strip().splitlines()[-1]))
    first, second = runs
    rows = []
    for law in ("linear", "hertz"):
        for tech in ("overload", "switch", "function"):
            ts = first[f"{law}/{tech}"] + second[f"{law}/{tech}"]
            rows.append(dict(law=law, technique=tech, ns_per_pair_best=min(ts), ns_per_pair_max=max(ts),
                             identical_to_overload=first[f"{law}/identical"][tech]))
    cached = {tech: not any(name.startswith(f"loop_{tech}") or (tech == "function" and name.endswith("_kernel"))
                            for name in second["compiled"]) for tech in ("overload", "switch", "function")}
    info = dict(date=time.strftime("%Y-%m-%d %H:%M:%S"), pairs=a.pairs, rounds=a.rounds, threads=1,
                second_process_compiled=second["compiled"], cache_kept=cached, loadavg=os.getloadavg())
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "law_dispatch.json").write_text(json.dumps(dict(info=info, rows=rows), indent=2))
    lines = [f"# Law dispatch in Numba ({info['date']}, {a.pairs:,} pairs, 1 thread, best of {2 * a.rounds} "
             "rounds in two processes)", "",
             "| law | technique | ns/pair (best) | ns/pair (worst) | same bits as overload | cache kept |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['law']} | {r['technique']} | {r['ns_per_pair_best']:.2f} | {r['ns_per_pair_max']:.2f} | "
                     f"{r['identical_to_overload']} | {cached[r['technique']]} |")
    lines += ["", f"Second process compiled: {second['compiled'] or 'nothing'}."]
    (OUT / "law_dispatch.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
