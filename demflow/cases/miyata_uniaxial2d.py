"""miyata-uniaxial-2d: uniaxial compression of circles and n = 4 superquadrics (Miyata §3.2).

The seed's protocol (Miyata §3.2 (1)-(2), Tables 1-2, Fig. 24): mono-size particles inserted in a
box periodic along x, settled under gravity, the surface trimmed (smooth: centres above z0 = 2.7 m
removed; rough: centres above z(x) = z0 + a sin(2πx/L), eq 60, a = 0.3 m, L = 2 m, x from the left
boundary), settled again, then a horizontal plate placed at the sample's top and lowered at
0.01 m/s.  Four samples (Table 1): circles r = 15 cm (CS smooth, CR rough) and superquadrics n = 4,
a = 19.5 cm, b = 9.76 cm (SS, SR); Table 2: ρ = 1650 kg/m³ (unit depth), k_n = k_s = 1e7 N/m
between particles and 1e8 N/m with the walls, e = 0.01, μ = 0.51, Δt = 1.7078e-4 s.

What is computed: the stress-settlement curve (Fig. 26) and its three regimes (initial 0-50 kPa,
transition 50-250 kPa, final > 250 kPa), the stress drops in the final regime (circles show them,
superquadrics do not), the ratio of plate to floor contacts vs the stress (Fig. 29) and the share
of the final load carried by the plate contacts formed first, next and last (Fig. 30: the first
40 %, the next 30 %, the last 30 % of the contacts, in order of formation).

Variants (``variant`` parameter):

- ``reduced`` (the default, what `demflow validate` runs): the seed's particles, materials, time
  step, bed depth and surface profiles in a 2 m wide box (one wavelength of eq 60) with one seed,
  to ``stress_max`` (900 kPa by default, the seed's final stress), the plate at 0.1 m/s (10 × the
  seed's; inertial number (v/H) d √(ρ/σ) ≈ 2e-3 at 50 kPa, quasi-static; the force-balance check
  measures it);
- ``full``: the seed's 10 m box and plate speed, ``n_seeds`` = 8 seeds per sample (slow: the
  superquadric cycle costs ~1-2 ms per step for 60 particles, so hours; see the report).

Assumptions (each stated on the report; the seed does not give these):

1. Every sample runs on demflow's 2D superquadric cycle (:mod:`demflow.simulation_sq2d`), the
   circles as n = 2, a = b = 15 cm (Table 1 lists them as "circular (n=2)": the seed ran them on
   its superquadric code too).
2. Linear law of Miyata eq 13 (N = k_n δ, the total overlap) with an incremental shear spring,
   Coulomb limit μ; the normal dashpot of eq 17 from e = 0.01 with the pair's effective mass (the
   particle's mass against a wall); no shear dashpot, no global damping (none is stated).
3. μ = 0.51 for particle-wall contacts too ("Friction 0.51", Table 2, does not say which).
4. The seed sets μ to another, unstated value "when circular particles are randomly sedimented in
   order to make disordered samples": circles are deposited with μ = ``mu_deposit_circles`` = 1.0,
   superquadrics with μ = 0.51; μ = 0.51 everywhere from the re-settling on.  Frictionless
   deposition was tried first and crystallised (measured, 2 m box, seed 1: a hexagonal bed with 6
   floor contacts per row, a stress-settlement curve linear from the first contact, 2 plate
   contacts up to 250 kPa), the opposite of the seed's purpose, so the unstated value is taken
   above 0.51.
5. Insertion (Fig. 24(a) is lost): a loose lattice (spacing 2 × bounding radius + 5 cm) with a
   random offset per row, a random jitter and, for superquadrics, random orientations (seeded);
   as many particles as fill the box to ``fill_height`` = 3.2 m at packing fraction 0.85, the same
   number for circles and superquadrics (equal masses: the seed's superquadric has 0.16 % less
   area than the circle with the printed a, b; kept as printed).
6. CS and CR (likewise SS and SR) are trimmed from the same deposited bed (one deposition per
   shape and seed).
7. "Settled" (both settling stages): the mean kinetic energy per particle below
   ``settle_ke`` × m g r (r = 15 cm), checked every 1000 steps.
8. The plate starts ``plate_gap`` = 5 mm above the highest particle point (both plates are walls
   longer than the box by 1 m on each side; walls are not repeated across the periodic boundary); the settlement is
   counted from the plate's first contact.  Contact history (springs) carries from the re-settled
   bed into the loading stage (same particles); after the trimming it starts afresh (the bed
   re-settles).
9. A plate contact's formation is the record at which its current, unbroken contact with the plate
   began; the Fig. 30 groups are the plate contacts alive at the final stress, ranked by formation
   (the seed's "first 40 % of the contact points newly created").
10. A stress drop is a fall of the plate stress below its running maximum by more than
    ``miyata2d.stress-drop`` (tolerances.py) in the final regime (> 250 kPa).
11. The blow-up guard is raised to overlaps of 0.9 × the smaller semi-axis (:data:`MAX_OVERLAP`):
    Table 2's k_n = 1e7 N/m at 900 kPa gives overlaps near half the superquadric's b.
12. Multi-seed variants: a check judges the mean over the seeds of its quantity (the range is in
    its name).
"""
from __future__ import annotations

import math

import numpy as np

from ..scene import Box, ContactModel, LinearLaw, Material, Outputs, Phase, Scene, Superquadrics, Wall
from .. import libm
from ..shapes import superquadric as sq
from .base import Case, CaseRun, Check

SRC = "Miyata §3.2"
G = 9.81
RHO = 1650.0          # Table 2 [kg/m³], unit depth
KN = 1.0e7            # Table 2, particle-particle, normal and tangential [N/m]
KN_WALL = 1.0e8       # Table 2, particle-wall, normal and tangential [N/m]
RESTITUTION = 0.01    # Table 2
MU = 0.51             # Table 2
DT = 1.7078e-4        # Table 2 [s]
PLATE_SPEED = 0.01    # Table 2 [m/s]
Z0 = 2.7              # §3.2 (2): sample height, trimming height [m]
ROUGH_A = 0.3         # eq 60 amplitude [m]
ROUGH_L = 2.0         # eq 60 wavelength [m]
REGIMES = (50e3, 250e3)  # §3.2 (3): initial 0-50 kPa, transition 50-250 kPa, final > 250 kPa
SHAPES = {"C": dict(a=0.15, b=0.15, n=2.0), "S": dict(a=0.195, b=0.0976, n=4.0)}  # Table 1
SAMPLES = ("CS", "CR", "SS", "SR")  # Table 1: shape (C circle, S superquadric) × surface (S smooth, R rough)
# blow-up guard: overlap / smaller semi-axis.  Table 2's k_n = 1e7 N/m at 900 kPa gives overlaps near half
# the superquadric's b (measured, reduced SS seed 1: 4.9 cm = 0.50 b at 860 kPa, where the default 0.5 stopped the
# run); the seed loaded to 900 kPa with the same stiffness, so its overlaps were as large: the guard is raised to 0.9
MAX_OVERLAP = 0.9
GROUPS = (0.4, 0.7)  # §3.2 (3), Fig. 30: first 40 %, 40-70 %, 70-100 % of the plate contacts formed


def _materials():
    return {"rock": Material(density=RHO), "wall": Material()}


def _laws(mu_particles: float):
    return {("rock", "rock"): LinearLaw(kn=KN, ks=KN, friction=mu_particles),
            ("rock", "wall"): LinearLaw(kn=KN_WALL, ks=KN_WALL, friction=MU)}


def floor_wall(W: float) -> Wall:
    """The floor: a wall along y = 0 longer than the box by 1 m on each side."""
    return Wall("floor", (0.0, 0.0), (1.0, 0.0), -1.0, W + 1.0, "wall")


def _scene(name, shape, x, y, th, W, mu_particles, walls) -> Scene:
    s = SHAPES[shape]
    n = len(x)
    return Scene(name=name,
                 discs=Superquadrics(x=np.asarray(x, float), y=np.asarray(y, float), a=np.full(n, s["a"]),
                                     b=np.full(n, s["b"]), n=np.full(n, s["n"]), material="rock",
                                     theta=np.asarray(th, float), restitution=RESTITUTION,
                                     max_overlap=MAX_OVERLAP),
                 materials=_materials(), laws=_laws(mu_particles), walls=walls,
                 contact_model=ContactModel(normal="overlap"), gravity=(0.0, -G), dt=DT,
                 box=Box(periodic_x=(0.0, W)), overlap_tolerance=0.5, outputs=Outputs(every=0))


def particle_count(W: float, p) -> int:
    """Particles inserted: the box filled to ``fill_height`` at packing fraction 0.85 (assumption 5)."""
    return int(math.ceil(W * p["fill_height"] * 0.85 / (math.pi * 0.15 ** 2)))


def insertion_scene(shape: str, W: float, seed: int, p) -> Scene:
    """Assumption 5: a loose lattice with a random offset per row, jitter and orientations."""
    rng = np.random.default_rng(seed)
    s = SHAPES[shape]
    rb = sq.bounding_radius(s["a"], s["b"], s["n"])
    sp = 2.0 * rb + 0.05
    nx = int(W // sp)
    N = particle_count(W, p)
    xs, ys = [], []
    row = 0
    while len(xs) < N:
        off = rng.uniform(0.0, W)
        for i in range(nx):
            if len(xs) < N:
                xs.append((off + (i + 0.5) * W / nx + rng.uniform(-0.01, 0.01)) % W)
                ys.append(rb + 0.02 + row * sp + rng.uniform(-0.01, 0.01))
        row += 1
    th = rng.uniform(0.0, math.pi, len(xs)) if shape == "S" else np.zeros(len(xs))
    mu = p["mu_deposit_circles"] if shape == "C" else MU
    return _scene(f"miyata-uniaxial-2d-{shape}-deposit", shape, xs, ys, th, W, mu, [floor_wall(W)])


def settle(sim, p, max_steps: int) -> int:
    """Run until the mean kinetic energy per particle is below settle_ke × m g r (assumption 7),
    checked every 1000 steps, at least 2000 steps.  Returns the steps run (negative: not settled)."""
    m = float(sim.bodies.mass.mean())
    lim = p["settle_ke"] * m * G * 0.15 * sim.n
    done = 0
    while done < max_steps:
        sim.run(1000)
        done += 1000
        if done >= 2000 and sim.kinetic_energy() < lim:
            return done
    return -done


def top_height(sim) -> float:
    """Highest point of any particle [m] (support function along +y)."""
    bd = sim.bodies
    h = [sq.support_point(math.sin(t), math.cos(t), a, b, n)[2] for t, a, b, n in zip(bd.th, bd.a, bd.b, bd.n)]
    return float(np.max(bd.y + np.array(h)))


def surface(x: np.ndarray, rough: bool) -> np.ndarray:
    """The trimming height: z0 (smooth) or eq 60, z0 + a sin(2πx/L) (rough) [m]."""
    return Z0 + (ROUGH_A * libm.sin(2.0 * math.pi * np.asarray(x) / ROUGH_L) if rough else 0.0)


def _state(sim, keep=None):
    bd = sim.bodies
    keep = np.arange(sim.n) if keep is None else keep
    return bd.x[keep].copy(), bd.y[keep].copy(), bd.th[keep].copy()


def current_contacts(sim):
    """The pair outputs (``sim.out``) of the current state.  A neighbour-list rebuild after a run's last
    step leaves ``sim.out`` zeroed (new list); the pass is then evaluated again on a copy of the
    contact history (the springs are not advanced) and the forces it sums are put back, so that
    looking does not change the run."""
    from ..simulation_sq2d import pair_pass

    if sim.finder.size == 0 or (sim.out.ovl > 0).any():
        return sim.out
    bd = sim.bodies
    keep = (bd.Fx.copy(), bd.Fy.copy(), bd.M.copy(), sim.walls.force.copy())
    pair_pass(bd, sim.finder, sim.other, sim.sx, sim.sy, sim.hist.copy(), sim.out, sim.walls, sim.law_params,
              sim.knobs, sim.dt, np.zeros(2, np.int64))
    bd.Fx[:], bd.Fy[:], bd.M[:], sim.walls.force[:] = keep
    return sim.out


def run_sample(bed, sample: str, W: float, p) -> dict:
    """Trim the deposited bed ``bed`` ((x, y, θ) of a settled bed), re-settle, load to stress_max.
    Returns the curve (a DataFrame), the final shares and the snapshots (see :class:`MiyataUniaxial2D`)."""
    import pandas as pd

    from ..build import build
    from ..contacts.neighbours import transfer_history

    shape, rough = sample[0], sample[1] == "R"
    x, y, th = bed
    keep = np.flatnonzero(y <= surface(x, rough))
    s2 = build(_scene(f"miyata-uniaxial-2d-{sample}-trimmed", shape, x[keep], y[keep], th[keep], W, MU, [floor_wall(W)]))
    steps2 = settle(s2, p, p["settle_max"])
    n = s2.n
    z_top = top_height(s2) + p["plate_gap"]
    plate = Wall("plate", (0.0, z_top), (1.0, 0.0), -1.0, W + 1.0, "wall",
                 phases=(Phase(cycles=10 ** 9, velocity=(0.0, -p["plate_speed"])),))
    x, y, th = _state(s2)
    s3 = build(_scene(f"miyata-uniaxial-2d-{sample}-loading", shape, x, y, th, W, MU, [floor_wall(W), plate]))
    s3.hist = transfer_history(s2.finder, s2.other, s2.hist, s3.finder, s3.other, n + 2)  # assumption 8
    th0 = s3.bodies.th.copy()
    bd0 = s3.bodies  # the state the loading starts from (what the engine decks of miyata-uniaxial-2d-engines start from)
    start = {k: getattr(bd0, k).copy() for k in ("x", "y", "th", "vx", "vy", "om", "mass", "inertia")}
    small = min(SHAPES[shape]["a"], SHAPES[shape]["b"])
    formed = {}  # particle → record index at which its current plate contact began
    rows, snaps = [], {}
    touched = None
    every = int(p["record_every"])
    rec = 0
    while True:
        s3.run(every)
        o = current_contacts(s3)
        on = o.ovl > 0
        fi, ot, fn = s3.finder[on], s3.other[on], o.fn[on]
        pl = ot == n + 1
        fl = ot == n
        plate_ids = fi[pl]
        alive = set(plate_ids.tolist())
        for k in list(formed):
            if k not in alive:
                del formed[k]
        for k in plate_ids.tolist():
            formed.setdefault(k, rec)
        stress = float(s3.walls.force[1, 1]) / W
        zp = float(s3.walls.py[1])
        if touched is None and stress > 0:
            touched = zp
        rows.append({"step": s3.step, "plate_y": zp, "settlement": 0.0 if touched is None else touched - zp,
                     "stress": stress, "floor_stress": -float(s3.walls.force[0, 1]) / W,
                     "plate_contacts": int(pl.sum()), "floor_contacts": int(fl.sum()),
                     "max_overlap": float(o.ovl[on].max()) / small if on.any() else 0.0,
                     "contacts": int((ot < n).sum())})
        for level in (REGIMES[0], REGIMES[1]):
            if level not in snaps and stress >= level:
                snaps[level] = {"th": s3.bodies.th.copy(), "x": s3.bodies.x.copy(), "y": s3.bodies.y.copy(),
                                "stress": stress}
        rec += 1
        if stress >= p["stress_max"] or rec * every > p["loading_max"]:
            break
    curve = pd.DataFrame(rows)
    # Fig. 30: plate contacts alive now, ranked by formation (assumption 9)
    ids = np.array(sorted(formed, key=lambda k: (formed[k], k)), dtype=np.int64)
    f_of = dict(zip(plate_ids.tolist(), fn[pl].tolist()))
    forces = np.array([f_of[k] for k in ids])
    m = len(ids)
    cut = [int(round(GROUPS[0] * m)), int(round(GROUPS[1] * m))]
    total = float(forces.sum()) if m else 0.0
    shares = [float(forces[a:b].sum()) / total if total > 0 else math.nan
              for a, b in ((0, cut[0]), (cut[0], cut[1]), (cut[1], m))]
    formed_stress = [float(curve.stress.iloc[formed[ids[c]]]) if 0 < c < m else math.nan for c in cut]
    bd = s3.bodies
    final = {"x": bd.x.copy(), "y": bd.y.copy(), "th": bd.th.copy(), "a": bd.a.copy(), "b": bd.b.copy(),
             "n": bd.n.copy(), "contacts": (current_contacts(s3), s3.contacts())[1], "n_particles": n, "stress": rows[-1]["stress"]}
    return {"curve": curve, "shares": shares, "plate_contacts_final": m, "formed_stress": formed_stress,
            "th0": th0, "snaps": snaps, "final": final, "settle_steps": steps2, "n_particles": n,
            "plate_start": z_top, "weight": float(s2.bodies.mass.sum()) * G, "start": start}


def run_shape(shape: str, W: float, seed: int, p, samples=SAMPLES) -> dict:
    """Deposit one bed of ``shape`` and run its samples (smooth and rough) from it."""
    from ..build import build

    s1 = build(insertion_scene(shape, W, seed, p))
    steps1 = settle(s1, p, p["deposit_max"])
    out = {}
    for sample in samples:
        if sample[0] == shape:
            out[sample] = run_sample(_state(s1), sample, W, p)
            out[sample]["deposit_steps"] = steps1
    return out


# ----------------------------------------------------------------------------------------- analysis
def at_stress(curve, level: float, col: str = "settlement") -> float:
    """``col`` where the plate stress first reaches ``level`` (linear between records); nan if never."""
    s = curve.stress.to_numpy()
    k = np.flatnonzero(s >= level)
    if not k.size:
        return math.nan
    k = int(k[0])
    if k == 0:
        return float(curve[col].iloc[0])
    s0, s1 = s[k - 1], s[k]
    v0, v1 = float(curve[col].iloc[k - 1]), float(curve[col].iloc[k])
    return v0 + (v1 - v0) * (level - s0) / (s1 - s0)


def stress_drops(curve, threshold: float, start: float = REGIMES[1]) -> list[tuple[float, float, float]]:
    """Stress drops in the final regime (assumption 10): each fall of the plate stress below (1 -
    threshold) × its running maximum, after it first reached ``start``.  Returns (settlement [m],
    stress before [Pa], stress after [Pa]) per drop (the running maximum restarts after a drop)."""
    s = curve.stress.to_numpy()
    d = curve.settlement.to_numpy()
    k0 = np.flatnonzero(s >= start)
    out = []
    if not k0.size:
        return out
    peak, kp = s[k0[0]], k0[0]
    low = None
    for k in range(int(k0[0]), len(s)):
        if low is None:
            if s[k] >= peak:
                peak, kp = s[k], k
            elif s[k] < (1.0 - threshold) * peak:
                low = k
        else:
            if s[k] < s[low]:
                low = k
            else:  # the drop has ended: record it, the running maximum restarts
                out.append((float(d[kp]), float(peak), float(s[low])))
                peak, kp, low = s[k], k, None
    if low is not None:
        out.append((float(d[kp]), float(peak), float(s[low])))
    return out


def largest_fall(curve, start: float = REGIMES[1]) -> float:
    """Largest fall of the plate stress below its running maximum, relative to that maximum, after the
    stress first reached ``start`` (0: it never fell)."""
    s = curve.stress.to_numpy()
    k = np.flatnonzero(s >= start)
    if not k.size:
        return 0.0
    s = s[int(k[0]):]
    run_max = np.maximum.accumulate(s)
    return float(np.max(1.0 - s / run_max))


def regime_stiffness(curve) -> tuple[float, float, float, float]:
    """Secant stiffness dσ/ds [Pa/m] of the initial (0-50 kPa), transition (50-250 kPa) regimes and of
    the first and second halves (by settlement) of the final regime (250 kPa to the end)."""
    s50, s250 = at_stress(curve, REGIMES[0]), at_stress(curve, REGIMES[1])
    k1 = REGIMES[0] / s50 if s50 > 0 else math.inf
    k2 = (REGIMES[1] - REGIMES[0]) / (s250 - s50) if s250 > s50 else math.inf
    end_s, end_sig = float(curve.settlement.iloc[-1]), float(curve.stress.iloc[-1])
    mid = 0.5 * (s250 + end_s)
    sig_mid = float(np.interp(mid, curve.settlement.to_numpy(), curve.stress.to_numpy()))
    k3a = (sig_mid - REGIMES[1]) / (mid - s250) if mid > s250 else math.nan
    k3b = (end_sig - sig_mid) / (end_s - mid) if end_s > mid else math.nan
    return k1, k2, k3a, k3b


def final_slope(curve) -> float:
    """Least-squares slope dσ/ds [Pa/m] of the final regime (stress > 250 kPa)."""
    on = curve[curve.stress >= REGIMES[1]]
    if len(on) < 3:
        return math.nan
    return float(np.polyfit(on.settlement.to_numpy(), on.stress.to_numpy(), 1)[0])


def contact_ratio(curve) -> np.ndarray:
    """Plate contacts / floor contacts per record (Fig. 29)."""
    return curve.plate_contacts.to_numpy() / np.maximum(curve.floor_contacts.to_numpy(), 1)


def ratio_rates(curve) -> tuple[float, float, float]:
    """Mean rise of the contact ratio per 100 kPa in the initial, transition and final regimes."""
    r = contact_ratio(curve)
    s = curve.stress.to_numpy()
    end = float(s[-1])

    def ratio_at(level):
        if level <= 0:
            return 0.0
        k = np.flatnonzero(s >= level)
        return float(r[k[0]]) if k.size else math.nan

    marks = (0.0, REGIMES[0], REGIMES[1], end)
    return tuple((ratio_at(b) - ratio_at(a)) / ((b - a) / 1e5) for a, b in zip(marks[:-1], marks[1:]))


def sample_values(r: dict, p) -> dict:
    """The numbers the checks judge, for one sample and seed."""
    from ..tolerances import tol

    c = r["curve"]
    k1, k2, k3a, k3b = regime_stiffness(c)
    fl = c.floor_contacts.to_numpy()[c.stress.to_numpy() > 0]
    rates = ratio_rates(c)
    ratio = contact_ratio(c)
    s = c.stress.to_numpy()
    weight = r["weight"] / p["width"]
    last = c.iloc[-1]
    return {"k_transition/k_initial": k2 / k1, "final stiffness change": k3b / k3a - 1.0,
            "drops": len(stress_drops(c, tol("miyata2d.stress-drop").value)),
            "settlement 50 kPa": at_stress(c, REGIMES[0]), "settlement 250 kPa": at_stress(c, REGIMES[1]),
            "final slope": final_slope(c), "ratio rate initial": rates[0], "ratio rate transition": rates[1],
            "ratio rate final": rates[2],
            "ratio 50 kPa": float(ratio[np.flatnonzero(s >= REGIMES[0])[0]]) if (s >= REGIMES[0]).any() else math.nan,
            "ratio 250 kPa": float(ratio[np.flatnonzero(s >= REGIMES[1])[0]]) if (s >= REGIMES[1]).any() else math.nan,
            "floor contacts spread": float((fl.max() - fl.min()) / fl.mean()) if fl.size else math.nan,
            "floor contacts mean": float(fl.mean()) if fl.size else 0.0, "largest fall": largest_fall(c),
            "contacts 250 kPa": at_stress(c, REGIMES[1], "contacts") if "contacts" in c else math.nan,
            "contacts final": float(c.contacts.iloc[-1]) if "contacts" in c else math.nan,
            "share initial": r["shares"][0], "share transition": r["shares"][1], "share final": r["shares"][2],
            "share early": r["shares"][0] + r["shares"][1],
            "balance": abs(float(last.floor_stress - last.stress) - weight) / float(last.stress),
            "final stress": float(last.stress), "plate contacts final": r["plate_contacts_final"]}


# Statements the reduced variant (2 m box, one seed) does not reproduce, and why (measured 2026-11-24 on its
# seed 1 with the default parameters; the numbers in braces are filled from the run).  The full variant
# judges them as conditions.
REDUCED_MISSES = {
    "final-linear": "Circles in the 2 m box, final regime: stiffness change {change:+.0%} between its halves (the "
                    "superquadrics here: {sq_changes}); measured on seed 1 with the defaults: +46 % (CS), +67 % (CR), "
                    "the circles stiffening: with Table 2's k_n = 1e7 N/m the overlaps reach {overlap:.2f} r at the "
                    "final stress and the bed gains contacts as it is squeezed ({c250:.0f} particle contacts at "
                    "250 kPa, {cend:.0f} at the end; measured with the defaults: circles 108 → 125 (CS) and 105 → 119 "
                    "(CR), +13-16 %, superquadrics 124 → 133 and 125 → 133, +6-7 %), in a bed of ~60 circles close "
                    "to a hexagonal crystal (the rows of the rotation map). A box effect in part: in a 4 m box "
                    "(--set width=4, seed 1, measured) CS's final regime is linear (-3 %), CR's still stiffens "
                    "(+68 %).",
    "drops": "One 2 m box and one seed: {drops:.0f} fall(s) above the threshold; the largest fall of the stress "
             "below its running maximum in the final regime is {fall:.1%}. In this variant CS (smooth) shows none "
             "and CR (rough, the same deposited bed) one: a drop is a rare event in ~60 circles under 5 plate "
             "contacts; the 10 m box with 8 seeds (variant=full) is the test. In a 4 m box (--set width=4, seed 1, "
             "measured) CS again shows none and CR two.",
}

VARIANTS = {"reduced": dict(width=2.0, n_seeds=1, plate_speed=0.1),
            "full": dict(width=10.0, n_seeds=8, plate_speed=PLATE_SPEED)}


class MiyataUniaxial2D(Case):
    name = "miyata-uniaxial-2d"
    title = "Uniaxial compression of circles and n = 4 superquadrics (Miyata §3.2, Figs 26, 29, 30)"
    source = SRC
    assumptions = (
        "Reduced variant (the default): the seed's particles, Table 2 parameters, bed depth and eq 60 surfaces in a "
        "2 m wide periodic box (one wavelength of eq 60, about 60 particles after trimming) instead of 10 m, one seed, "
        "and the plate at 0.1 m/s instead of 0.01 m/s (inertial number I = (v/H) d √(ρ/σ) ≈ 2e-3 at 50 kPa: "
        "quasi-static; the force balance check measures it); `--set variant=full`: 10 m, 0.01 m/s, 8 seeds (slow).",
        "All four samples run on demflow's superquadric cycle, circles as n = 2, a = b = 15 cm (Table 1: 'circular "
        "(n=2)').",
        "Miyata eq 13 (N = k_n δ) with an incremental shear spring and Coulomb limit; the eq 17 normal dashpot from "
        "e = 0.01 with the pair's effective mass (the particle's mass at a wall); no shear dashpot, no global damping.",
        "μ = 0.51 at the walls too (Table 2 does not say).",
        "Circles are deposited with μ = mu_deposit_circles = 1.0: the seed uses an unstated friction 'when circular "
        "particles are randomly sedimented in order to make disordered samples'; frictionless deposition crystallised "
        "(measured, 2 m box: a hexagonal bed, 6 floor contacts per row, a stress-settlement curve linear from the "
        "first contact with 2 plate contacts up to 250 kPa), the opposite of the seed's purpose.",
        "Insertion (Fig. 24(a) lost): a loose lattice with a random offset per row, jitter and, for superquadrics, "
        "random orientations (seeded), the same count for both shapes (equal masses), enough to fill 3.2 m at "
        "packing fraction 0.85; CS/CR (SS/SR) are trimmed from one deposited bed per seed.",
        "Settled: mean kinetic energy per particle below settle_ke × m g r; the plate starts 5 mm above the top; "
        "settlement counted from its first contact; contact springs carry into the loading stage.",
        "Blow-up guard raised to overlaps of 0.9 × the smaller semi-axis: Table 2's k_n = 1e7 N/m at 900 kPa gives "
        "overlaps of about half the superquadric's b (measured 4.9 cm = 0.50 b at 860 kPa, reduced SS seed 1).",
        "Seeds: with several seeds a check judges the mean over the seeds (the range is in its name).",
        "Fig. 30 groups: the plate contacts alive at the final stress ranked by when their unbroken contact began; "
        "first 40 %, next 30 %, last 30 % (the seed's 'first 40 % of the contact points newly created').",
        "A stress drop: the plate stress falling below its running maximum by more than the tolerance "
        "miyata2d.stress-drop in the final regime (> 250 kPa); 'almost linear' final regime: the secant stiffness "
        "of its second half within miyata2d.final-linear of its first half; 'parallel' smooth and rough final "
        "regimes: least-squares slopes within miyata2d.parallel.",
    )
    params = dict(variant="reduced", samples="CS,CR,SS,SR", seed=1, n_seeds=0, width=0.0, plate_speed=0.0,
                  fill_height=3.2, mu_deposit_circles=1.0, settle_ke=1e-6, deposit_max=100000, settle_max=60000,
                  plate_gap=0.005, record_every=50, stress_max=900e3, loading_max=2000000)

    @staticmethod
    def resolved(p) -> dict:
        """The parameters with the variant's width, seeds and plate speed where not given (0: the variant's)."""
        if p["variant"] not in VARIANTS:
            raise KeyError(f"variant {p['variant']!r} is not one of {sorted(VARIANTS)}")
        q = dict(p)
        for k, v in VARIANTS[p["variant"]].items():
            if not q[k]:
                q[k] = v
        q["width"], q["plate_speed"], q["n_seeds"] = float(q["width"]), float(q["plate_speed"]), int(q["n_seeds"])
        if abs(q["width"] / ROUGH_L - round(q["width"] / ROUGH_L)) > 1e-9:
            raise ValueError(f"width={q['width']} is not a whole number of eq 60 wavelengths ({ROUGH_L} m): the rough "
                             "surface must be periodic")
        return q

    def run(self, p) -> CaseRun:
        import time

        q = self.resolved(p)
        samples = tuple(s for s in q["samples"].split(",") if s)
        out = {s: {} for s in samples}
        timing = {}
        for shape in ("C", "S"):
            mine = tuple(s for s in samples if s[0] == shape)
            if not mine:
                continue
            for k in range(q["n_seeds"]):
                seed = q["seed"] + k
                t = time.perf_counter()
                res = run_shape(shape, q["width"], seed, q, mine)
                timing[(shape, seed)] = time.perf_counter() - t
                for s, r in res.items():
                    out[s][seed] = r
        return CaseRun({}, {"samples": out, "params": q, "timing": timing})

    # ------------------------------------------------------------------------------------- checks
    @staticmethod
    def _values(run) -> dict:
        q = run.extras["params"]
        return {s: {seed: sample_values(r, q) for seed, r in by_seed.items()}
                for s, by_seed in run.extras["samples"].items()}

    def checks(self, run, p):
        from ..tolerances import tol

        q = run.extras["params"]
        V = self._values(run)
        out = []
        a_s, b_s = SHAPES["S"]["a"], SHAPES["S"]["b"]
        ratio = sq.area(a_s, b_s, 4.0) / (math.pi * 0.15 ** 2)
        out.append(Check.against("Table 1: superquadric mass / circle mass (a = 19.5 cm, b = 9.76 cm, n = 4 vs "
                                 "r = 15 cm)", ratio, 1.0, "miyata2d.equal-mass", SRC + " (2), Table 1"))
        m = RHO * math.pi * 0.15 ** 2
        out.append(Check.info("Table 2: Δt / √(m/k_wall) (circle mass, k = 1e8 N/m)", DT / math.sqrt(m / KN_WALL),
                              SRC + ", Table 2", "The seed's Δt against the stiffest contact's time scale "
                              "(critical: 2; demflow's safe packing estimate: 0.333)."))

        def mean(s, key):
            vals = np.array([v[key] for v in V[s].values()], dtype=float)
            return float(np.mean(vals)), vals

        def label(s, key, fmt="{:.3g}"):
            v, vals = mean(s, key)
            if len(vals) == 1:
                return f"{s} seed {next(iter(V[s]))}", v
            return f"{s} seeds {min(V[s])}-{max(V[s])} mean (range {fmt.format(vals.min())}-{fmt.format(vals.max())})", v

        n_min = tol("miyata2d.min-contacts").value

        def cond(name, ok, value, tname, src=SRC + " (3)", count=None):
            """A condition; a miss instead when it rests on ``count`` = (contacts, what) below n_min."""
            if count is not None and count[0] < n_min:
                out.append(Check.miss(name, value, value, src, f"Not resolved by this variant: {count[1]} "
                                      f"{count[0]:.3g} < {n_min:.0f} contacts (the smallest over its seeds), so each "
                                      f"contact moves the quantity by about 1/{count[0]:.3g}; the statement is judged "
                                      "in a wider box (variant=full). " + tol("miyata2d.min-contacts").why,
                                      relative=False))
            else:
                out.append(Check.condition(name, bool(ok), value, src, tol(tname).why, kind=tol(tname).kind))

        def fewest(s, key):
            return float(min(v[key] for v in V[s].values()))

        drop = tol("miyata2d.stress-drop").value
        reduced = q.get("variant") == "reduced" and q.get("width") == VARIANTS["reduced"]["width"]
        for s in V:
            who, v = label(s, "k_transition/k_initial")
            cond(f"Fig. 26 {who}: secant stiffness 50-250 kPa / 0-50 kPa > 1 (large settlement at low stress, then "
                 "a stiffer response)", v > tol("miyata2d.regimes").value, v, "miyata2d.regimes")
            who, v = label(s, "final stiffness change")
            lim = tol("miyata2d.final-linear").value
            name = (f"Fig. 26 {who}: final regime (> 250 kPa) almost linear: stiffness change between its halves "
                    f"within ±{lim:.0%}")
            if reduced and s[0] == "C":  # not reproduced by the reduced variant: REDUCED_MISSES
                c250, cend = mean(s, "contacts 250 kPa")[0], mean(s, "contacts final")[0]
                out.append(Check.miss(name, v, 0.0, SRC + " (3)", REDUCED_MISSES["final-linear"].format(
                    change=v, overlap=max(float(r["curve"].max_overlap.max()) for r in run.extras["samples"][s].values()),
                    c250=c250, cend=cend, sq_changes=", ".join(f"{x}: {mean(x, 'final stiffness change')[0]:+.0%}"
                                                               for x in ("SS", "SR") if x in V) or "not run"),
                    relative=False))
            else:
                cond(name, abs(v) <= lim, v, "miyata2d.final-linear")
            who, v = label(s, "drops")
            if s[0] == "C":
                name = (f"Fig. 26 {who}: stress drops (> {drop:.0%} of the running maximum) in the final regime: at "
                        "least one (circles)")
                if reduced:
                    out.append(Check.miss(name, v, 1.0, SRC + " (3)", REDUCED_MISSES["drops"].format(
                        drops=v, fall=mean(s, "largest fall")[0]), relative=False))
                else:
                    cond(name, v >= 1, v, "miyata2d.stress-drop")
            else:
                cond(f"Fig. 26 {who}: stress drops (> {drop:.0%} of the running maximum) in the final regime: none "
                     "(superquadrics)", v == 0, v, "miyata2d.stress-drop")
            who, v = label(s, "floor contacts spread")
            lim = tol("miyata2d.floor-constant").value
            cond(f"Fig. 29 {who}: floor contacts almost constant during loading: (max - min)/mean within {lim:.0%}",
                 v <= lim, v, "miyata2d.floor-constant")
            r1, r2, r3 = (mean(s, k)[0] for k in ("ratio rate initial", "ratio rate transition", "ratio rate final"))
            cond(f"Fig. 29 {label(s, 'ratio rate initial')[0]}: plate/floor contact ratio rises fastest in the initial "
                 f"regime, slower in the transition, slowest in the final (per 100 kPa: {r1:.3g}, {r2:.3g}, {r3:.3g})",
                 r1 > r2 > r3, r1, "miyata2d.ratio-rates",
                 count=(fewest(s, "floor contacts mean"), "floor contacts (the ratio's denominator)"))
            who, v = label(s, "share early")
            lim = tol("miyata2d.share-early").value
            cond(f"Fig. 30 {who}: load share of the contacts formed in the initial and transition states "
                 f"(first 70 %) > {lim:.0%}", v > lim, v, "miyata2d.share-early", count=(fewest(s, "plate contacts final"), "plate contacts at the final stress"))
            who, v = label(s, "share final")
            lim = tol("miyata2d.share-final").value
            cond(f"Fig. 30 {who}: load share of the contacts formed in the final state (last 30 %) <= {lim:.0%}",
                 v <= lim, v, "miyata2d.share-final", count=(fewest(s, "plate contacts final"), "plate contacts at the final stress"))
            if s[0] == "S":
                who, v = label(s, "share initial")
                lim = tol("miyata2d.share-initial-sq").value
                cond(f"Fig. 30 {who}: load share of the contacts formed in the initial state (first 40 %) > "
                     f"{lim:.0%} (superquadrics)", v > lim, v, "miyata2d.share-initial-sq", count=(fewest(s, "plate contacts final"), "plate contacts at the final stress"))
                who, v = label(s, "share final")
                lim = tol("miyata2d.share-final-sq").value
                cond(f"Fig. 30 {who}: load share of the contacts formed in the final state < {lim:.0%} "
                     "(superquadrics)", v < lim, v, "miyata2d.share-final-sq", count=(fewest(s, "plate contacts final"), "plate contacts at the final stress"))
            who, v = label(s, "balance")
            out.append(Check.against(f"{who}: floor - plate stress = bed weight / width at the final stress "
                                     "(quasi-static loading), error / final stress", v, 0.0, "miyata2d.quasi-static",
                                     SRC + " (1)"))
            out.append(Check.info(f"{label(s, 'settlement 50 kPa')[0]}: settlement at 50 kPa [m]",
                                  mean(s, "settlement 50 kPa")[0], SRC, "End of the initial state (Fig. 26)."))
            out.append(Check.info(f"{label(s, 'settlement 250 kPa')[0]}: settlement at 250 kPa [m]",
                                  mean(s, "settlement 250 kPa")[0], SRC, "End of the transition state (Fig. 26)."))
            out.append(Check.info(f"{label(s, 'plate contacts final')[0]}: plate contacts at the final stress",
                                  mean(s, "plate contacts final")[0], SRC, "The Fig. 30 groups split these 40/30/30; "
                                  "few contacts make the shares coarse (one contact of 5 is 20 %)."))
            where = "; ".join(f"seed {seed}: " + (", ".join(f"{1e3 * d:.0f} mm ({a / 1e3:.0f} → {b / 1e3:.0f} kPa)"
                                                          for d, a, b in stress_drops(r["curve"], drop)) or "none")
                              for seed, r in run.extras["samples"][s].items())
            out.append(Check.info(f"{s}: stress drops located (settlement, stress before → after)",
                                  mean(s, "drops")[0], SRC, f"Falls > {drop:.0%} below the running maximum in the "
                                  f"final regime: {where}."))
            mo = max(float(r["curve"].max_overlap.max()) for r in run.extras["samples"][s].values())
            out.append(Check.info(f"{s}: largest overlap during loading / smaller semi-axis", mo, SRC + ", Table 2",
                                  "k_n = 1e7 N/m at 900 kPa: overlaps of tens of per cent of the particle (the "
                                  "blow-up guard is MAX_OVERLAP)."))
        # smooth vs rough (the same shape)
        for shape in ("C", "S"):
            sm, ro = shape + "S", shape + "R"
            if sm not in V or ro not in V:
                continue
            a, b = mean(sm, "settlement 250 kPa")[0], mean(ro, "settlement 250 kPa")[0]
            cond(f"Fig. 26 {ro} vs {sm}: larger settlement through the initial and transition states (at 250 kPa: "
                 f"{b:.3g} vs {a:.3g} m)", b > a, b / a, "miyata2d.rough-settles-more")
            ka, kb = mean(sm, "final slope")[0], mean(ro, "final slope")[0]
            lim = tol("miyata2d.parallel").value
            cond(f"Fig. 26 {ro} vs {sm}: final regimes parallel: least-squares slopes within ±{lim:.0%} "
                 f"({kb / 1e6:.3g} vs {ka / 1e6:.3g} MPa/m)", abs(kb / ka - 1.0) <= lim, kb / ka - 1.0,
                 "miyata2d.parallel")
            for level, key in ((50, "ratio 50 kPa"), (250, "ratio 250 kPa")):
                a, b = mean(sm, key)[0], mean(ro, key)[0]
                cond(f"Fig. 29 {ro} vs {sm}: fewer plate contacts (per floor contact) at {level} kPa ({b:.3g} vs "
                     f"{a:.3g})", b < a, b - a, "miyata2d.rough-fewer-contacts",
                     count=(min(fewest(sm, "floor contacts mean"), fewest(ro, "floor contacts mean")),
                            "floor contacts (the ratio's denominator)"))
        for surf in ("S", "R"):
            c, s_ = "C" + surf, "S" + surf
            if c in V and s_ in V:
                out.append(Check.info(f"Fig. 29 {s_} / {c}: contact ratio at 250 kPa (the seed: the shape's effect "
                                      "is inconclusive)", mean(s_, "ratio 250 kPa")[0] / mean(c, "ratio 250 kPa")[0],
                                      SRC, "No statement to check: shown."))
        return out

    # ------------------------------------------------------------------------------------- report
    def tables(self, run, p):
        import pandas as pd

        q = run.extras["params"]
        rows = []
        for s, by_seed in run.extras["samples"].items():
            for seed, r in by_seed.items():
                v = sample_values(r, q)
                c = r["curve"]
                rows.append({"sample": s, "seed": seed, "particles": r["n_particles"],
                             "deposit, re-settle steps": f"{r['deposit_steps']}, {r['settle_steps']}",
                             "loading steps": int(c.step.iloc[-1]), "final stress [kPa]": v["final stress"] / 1e3,
                             "settlement at 50 / 250 kPa / end [mm]": f"{1e3 * v['settlement 50 kPa']:.0f} / "
                             f"{1e3 * v['settlement 250 kPa']:.0f} / {1e3 * float(c.settlement.iloc[-1]):.0f}",
                             "stress drops": v["drops"], "plate contacts at the end": v["plate contacts final"],
                             "load share initial / transition / final [%]":
                             f"{100 * v['share initial']:.0f} / {100 * v['share transition']:.0f} / "
                             f"{100 * v['share final']:.0f}"})
        t = pd.DataFrame(rows)
        timing = pd.DataFrame([{"shape": k[0], "seed": k[1], "wall time [s] (deposit + its samples)": round(v, 1)}
                               for k, v in run.extras["timing"].items()])
        return [(f"Samples ({q['variant']} variant: {q['width']:g} m wide, plate {q['plate_speed']:g} m/s)", t),
                ("Run time", timing)]

    def figures(self, run, p, outdir):
        import matplotlib.pyplot as plt

        from ..plotting import save_figure
        from ..tolerances import tol

        S = run.extras["samples"]
        colors = {"CS": "k", "CR": "tab:blue", "SS": "tab:red", "SR": "tab:orange"}
        paths = []
        # Fig. 26: stress-settlement, regimes, drops
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        for s, by_seed in S.items():
            for k, (seed, r) in enumerate(by_seed.items()):
                c = r["curve"]
                ax.plot(c.settlement * 1e3, c.stress / 1e3, "-", color=colors.get(s, "0.5"), lw=1.2 if k == 0 else 0.5,
                        label=s if k == 0 else None)
                d = stress_drops(c, tol("miyata2d.stress-drop").value)
                if d:
                    ax.plot([1e3 * x for x, _, _ in d], [y / 1e3 for _, y, _ in d], "v", color=colors.get(s, "0.5"),
                            ms=6, mfc="none")
        for level in REGIMES:
            ax.axhline(level / 1e3, color="0.7", lw=0.8, ls="--")
        ax.set_xlabel("settlement of the plate [mm]")
        ax.set_ylabel("vertical stress on the plate [kPa]")
        ax.set_title("Stress-settlement (Miyata Fig. 26); ▽ stress drops")
        ax.legend()
        paths.append(save_figure(fig, f"{outdir}/stress_settlement.png"))
        # Fig. 29: contact ratio
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        for s, by_seed in S.items():
            for k, (seed, r) in enumerate(by_seed.items()):
                c = r["curve"]
                ax.plot(c.stress / 1e3, contact_ratio(c), "-", color=colors.get(s, "0.5"), lw=1.2 if k == 0 else 0.5,
                        label=s if k == 0 else None, drawstyle="steps-post")
        for level in REGIMES:
            ax.axvline(level / 1e3, color="0.7", lw=0.8, ls="--")
        ax.set_xlabel("vertical stress on the plate [kPa]")
        ax.set_ylabel("plate contacts / floor contacts")
        ax.set_title("Contacts on the plate (Miyata Fig. 29)")
        ax.legend()
        paths.append(save_figure(fig, f"{outdir}/contact_ratio.png"))
        # Fig. 30: load shares
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        names = list(S)
        for g, (label, col) in enumerate((("initial (first 40 %)", "0.2"), ("transition (40-70 %)", "0.55"),
                                          ("final (last 30 %)", "0.85"))):
            vals = [np.mean([r["shares"][g] for r in S[s].values()]) * 100 for s in names]
            ax.bar(np.arange(len(names)) + (g - 1) * 0.27, vals, 0.27, color=col, edgecolor="k", label=label)
        for y, txt in ((40, "equal share: 40 / 30 / 30 %"), (30, None)):
            ax.axhline(y, color="tab:green", lw=0.8, ls=":", label=txt)
        ax.axhline(20, color="tab:red", lw=0.8, ls="--", label="seed: final <= 20 % (SS, SR < 15 %)")
        ax.set_xticks(np.arange(len(names)), names)
        ax.set_ylabel("share of the final plate load [%]")
        ax.set_title(f"Load carried by the contacts formed in each state (Miyata Fig. 30), "
                     f"{run.extras['params']['stress_max'] / 1e3:.0f} kPa", fontsize=9)
        ax.set_ylim(0, 100)
        ax.legend(fontsize=7, loc="upper left", ncol=2)
        paths.append(save_figure(fig, f"{outdir}/load_shares.png"))
        # bonus: rotations (Fig. 28) and force chains (Fig. 27) of the smooth samples, first seed
        smooth = [s for s in ("CS", "SS") if s in S]
        if smooth:
            from matplotlib.collections import LineCollection, PolyCollection

            fig, axes = plt.subplots(len(smooth), 3, figsize=(13, 3.2 * len(smooth)), squeeze=False)
            for row, s in enumerate(smooth):
                r = next(iter(S[s].values()))
                f = r["final"]
                panels = []
                sn = r["snaps"]
                if REGIMES[0] in sn:
                    panels.append(("rotation 0-50 kPa", sn[REGIMES[0]], np.abs(sn[REGIMES[0]]["th"] - r["th0"])))
                if REGIMES[0] in sn and REGIMES[1] in sn:
                    panels.append(("rotation 50-250 kPa", sn[REGIMES[1]],
                                   np.abs(sn[REGIMES[1]]["th"] - sn[REGIMES[0]]["th"])))
                for col in range(2):
                    ax = axes[row, col]
                    if col < len(panels):
                        title, st, rot = panels[col]
                        polys = [sq.outline(a, b, n, t, 48) + (x, y) for x, y, t, a, b, n in
                                 zip(st["x"], st["y"], st["th"], f["a"], f["b"], f["n"])]
                        pc = PolyCollection(polys, array=rot, cmap="Greys", edgecolors="0.5", linewidths=0.3)
                        ax.add_collection(pc)
                        fig.colorbar(pc, ax=ax, label="|Δθ| [rad]")
                        ax.set_title(f"{s}: {title} (Fig. 28)", fontsize=9)
                    ax.set_aspect("equal")
                    ax.autoscale()
                ax = axes[row, 2]
                polys = [sq.outline(a, b, n, t, 48) + (x, y) for x, y, t, a, b, n in
                         zip(f["x"], f["y"], f["th"], f["a"], f["b"], f["n"])]
                ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors="0.6", linewidths=0.3))
                ct = f["contacts"]
                segs, widths = [], []
                fmax = float(ct["fn"].max()) if len(ct["fn"]) else 1.0
                for i, j, cx, cy, fn in zip(ct["i"], ct["j"], ct["cpx"], ct["cpy"], ct["fn"]):
                    for k in (i, j):
                        if k < f["n_particles"] and abs(f["x"][k] - cx) < 0.5:
                            segs.append(((f["x"][k], f["y"][k]), (cx, cy)))
                            widths.append(0.2 + 3.0 * fn / fmax)
                ax.add_collection(LineCollection(segs, linewidths=widths, colors="k"))
                ax.set_aspect("equal")
                ax.autoscale()
                ax.set_title(f"{s}: contact forces at {f['stress'] / 1e3:.0f} kPa (Fig. 27)", fontsize=9)
            paths.append(save_figure(fig, f"{outdir}/rotations_force_chains.png"))
        return paths
