"""Per particle-step rate of the ellipsoid cycle with the demflow found at ROOT: near-spherical ellipsoids
(1.003 : 1 : 0.997) on benchmarks/packing3d.py's FCC lattice of 4000, one thread, 3 rounds of 40 steps.

    python benchmarks/bench_ab_ellipsoid.py ROOT    # run it alternately for two roots (a worktree of the base commit, this tree)
"""
import sys, time
root = sys.argv[1]
sys.path.insert(0, root); sys.path.insert(0, root + "/benchmarks")
import warnings; warnings.simplefilter("ignore")
import numpy as np
from demflow.jit import set_threads
set_threads(1)
import demflow
from packing3d import dense_fcc
from bench_ellipsoid import ellipsoid_scene
assert demflow.__file__.startswith(root), demflow.__file__
sim = demflow.build(ellipsoid_scene(dense_fcc(4000), 0.003))
sim.run(5)
ts = []
for _ in range(3):
    t = time.perf_counter(); sim.run(40); ts.append(time.perf_counter() - t)
print(root, "best %.3e particle-steps/s, rounds" % (4000 * 40 / min(ts)), [round(4000 * 40 / t / 1e5, 2) for t in ts])
