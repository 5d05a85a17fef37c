"""Where the 3D pair pass waits: `perf` samples counted per machine instruction of ``sphere_forces``.

    perf record -e cpu-clock:u -F 5000 -o pass.data python benchmarks/perf_pass3d.py run --n 100000 --steps 300 --out pass
    perf script -i pass.data -F ip > pass.ips
    python benchmarks/perf_pass3d.py annotate --out pass [--top 30]

``run``: builds packing3d.py's benchmark packing (``dense_fcc(n)``, one thread; ``--conventions liggghts``: in the
LIGGGHTS deck's conventions), runs ``--warm`` untimed steps (default 200: compilation, first rebuild), writes the
compiled pass's machine code as it lies in memory (``<out>.bin``, read up to the end of its memory mapping, at most
128 KiB) and its address (``<out>.addr``: Numba's ``get_pointer_to_function``), then runs
``--steps`` steps.  ``annotate``: disassembles ``<out>.bin`` at that address (``objdump``), counts the samples of
``<out>.ips`` (one instruction pointer a line, from ``perf script -F ip``) per instruction, and writes
``<out>.annot`` (samples, share of the pass's samples, offset, instruction) and prints the share per 256-byte
stretch and the hottest instructions.  A sample lands on the instruction that waits to retire, usually the one after
a long operation (a square root, a division, a load that missed).  Used for
benchmarks/results/speed_experiments_session38.md.  Needs Linux ``perf`` (cpu-clock: no hardware counters needed)
and ``objdump``.

Instructions instead of samples (valgrind's callgrind; benchmarks/results/speed_experiments_session39.md).  Under
valgrind Numba sees another CPU and would recompile every kernel (half an hour); so compile them natively first into a
cache of their own with the CPU named, then run the same under valgrind, which loads the host's machine code::

    export NUMBA_CACHE_DIR=/tmp/pass-cache NUMBA_CPU_NAME=znver3 \
        NUMBA_CPU_FEATURES=$(python -c "import llvmlite.binding as l; print(l.get_host_cpu_features().flatten())")
    python benchmarks/perf_pass3d.py run --n 10000 --steps 20 --out pass     # fills the cache
    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=pass.cg \
        python benchmarks/perf_pass3d.py run --n 10000 --steps 20 --out pass
    python benchmarks/perf_pass3d.py annotate --out pass --callgrind pass.cg

(``NUMBA_CPU_NAME``: the host's, ``python -c "import llvmlite.binding as l; print(l.get_host_cpu_name())"``.)  With
``--callgrind`` the counts are instructions executed, and the summary groups the instructions by how often each ran
(an instruction run once per listed pair, once per touching pair, ...: the pass's stages).
"""
from __future__ import annotations

import argparse
import collections
import ctypes
import re
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "benchmarks"))

LIMIT = 1 << 17


def run(n: int, steps: int, out: str, warm: int = 200, conventions: str = "own") -> None:
    from bench_engines3d import liggghts_scene
    from packing3d import dense_fcc

    from demflow import build
    from demflow.contacts import spheres
    from demflow.jit import set_threads

    set_threads(1)
    scene = dense_fcc(n)
    sim = build(liggghts_scene(scene) if conventions == "liggghts" else scene)
    sim.run(warm)
    compiled = list(spheres.sphere_forces.overloads.values())
    if len(compiled) != 1:
        sys.exit(f"sphere_forces has {len(compiled)} compiled versions in this process; this tool reads one")
    cres = compiled[0]
    addr = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    end = addr + LIMIT
    for line in open("/proc/self/maps"):
        lo, hi = (int(x, 16) for x in line.split()[0].split("-"))
        if lo <= addr < hi:
            end = min(end, hi)
    Path(out + ".bin").write_bytes(ctypes.string_at(addr, end - addr))
    Path(out + ".addr").write_text(f"{addr:#x} {end - addr}\n")
    t = time.perf_counter()
    sim.run(steps)
    print(f"sphere_forces at {addr:#x}; {steps} steps of {n} spheres in {time.perf_counter() - t:.2f} s")


def callgrind_counts(path: str, addr: int, size: int) -> collections.Counter:
    """Instructions executed per offset into the pass, from a callgrind file written with ``--dump-instr=yes``
    (cost lines ``position line Ir``, positions absolute or relative to the last (``+n``, ``-n``, ``*``); the line
    after ``calls=`` is a call's inclusive cost, not the calling instruction's own)."""
    counts = collections.Counter()
    pos = 0
    after_call = False
    for line in open(path):
        if not line or line[0] not in "0123456789+-*":
            after_call = line.startswith("calls=")
            continue
        f = line.split()
        tok = f[0]
        pos = pos if tok == "*" else pos + int(tok[1:], 0) if tok[0] == "+" else pos - int(tok[1:], 0) \
            if tok[0] == "-" else int(tok, 0)
        if after_call:
            after_call = False
            continue
        if len(f) >= 3 and addr <= pos < addr + size:
            counts[pos - addr] += int(f[-1])
    return counts


def annotate(out: str, top: int, callgrind: str | None = None) -> None:
    addr, size = Path(out + ".addr").read_text().split()
    addr, size = int(addr, 16), int(size)
    if callgrind:
        counts = callgrind_counts(callgrind, addr, size)
    else:
        counts = collections.Counter()
        for line in open(out + ".ips"):
            ip = int(line.split()[0], 16)
            if addr <= ip < addr + size:
                counts[ip - addr] += 1
    total = sum(counts.values())
    if not total:
        sys.exit("nothing counted falls inside the pass: was the profile recorded from the same run as <out>.addr?")
    dis = subprocess.run(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", f"--adjust-vma={addr:#x}",
                          out + ".bin"], capture_output=True, text=True, check=True).stdout
    rows = []
    for line in dis.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s", line)
        if m:
            off = int(m.group(1), 16) - addr
            c = counts.get(off, 0)
            rows.append((c, f"{c:6d} {100 * c / total:6.2f} {off:6x} {line.split(chr(9))[-1].strip()}"))
    Path(out + ".annot").write_text("\n".join(r for _, r in rows) + "\n")
    stretch = collections.Counter()
    for off, c in counts.items():
        stretch[off // 256] += c
    if callgrind:
        runs = collections.Counter()  # executions -> [instructions run that often, their total]
        width = collections.Counter()
        for off, c in counts.items():
            runs[c] += c
            width[c] += 1
        print(f"{total} instructions executed in the pass; by how often an instruction ran:")
        for c, ir in runs.most_common(12):
            print(f"  {c:12d} times: {width[c]:4d} instructions, {100 * ir / total:5.1f} %")
    print(f"{total} {'instructions' if callgrind else 'samples'} in the pass")
    print("share per 256 bytes: " + " ".join(f"{k * 256:x}:{100 * v / total:.1f}%" for k, v in sorted(stretch.items())
                                              if v > 0.005 * total))
    for _, r in sorted(rows, key=lambda x: -x[0])[:top]:
        print(r)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=("run", "annotate"))
    ap.add_argument("--n", type=int, default=100000, help="spheres (run)")
    ap.add_argument("--steps", type=int, default=300, help="steps sampled (run)")
    ap.add_argument("--warm", type=int, default=200,
                    help="untimed steps before (run; bench_engines3d.py's S: 3000 at 1e4)")
    ap.add_argument("--conventions", choices=("own", "liggghts"), default="own",
                    help="run: the scene as written, or in the LIGGGHTS deck's conventions "
                         "(bench_engines3d.liggghts_scene)")
    ap.add_argument("--out", default="pass", help="prefix of the files written and read")
    ap.add_argument("--top", type=int, default=30, help="hottest instructions printed (annotate)")
    ap.add_argument("--callgrind", help="annotate: a callgrind file (--dump-instr=yes) instead of <out>.ips")
    a = ap.parse_args(argv)
    if a.mode == "run":
        run(a.n, a.steps, a.out, a.warm, a.conventions)
    else:
        annotate(a.out, a.top, a.callgrind)


if __name__ == "__main__":
    main()
