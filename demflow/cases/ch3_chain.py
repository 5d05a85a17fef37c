"""ch3-impulse-chain: an impulse through a chain of 100 balls (ch3 §3.5.4.3, Fig. 3.9).

One hundred identical balls (mass 1.5708 kg, 1 m apart, touching with no initial force) in a line,
no gravity, restitution 0.3 (dashpot by ch3 eq 3.28 with m* = m/2), the bottom ball fixed; "a
vertical impulse force is applied on the top ball": here an initial velocity v0 = 1 m/s towards
the chain (an impulse P = m v0; the response is linear in P while all contacts stay closed).
ch3 reports the first-arrival delay and the attenuation with distance, and the reflection from
the bottom (Fig. 3.9, lost).

Reference: the long-wave speed of a chain of masses m and springs k, c = d√(k/m) (the largest
group velocity of the discrete chain): the pulse reaches the ball s places from the source after
s√(m/k).  Arrival = the time of the first maximum of the ball's speed (parabola through the three
samples), its apparent speed the slope of arrival time against distance for balls 20-80 places
from the source.  Assumptions: kn = 3962 N/m as the stack (ch3 gives no value; the prediction
scales with it); v0 = 1 m/s.
"""
from __future__ import annotations

import numpy as np

from ..laws.restitution import zeta_linear
from ..scene import LinearLaw, Material
from ..scene3d import Outputs3D, Scene3D, Spheres
from .base import Case, CaseRun, Check
from .ch3_stack import KN, MASS

SRC = "ch3 §3.5.4.3"


def chain_scene(n: int = 100, restitution: float = 0.3, dt_fraction: float = 0.1, v0: float = 1.0,
                name: str = "ch3-impulse-chain") -> Scene3D:
    cn = 2.0 * zeta_linear(restitution) * float(np.sqrt(KN * MASS / 2.0)) if restitution < 1 else 0.0
    vel = np.zeros((n, 3))
    vel[-1, 2] = -v0
    return Scene3D(name=name, spheres=Spheres(x=[0.0] * n, y=[0.0] * n, z=[float(j) for j in range(n)],
                                              radius=[0.5] * n, material="ball", mass=[MASS] * n,
                                              fixed=[True] + [False] * (n - 1), velocity=vel),
                   materials={"ball": Material(density=1.0)}, laws={("ball", "ball"): LinearLaw(kn=KN, cn=cn)},
                   dt_fraction=dt_fraction, outputs=Outputs3D(every=1, track_spheres=tuple(range(n))),
                   max_contacts=2)  # a chain: each ball touches the two next to it


def arrivals(sim) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(distance from the source in balls, arrival time, peak speed) for balls 1 .. n-2."""
    r = sim.records()
    t = r["step"] * sim.dt
    speed = -r["track"][:, :, 5]
    n = speed.shape[1]
    dist, tarr, peak = [], [], []
    for j in range(1, n - 1):
        s = speed[:, j]
        k = np.nonzero((s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:]) & (s[1:-1] > 1e-4))[0]
        if not k.size:
            continue
        k = k[0] + 1
        y0, y1, y2 = s[k - 1], s[k], s[k + 1]
        den = y0 - 2 * y1 + y2
        dk = 0.5 * (y0 - y2) / den if den != 0 else 0.0
        dist.append(n - 1 - j)
        tarr.append(t[k] + dk * sim.dt)
        peak.append(y1 - 0.25 * (y0 - y2) * dk)
    return np.array(dist), np.array(tarr), np.array(peak)


class ImpulseChain(Case):
    name = "ch3-impulse-chain"
    title = "Impulse through a chain of 100 balls (ch3 Fig. 3.9)"
    source = SRC
    assumptions = (
        "kn = 3962 N/m (as the stack; ch3 gives none) and an impulse as an initial velocity of 1 m/s of the top "
        "ball; dashpot from e = 0.3 by ch3 eq 3.28 with m* = m/2.",
        "Arrival = first maximum of each ball's speed; the apparent speed is the slope over balls 20-80 places "
        "from the source.",
    )
    params = dict(dt_fraction=0.1)

    def run(self, p) -> CaseRun:
        from ..build import build

        out = {}
        for label, e in (("e = 0.3", 0.3), ("undamped", 1.0)):
            sim = build(chain_scene(restitution=e, dt_fraction=p["dt_fraction"]))
            sim.run(int(1.3 * 100 * np.sqrt(MASS / KN) / sim.dt))
            d, t, pk = arrivals(sim)
            r = sim.records()
            out[label] = {"dist": d, "t": t, "peak": pk, "dt": sim.dt,
                          "speed": -r["track"][:, :, 5], "time": r["step"] * sim.dt}
        return CaseRun({}, {"runs": out})

    def checks(self, run, p):
        tau = float(np.sqrt(MASS / KN))
        out = []
        for label in ("e = 0.3", "undamped"):
            q = run.extras["runs"][label]
            sel = (q["dist"] >= 20) & (q["dist"] <= 80)
            slope = np.polyfit(q["dist"][sel], q["t"][sel], 1)[0]
            name = f"{label}: arrival time per ball vs √(m/k) (apparent wave speed⁻¹) [s]"
            if label == "e = 0.3":
                out.append(Check.against(name, slope, tau, "ch3.chain-arrival", SRC))
                k50 = list(q["dist"]).index(50)
                out.append(Check.info("e = 0.3: arrival 50 balls from the source vs 50√(m/k) [s]", q["t"][k50], SRC,
                                      "The peak of a spreading pulse: shown.", reference=50 * tau))
                pk = q["peak"][np.argsort(q["dist"])]
                out.append(Check.condition("e = 0.3: the peak speed falls with distance from the source (attenuation)",
                                           bool(np.all(np.diff(pk) < 0)), float(pk[-1] / pk[0]), SRC,
                                           "ch3: 'attenuation with distance'; value: last/first peak speed.",
                                           kind="source"))
            else:
                out.append(Check.info(name, slope, SRC, "Without dashpots the discrete chain's front lags the "
                                      "long-wave speed (its peak follows the Bessel front J_2s, delayed by ~s^{1/3}); "
                                      "shown, not checked.", reference=tau))
        return out

    def figures(self, run, p, outdir):
        import matplotlib.pyplot as plt

        from ..plotting import save_figure

        q = run.extras["runs"]["e = 0.3"]
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
        sp = q["speed"]
        scale = 2.0 / max(sp.max(), 1e-12)
        for j in range(1, sp.shape[1] - 1, 3):
            a1.plot(q["time"], (sp.shape[1] - 1 - j) + scale * sp[:, j], "k-", lw=0.5)
        a1.set_xlabel("time [s]")
        a1.set_ylabel("balls from the source (+ speed)")
        a1.set_title("impulse through the chain (ch3 Fig. 3.9)")
        a2.plot(q["dist"], q["t"], "k.", ms=3, label="arrival (e = 0.3)")
        a2.plot(q["dist"], q["dist"] * np.sqrt(MASS / KN), "r-", lw=0.8, label="s√(m/k)")
        u = run.extras["runs"]["undamped"]
        a2.plot(u["dist"], u["t"], "b.", ms=2, label="undamped")
        a2.set_xlabel("balls from the source")
        a2.set_ylabel("arrival time [s]")
        a2.legend(fontsize=8)
        path = f"{outdir}/chain.png"
        save_figure(fig, path)
        return [path]
