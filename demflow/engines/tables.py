"""Build the common result tables from an external engine's records.

Every engine reader ends here, so YADE, LIGGGHTS and demflow results have the same
columns, units, sign conventions and schema version (see :mod:`demflow.results` and
:mod:`demflow.schema`; the contacts' force vectors fx, fy come from fn, fs and n by the one
convention of :func:`demflow.schema.contact_force_on_i`).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..results import Results, concat, versioned


def results_from_records(sim, *, engine, steps, wall, wallpos, track, kinetic, snapshots) -> Results:
    """The result tables (current schema) of an engine run.

    sim: the built demflow simulation of the same scene (names, masses, laws).

    steps (R,), wall (R, W, 3) force on each wall and moment about P, wallpos (R, W, 2),
    track (R, T, 2) fn, fs of tracked pairs, kinetic (R,) [force·length] (NaN if unknown);
    snapshots: list of dict(step, particles=[[x, y, theta, vx, vy, omega, r]], contacts=
    [[finder, other, px, py, ex, ey, fn, fs, overlap]], walls=[[px, py, ex, ey]]).
    """
    dt = sim.dt
    t = steps * dt
    wf, tr = [], []
    for w, name in enumerate(sim.wall_names):
        wf.append(pd.DataFrame(dict(step=steps, time=t, wall=name, fx=wall[:, w, 0], fy=wall[:, w, 1],
                                    moment=wall[:, w, 2], px=wallpos[:, w, 0], py=wallpos[:, w, 1])))
    name = lambda b: f"wall:{sim.wall_names[b - sim.n]}" if b >= sim.n else str(b)
    for k, (a, b) in enumerate(sim.track):
        tr.append(pd.DataFrame(dict(step=steps, time=t, a=name(a), b=name(b), fn=track[:, k, 0], fs=track[:, k, 1])))
    energy = pd.DataFrame(dict(step=steps, time=t, kinetic=kinetic, elastic=np.full(len(steps), np.nan)))
    parts, cons, geo = [], [], []
    mu = sim.t["mu"]
    for s in snapshots:
        p = np.asarray(s["particles"], dtype=float).reshape(-1, 7)
        parts.append(pd.DataFrame(dict(step=s["step"], time=s["step"] * dt, id=np.arange(len(p)), x=p[:, 0],
                                       y=p[:, 1], theta=p[:, 2], vx=p[:, 3], vy=p[:, 4], omega=p[:, 5],
                                       radius=p[:, 6])))
        c = np.asarray(s["contacts"], dtype=float).reshape(-1, 9)
        a = c[:, 0].astype(np.int64)
        b = c[:, 1].astype(np.int64)
        is_wall = b >= sim.n
        mb = np.where(is_wall, sim.wmat[np.clip(b - sim.n, 0, max(sim.nw - 1, 0))] if sim.nw else 0,
                      sim.mat[np.clip(b, 0, sim.n - 1)])
        mus = mu[sim.mat[a], mb] if len(a) else np.zeros(0)
        cons.append(pd.DataFrame(dict(
            step=s["step"], time=s["step"] * dt, i=a, j=np.where(is_wall, -1, b),
            wall=np.array([sim.wall_names[x - sim.n] if x >= sim.n else "" for x in b], dtype=object),
            px=c[:, 2], py=c[:, 3], nx=c[:, 4], ny=c[:, 5], fn=c[:, 6], fs=c[:, 7],
            sliding=np.abs(c[:, 7]) >= mus * c[:, 6] * (1 - 1e-9), overlap=c[:, 8])))
        wg = np.asarray(s["walls"], dtype=float).reshape(-1, 4)
        geo.append(pd.DataFrame(dict(step=s["step"], wall=sim.wall_names, px=wg[:, 0], py=wg[:, 1], ex=wg[:, 2],
                                     ey=wg[:, 3], h1=sim.wh1, h2=sim.wh2)))
    meta = dict(engine=engine, scene=sim.scene.name, dt=dt, steps=int(sim.scene.n_steps), n_discs=sim.n,
                walls=sim.wall_names)
    return versioned(Results(wall_forces=concat(wf, "wall_forces"), tracked=concat(tr, "tracked"),
                             energy=concat([energy], "energy"), particles=concat(parts, "particles"),
                             contacts=concat(cons, "contacts"), meta=meta,
                             walls={"geometry": concat(geo, "wall_geometry")}))
