"""Micro-mechanical averages of one snapshot: coordination number, fabric tensor, average stress.

Works on any engine's :class:`~demflow.results.Results` (common tables only):

- contacts: step, i, j, wall, px, py, nx, ny, fn, fs (j = -1 for disc-wall; n from i towards
  j / the wall; force on i = -(fn n + fs t) with t = (ny, -nx), the demflow convention
  (contacts/forces.py; the LIGGGHTS adapter converts to it)
- particles: step, id, x, y, radius

Contacts count as *active* when |fn| > tol (tol = 0: every row that carries a normal force;
rows with fn = 0 are touching-but-unloaded or listed-but-apart and are ignored). Each pair is
assumed to be listed once per snapshot (as every engine adapter writes it).
2D, unit thickness: the "volume" of ch3 eq 3.17 is an area A [length²] times 1, so stresses are
force per length [force/length].
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..schema import contact_force_on_i
from .forces import snapshot_steps


def _one_step(table: pd.DataFrame, step):
    s = snapshot_steps(table, step)
    if s.size != 1:
        raise ValueError("these averages are per snapshot: give one step (or None for the last)")
    return s[0]


def _tables(data, particles=None):
    contacts = data.contacts if hasattr(data, "contacts") else data
    if particles is None and hasattr(data, "particles"):
        particles = data.particles
    return contacts, particles


def _active(contacts, step, tol, include_walls=True):
    c = contacts[contacts["step"] == step]
    c = c[np.abs(c["fn"].to_numpy(dtype=float)) > tol]
    if not include_walls:
        c = c[c["j"].to_numpy() >= 0]
    return c


# ----------------------------------------------------------------------------- coordination
@dataclass
class Coordination:
    """Coordination numbers of one snapshot (2D discs).

    z                  = 2 C_pp / N                 disc-disc contacts only, every disc
    z_walls            = (2 C_pp + C_pw) / N        disc-wall contacts count once (for the disc)
    z_no_rattlers      = 2 C'_pp / (N - N_r)        rattlers and their contacts removed
    z_no_rattlers_walls= (2 C'_pp + C'_pw) / (N - N_r)

    Rattlers: discs with fewer than ``min_contacts`` active contacts (wall contacts included),
    removed iteratively (removing one may turn its neighbours into rattlers).
    """

    n_particles: int
    n_contacts: int  # active disc-disc contacts C_pp
    n_wall_contacts: int  # active disc-wall contacts C_pw
    n_rattlers: int
    z: float
    z_walls: float
    z_no_rattlers: float
    z_no_rattlers_walls: float
    per_particle: pd.Series  # id -> number of active contacts (walls included)
    rattlers: np.ndarray  # ids


def coordination_number(data, step=None, particles=None, tol=0.0, min_contacts=2) -> Coordination:
    """Coordination numbers (contacts per disc) of one snapshot; see :class:`Coordination`.

    ``data``: Results, or a contacts table (then ``particles`` gives the discs; without it, the
    discs are those appearing in the contacts, which misses discs without any contact).
    ``min_contacts``: rattler threshold (2 for frictional discs; 3 is usual for frictionless).
    """
    contacts, parts = _tables(data, particles)
    st = _one_step(contacts, step)
    c = _active(contacts, st, tol)
    i = c["i"].to_numpy()
    j = c["j"].to_numpy()
    pp = j >= 0
    if parts is not None and len(parts):
        ids = np.unique(parts.loc[parts["step"] == st, "id"].to_numpy())
        if ids.size == 0:
            raise ValueError(f"no particles at step {st}")
    else:
        ids = np.unique(np.concatenate([i, j[pp]]))
    N = ids.size
    counts = pd.Series(0, index=ids)
    counts = counts.add(pd.Series(i).value_counts(), fill_value=0).add(pd.Series(j[pp]).value_counts(), fill_value=0)
    counts = counts.astype(int)
    # iterative rattler removal
    alive = pd.Series(True, index=ids)
    while True:
        ai = alive.reindex(i, fill_value=False).to_numpy()
        aj = np.where(pp, alive.reindex(np.where(pp, j, ids[0]), fill_value=False).to_numpy(), True)
        keep = ai & aj
        cnt = pd.Series(0, index=ids).add(pd.Series(i[keep]).value_counts(), fill_value=0) \
            .add(pd.Series(j[keep & pp]).value_counts(), fill_value=0)
        new = alive & (cnt >= min_contacts)
        if new.equals(alive):
            break
        alive = new
    nr = int((~alive).sum())
    c_pp, c_pw = int(pp.sum()), int((~pp).sum())
    c_pp2, c_pw2 = int((keep & pp).sum()), int((keep & ~pp).sum())
    Nm = N - nr
    return Coordination(n_particles=int(N), n_contacts=c_pp, n_wall_contacts=c_pw, n_rattlers=nr,
                        z=2 * c_pp / N, z_walls=(2 * c_pp + c_pw) / N,
                        z_no_rattlers=2 * c_pp2 / Nm if Nm else float("nan"),
                        z_no_rattlers_walls=(2 * c_pp2 + c_pw2) / Nm if Nm else float("nan"),
                        per_particle=counts, rattlers=ids[~alive.to_numpy()])


# ----------------------------------------------------------------------------- fabric
def fabric_tensor(data, step=None, include_walls=False, tol=0.0) -> np.ndarray:
    """Fabric tensor φ = (1/N_c) Σ_c n^c ⊗ n^c (2×2, dimensionless, trace 1) of the active
    contacts of one snapshot; disc-disc contacts only unless ``include_walls``.
    (The sign of n does not matter.)"""
    contacts, _ = _tables(data)
    st = _one_step(contacts, step)
    c = _active(contacts, st, tol, include_walls)
    if len(c) == 0:
        raise ValueError(f"no active contacts at step {st}")
    n = c[["nx", "ny"]].to_numpy(dtype=float)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    return n.T @ n / n.shape[0]


# ----------------------------------------------------------------------------- stress
@dataclass
class AverageStress:
    """Average stress of ch3 eq 3.17 over an area A (2D, unit thickness) [force/length]."""

    sigma: np.ndarray  # 2×2, sigma[a, b] = (1/A) Σ x_a F_b (eq 3.17 index order)
    area: float
    compression_positive: bool
    pressure: float  # (σ_xx + σ_yy)/2
    shear: float  # sqrt(((σ_xx - σ_yy)/2)² + σ_sym_xy²): radius of Mohr's circle
    asymmetry: float  # (σ_xy - σ_yx)/2: 0 when every disc is in moment equilibrium
    n_contacts: int  # contact terms summed (a disc-disc contact inside the region counts twice)


def contact_force_vectors(contacts: pd.DataFrame):
    """Force on disc i [force] of each row: F_i = -(fn n + fs t), t = (ny, -nx); the other
    body gets -F_i."""
    return np.column_stack(contact_force_on_i(contacts["nx"], contacts["ny"], contacts["fn"], contacts["fs"]))


def average_stress(data, area, step=None, particles=None, ids=None, include_walls=True,
                   compression_positive=True, tol=0.0) -> AverageStress:
    """Average stress tensor of ch3 eq 3.17, σ_ab = (1/V) Σ_p Σ_{c of p} x^c_a F^c_b, in 2D with
    unit thickness (V = area A [length²], σ in force/length).

    Choices:
    - x^c is the contact point relative to the centre of disc p (x^c = p^c - x_p) and F^c the force
      on p. For a disc in force equilibrium this equals eq 3.17 with absolute positions; the
      relative form is independent of the origin. For a disc-disc contact with both discs
      summed, the two terms add up to the branch vector form l ⊗ f (l = x_j - x_i, f the force of
      i on j), i.e. (1/A) Σ_c f_i l_j of the brief up to the index order, which matters only when
      the result is not symmetric (discs out of moment equilibrium).
    - Walls are not particles: a disc-wall contact contributes once, through the disc's term
      (p^c - x_p) ⊗ F (its contact point), and only if ``include_walls``.
    - ``ids``: the discs inside the RVE (default every disc of the snapshot); a contact with a
      disc outside contributes only through the inside disc.
    - Sign: eq 3.17 as written is tension-positive; ``compression_positive=True`` (default)
      returns -σ so that a compressed packing has positive pressure.
    """
    if not area > 0:
        raise ValueError("area must be positive")
    contacts, parts = _tables(data, particles)
    if parts is None:
        raise ValueError("the particles table (positions) is needed")
    st = _one_step(contacts, step)
    c = _active(contacts, st, tol, include_walls)
    p = parts[parts["step"] == st].drop_duplicates("id").set_index("id")
    inside = p.index.to_numpy() if ids is None else np.asarray(ids)
    F = contact_force_vectors(c)
    pc = c[["px", "py"]].to_numpy(float)
    i = c["i"].to_numpy()
    j = c["j"].to_numpy()
    sigma = np.zeros((2, 2))
    nterms = 0
    ini = np.isin(i, inside)
    if ini.any():
        xi = p.loc[i[ini], ["x", "y"]].to_numpy(float)
        sigma += (pc[ini] - xi).T @ F[ini]
        nterms += int(ini.sum())
    inj = (j >= 0) & np.isin(j, inside)
    if inj.any():
        xj = p.loc[j[inj], ["x", "y"]].to_numpy(float)
        sigma += (pc[inj] - xj).T @ (-F[inj])
        nterms += int(inj.sum())
    sigma /= area
    if compression_positive:
        sigma = -sigma
    sym = 0.5 * (sigma[0, 1] + sigma[1, 0])
    return AverageStress(sigma=sigma, area=float(area), compression_positive=bool(compression_positive),
                         pressure=float(0.5 * np.trace(sigma)),
                         shear=float(np.hypot(0.5 * (sigma[0, 0] - sigma[1, 1]), sym)),
                         asymmetry=float(0.5 * (sigma[0, 1] - sigma[1, 0])), n_contacts=nterms)
