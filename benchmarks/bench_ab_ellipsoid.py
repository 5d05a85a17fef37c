"""Per particle-step rate of the ellipsoid cycle with the demflow found at ROOT, one thread, for A/B comparisons of
two trees (a worktree of the base commit and this tree), run alternately in fresh processes.

    python benchmarks/bench_ab_ellipsoid.py ROOT [--scene lattice|bed]

- ``lattice``: near-spherical ellipsoids (1.003 : 1 : 0.997) on benchmarks/packing3d.py's FCC lattice of 4000,
  3 rounds of 40 steps;
- ``bed``: the 80-ellipsoid bed of issue 16's speed acceptance (benchmarks/bench_ellipsoid_vs_clumps.py: the
  miyata-uniaxial-3d protocol's first stage with the seed's ellipsoid) settled 120 000 steps (untimed), then 3 rounds
  of 2000 steps.
"""
import argparse
import sys
import time
import warnings

ap = argparse.ArgumentParser()
ap.add_argument("root")
ap.add_argument("--scene", choices=("lattice", "bed"), default="lattice")
a = ap.parse_args()
root = a.root
sys.path.insert(0, root)
sys.path.insert(0, root + "/benchmarks")
warnings.simplefilter("ignore")
from demflow.jit import set_threads  # noqa: E402

set_threads(1)
import demflow  # noqa: E402

assert demflow.__file__.startswith(root), demflow.__file__
if a.scene == "lattice":
    from bench_ellipsoid import ellipsoid_scene  # noqa: E402
    from packing3d import dense_fcc  # noqa: E402

    sim = demflow.build(ellipsoid_scene(dense_fcc(4000), 0.003))
    steps = 40
else:
    from bench_ellipsoid_vs_clumps import bed  # noqa: E402

    sim = bed("ellipsoids", 8, 120000)
    steps = 2000
sim.run(5)
n = sim.spheres.pos.shape[0]
ts = []
for _ in range(3):
    t = time.perf_counter()
    sim.run(steps)
    ts.append(time.perf_counter() - t)
print(root, a.scene, "best %.3e particle-steps/s, rounds" % (n * steps / min(ts)), [round(n * steps / t / 1e5, 2) for t in ts])
