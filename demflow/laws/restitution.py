"""Coefficient of restitution e ↔ contact damping, in the conventions users meet.

A Hertzian contact with a dashpot c = 2ζ√(m* k_n(δ)), k_n(δ) = dF/dδ = 2E*√(R*δ) the tangent
stiffness (ch3 eq 3.28 with the Hertz stiffness; Miyata eqs 28-30; Tsuji et al. 1992), has a
restitution coefficient that depends on ζ only, not on the impact velocity: scaled to the maximum
overlap, every impact solves the same equation

    ξ'' = -max(0, ξ^{3/2} + 2ζ√(3/2) ξ^{1/4} ξ'),   ξ(0) = 0, ξ'(0) = 1,

(no tensile force: once the total force reaches zero the bodies fly apart) and e = -ξ' at the end
of contact.  Three ways to pick ζ from a target e:

- ``"exact"`` (demflow's default): ζ solves e(ζ) = e for that equation (an adaptive Dormand-Prince
  integration with an end-of-contact event, ``brentq`` on ζ), so a Hertz impact rebounds with the e
  asked for.
- ``"yade"``: YADE 2023.02a ``Ip2_FrictMat_FrictMat_MindlinPhys(en, es)`` — Thornton, Cummins &
  Cleary (2013) eqs B6-B7, a 10-term polynomial fit; verified here on the installed YADE
  (``phys.betan`` = 0.2330248576834424 for en = 0.5, equal to this function to the last digit).
  YADE's dashpot uses c = 2β√(m̄ k_n) with m̄ the *member* masses (see ENGINES.md).
- ``"liggghts"``: LIGGGHTS 3.8 ``model hertz``: γ = -2√(5/6) β √(S m*), β = ln e /√(ln²e + π²),
  S = 2Y*√(R*δ) (normal) or 8G*√(R*δ) (tangential): ζ = √(5/6)·|ln e|/√(ln²e + π²).  This is the
  linear-spring relation scaled by √(5/6); its actual restitution differs from the target (measured
  in the hertz-impacts case).

And the linear spring (thesis §2.2.4.7, ch3 eq 3.28): ζ = |ln e| / √(ln²e + π²) exactly.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..jit import njit

CONVENTIONS = ("exact", "yade", "liggghts", "linear")

# Thornton, Cummins & Cleary (2013), Table 2: fit of α(e) for a Hertzian contact without attraction
_THORNTON_H = (-6.918798, -16.41105, 146.8049, -796.4559, 2928.711, -7206.864, 11494.29, -11342.18,
               6276.757, -1489.915)


def zeta_linear(e: float) -> float:
    """Damping ratio ζ = c / (2√(k m*)) of a *linear* spring-dashpot with restitution e (exact)."""
    _check_e(e)
    if e == 1.0:
        return 0.0
    if e == 0.0:
        return 1.0
    le = math.log(e)
    return -le / math.sqrt(le * le + math.pi ** 2)


def zeta_liggghts(e: float) -> float:
    """LIGGGHTS ``model hertz``: γ_n = -2√(5/6) β √(S_n m*) ⇒ ζ = √(5/6) · (-β)."""
    return math.sqrt(5.0 / 6.0) * zeta_linear(e)


def zeta_yade(e: float) -> float:
    """YADE 2023.02a MindlinPhys from en: Thornton et al. (2013) eqs B6-B7."""
    _check_e(e)
    if e == 1.0:
        return 0.0
    a = 0.0
    for h in reversed(_THORNTON_H):
        a = e * (h + a)
    return math.sqrt(1.0 / (1.0 - (1.0 + e) ** 2 * math.exp(a)) - 1.0)


# Dormand & Prince (1980) RK5(4)7M: stage weights, 5th-order solution, 5th - 4th order error weights (the
# nodes are not needed: the scaled impact does not depend on time)
_DP_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0.0],
    [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]])
_DP_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
_DP_E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])


@njit
def _impact_force(xi, v, b):
    """Scaled total contact force ξ^{3/2} + b ξ^{1/4} ξ' (square roots only: correctly rounded)."""
    if xi <= 0.0:
        return 0.0
    r = math.sqrt(xi)
    return xi * r + b * math.sqrt(r) * v


@njit
def _dp_step(xi, v, h, b, out, kx, kv):
    """One Dormand-Prince step of ξ'' = -max(0, force) from (ξ, ξ'); out = (ξ, ξ', err ξ, err ξ').
    kx, kv (7,): the stages' scratch, allocated once by the caller."""
    for s in range(7):
        x, w = xi, v
        for j in range(s):
            x += h * _DP_A[s, j] * kx[j]
            w += h * _DP_A[s, j] * kv[j]
        kx[s] = w
        kv[s] = -max(_impact_force(x, w, b), 0.0)
    x1, v1, ex, ev = xi, v, 0.0, 0.0
    for s in range(7):
        x1 += h * _DP_B[s] * kx[s]
        v1 += h * _DP_B[s] * kv[s]
        ex += h * _DP_E[s] * kx[s]
        ev += h * _DP_E[s] * kv[s]
    out[0], out[1], out[2], out[3] = x1, v1, ex, ev


@njit
def _impact_rebound(b, rtol):
    """ξ' at the end of contact (total force back to zero after the peak) of the scaled impact.

    Adaptive Dormand-Prince 5(4) with local extrapolation, error per step ≤ rtol·max(|y|) + 1e-15;
    the end of contact inside the last step is located by bisection on the step length, each trial
    a full step from the last accepted state.  Returns NaN when no end of contact is found."""
    xi, v, t, h = 0.0, 1.0, 0.0, 1e-6
    out = np.zeros(4)
    kx = np.zeros(7)
    kv = np.zeros(7)
    for _ in range(1_000_000):
        _dp_step(xi, v, h, b, out, kx, kv)
        err = max(abs(out[2]) / (rtol * max(abs(xi), abs(out[0])) + 1e-15),
                  abs(out[3]) / (rtol * max(abs(v), abs(out[1])) + 1e-15))
        if err > 1.0:
            h *= max(0.2, 0.9 * err ** -0.2)
            continue
        x1, v1 = out[0], out[1]
        if v1 < 0.0 and _impact_force(x1, v1, b) <= 0.0:
            lo, hi = 0.0, h  # force > 0 after lo, <= 0 after hi
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                _dp_step(xi, v, mid, b, out, kx, kv)
                if out[1] < 0.0 and _impact_force(out[0], out[1], b) <= 0.0:
                    hi = mid
                else:
                    lo = mid
            _dp_step(xi, v, hi, b, out, kx, kv)
            return out[1]
        xi, v, t = x1, v1, t + h
        if t > 20.0:
            return np.nan
        h *= min(5.0, 0.9 * max(err, 1e-10) ** -0.2)
    return np.nan


def hertz_restitution(zeta: float, rtol: float = 1e-13) -> float:
    """The restitution e of a Hertz impact with dashpot c = 2ζ√(m* k_n(δ)) (module docstring).

    Integrated by :func:`_impact_rebound` (Numba, scalar arithmetic and square roots only) rather than
    scipy's ``solve_ivp``, whose steps go through BLAS: the last bits of ζ then depended on the CPU
    OpenBLAS picks its kernels for (ζ(0.5) differed by 1.8e-14 between AVX-512 Intel and AMD hosts,
    measured 2026-11-25), and ζ enters the engine decks and every 3D run.  Agreement with solve_ivp
    (DOP853, rtol 1e-13) within tolerance ``hertz.impact-integrator`` is a test (tests/test_spheres3d.py)."""
    if zeta < 0 or not math.isfinite(zeta):
        raise ValueError(f"zeta={zeta!r}: give a finite damping ratio >= 0")
    if zeta == 0.0:
        return 1.0
    end = _impact_rebound(2.0 * zeta * math.sqrt(1.5), rtol)
    if not math.isfinite(end):
        raise RuntimeError(f"hertz_restitution: no end of contact found for zeta={zeta}")
    return float(-end)


@functools.lru_cache(maxsize=256)
def zeta_exact(e: float) -> float:
    """ζ such that a Hertz impact rebounds with restitution e (module docstring; ``brentq``)."""
    from scipy.optimize import brentq

    _check_e(e)
    if e == 1.0:
        return 0.0
    if e == 0.0:
        raise ValueError("restitution e=0 has no finite Hertz dashpot (e(ζ) > 0 for all ζ); "
                         "give e > 0, e.g. 0.01")
    hi = 1.0
    while hertz_restitution(hi) > e:
        hi *= 2.0
        if hi > 1e6:
            raise ValueError(f"restitution e={e} is below what a Hertz dashpot reaches; give a larger e")
    return float(brentq(lambda z: hertz_restitution(z) - e, 0.0, hi, xtol=1e-13, rtol=1e-12))


def zeta_for(e: float, convention: str) -> float:
    """The damping ratio ζ (c = 2ζ√(m* k_n)) giving restitution e in ``convention``."""
    if convention == "exact":
        return zeta_exact(e)
    if convention == "yade":
        return zeta_yade(e)
    if convention == "liggghts":
        return zeta_liggghts(e)
    if convention == "linear":
        return zeta_linear(e)
    raise ValueError(f"restitution convention {convention!r}: use one of {CONVENTIONS}")


def _check_e(e: float) -> None:
    if isinstance(e, bool) or not isinstance(e, (int, float, np.floating)) or not (0.0 <= e <= 1.0):
        raise ValueError(f"restitution e={e!r}: give a number with 0 <= e <= 1")
