"""Rate study of the dry simple shear (seed 1): rms static-equilibrium error of the wall forces at
four shear rates; sets the simple-shear.equilibrium tolerance (demflow/tolerances.py).

    python benchmarks/simple_shear_rate.py > benchmarks/results/simple_shear_rate.txt
"""
import time
from demflow.cases import get_case
from demflow.cases import simple_shear_setup as setup
from demflow.cases.thesis_simple_shear import run_variant, equilibrium
case = get_case("thesis-simple-shear")
specs = {k: setup.compress(k, 1) for k in ("loose", "dense")}
for rate in (0.2, 0.1, 0.05, 0.02):
    p = case.merged(dict(rate=rate))
    for k, spec in specs.items():
        t = time.time(); res = run_variant(spec, False, p); rms, mx = equilibrium(res)
        print(f"rate {rate} {k}: rms {100*rms:.3f} % max {100*mx:.2f} %  ({time.time()-t:.1f} s)", flush=True)
