"""Time 3 × 300 steps of the 1e5-disc bench_dem packing on one thread with the demflow found at ROOT.

    python benchmarks/bench_ab_steps.py ROOT      # e.g. a worktree of the base commit, or this tree

Prints per round the CPU time, the wall time, the part spent in neighbour-list rebuilds (Python) and
in the compiled steps.  Used beside bench_ab.py to separate the step kernels from process-to-process
noise: run it alternately for two roots (see benchmarks/results/core_ab.md).
"""
import sys, time
root = sys.argv[1]
sys.path.insert(0, root); sys.path.insert(0, root + "/benchmarks")
import numba
numba.set_num_threads(1)
import bench_dem as b
import demflow.simulation as S
print(S.__file__)
scene = b.make_scene(100000)
sim = b.build(scene); sim.run(20, threads=1)
tr = [0.0]
orig = S.Simulation.rebuild
def timed(self):
    t0 = time.perf_counter(); orig(self); tr[0] += time.perf_counter() - t0
S.Simulation.rebuild = timed
for k in range(3):
    tr[0] = 0.0; r0 = sim.rebuilds
    t0 = time.perf_counter(); c0 = time.process_time(); sim.run(300, threads=1); t = time.perf_counter() - t0; c = time.process_time() - c0
    print(f"cpu {c:.2f} s total {t:.2f} s, rebuild {tr[0]:.2f} s ({sim.rebuilds - r0} rebuilds), steps {t - tr[0]:.2f} s")
