"""Prints, as JSON, a sha256 of what demflow computes from a scene before its kernels run, for tests/test_libm.py.

Run in a fresh process (``python tests/libm_probe.py [--control]``), once as numpy comes and once with numpy's
CPU-specific code switched off (``NPY_DISABLE_CPU_FEATURES``): every entry must come out the same.  Each entry goes
through one place that once used, or could use, a numpy function compiled per CPU: sphere masses and the Rayleigh
step (r³), a short run of the 3D golden bed, the ellipsoids' safe step (a surface grid of sines and cosines), the
3D conformance decks written for YADE and LIGGGHTS, a clump template, the 2D kissing bound (arcsin), the BEM's
circles and log-weighted quadrature, the one-wall Stokes resistance (arccosh, tanh), the C&S friction (tan) and
Miyata's rough trimming surface (sin), and the q-model's maximum-likelihood fit (its likelihood's log
and exp: the fit's stopping point follows their last bits).  ``--control`` adds an entry computed through ``np.tanh`` (the negative
control: numpy has CPU-specific code for it on AVX2 and on AVX-512 CPUs).
"""
from __future__ import annotations

import hashlib
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
warnings.simplefilter("ignore")


def digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        if isinstance(a, (str, bytes)):
            h.update(a.encode() if isinstance(a, str) else a)
        else:
            h.update(np.ascontiguousarray(np.asarray(a, dtype=np.float64)).tobytes())
    return h.hexdigest()


def probe(control: bool) -> dict:
    import demflow as df
    from demflow.analysis.forces import fit_q_model
    from demflow.bem.geometry import circle
    from demflow.bem.quadrature import log_gauss
    from demflow.cases import conformance_3d as conf
    from demflow.cases.cs_nine_disc import nine_disc_scene
    from demflow.cases.miyata_uniaxial2d import surface
    from demflow.coupling import wall_resistance
    from demflow.integrate import kissing_number
    import golden3d_scenes as g3

    out = {}
    sim = df.build(g3.settling_bed())
    out["bed3d: masses, dt"] = digest(sim.spheres.mass, [sim.dt, sim.dt_safe])
    sim.run(300)
    out["bed3d: state after 300 steps"] = digest(sim.spheres.pos, sim.spheres.vel, sim.spheres.angvel)
    ell = df.build(g3.ellipsoid_bed())
    out["ell3d: safe step, masses"] = digest([ell.dt_safe], ell.bodies.mass, ell.bodies.moments)
    with tempfile.TemporaryDirectory() as tmp:
        texts = []
        for v, engines in sorted(conf.VARIANTS.items()):  # every deck a reference is stored from
            sc = conf.scene(v, conf.PARAMS)
            for engine in engines:
                where = Path(tmp) / engine / v
                where.mkdir(parents=True)
                texts += [p.read_text() for p in sorted(conf.engine_for(engine, v).write_deck(sc, df.build(sc), where))]
        out["conformance-3d decks"] = digest("\n".join(texts))
    T = df.ClumpTemplate.ellipsoid_like(8)
    out["clump template K=8"] = digest(T.centres, T.radii, [T.mass], T.moments)
    R = np.linspace(0.5, 3.0, 101)
    out["2D kissing bound"] = digest(kissing_number(R, 1.0))
    x, w = log_gauss(24)
    out["BEM: log-weighted quadrature, circle"] = digest(x, w, circle((0.3, -0.2), 1.1, 64).ends)
    out["one-wall Stokes resistance"] = digest(wall_resistance(1e-3, 1.0, np.linspace(1.0001, 5.0, 97)))
    nd = nine_disc_scene("probe", kn=1.35e9, ks=1.35e9, phi_deg=26.0, speed=0.12, load_cycles=40, rest_cycles=40)
    out["C&S friction"] = digest([law.friction for law in nd.laws.values()])
    out["Miyata rough surface"] = digest(surface(np.linspace(0.0, 4.0, 101), True))
    F = np.random.default_rng(11).gamma(2.5, 1.0, 4000)
    q = fit_q_model(F / F.mean())
    out["q-model fit (log, exp)"] = digest([q.N, q.ci[0], q.ci[1], q.loglik, q.se])
    if control:
        out["control: np.tanh"] = digest(np.tanh(np.linspace(-5.0, 5.0, 100001)))
    return out


if __name__ == "__main__":
    print(json.dumps(probe("--control" in sys.argv)))
