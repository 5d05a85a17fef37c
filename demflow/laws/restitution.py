"""Coefficient of restitution e ↔ contact damping, in the conventions users meet.

A Hertzian contact with a dashpot c = 2ζ√(m* k_n(δ)), k_n(δ) = dF/dδ = 2E*√(R*δ) the tangent
stiffness (ch3 eq 3.28 with the Hertz stiffness; Miyata eqs 28-30; Tsuji et al. 1992), has a
restitution coefficient that depends on ζ only, not on the impact velocity: scaled to the maximum
overlap, every impact solves the same equation

    ξ'' = -max(0, ξ^{3/2} + 2ζ√(3/2) ξ^{1/4} ξ'),   ξ(0) = 0, ξ'(0) = 1,

(no tensile force: once the total force reaches zero the bodies fly apart) and e = -ξ' at the end
of contact.  Three ways to pick ζ from a target e:

- ``"exact"`` (demflow's default): ζ solves e(ζ) = e for that equation (scipy: ``solve_ivp`` with
  an end-of-contact event, ``brentq`` on ζ), so a Hertz impact rebounds with the e asked for.
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


def hertz_restitution(zeta: float, rtol: float = 1e-11) -> float:
    """The restitution e of a Hertz impact with dashpot c = 2ζ√(m* k_n(δ)) (module docstring)."""
    from scipy.integrate import solve_ivp

    if zeta < 0 or not math.isfinite(zeta):
        raise ValueError(f"zeta={zeta!r}: give a finite damping ratio >= 0")
    if zeta == 0.0:
        return 1.0
    b = 2.0 * zeta * math.sqrt(1.5)

    def rhs(_t, y):
        xi = max(y[0], 0.0)
        f = xi ** 1.5 + b * xi ** 0.25 * y[1]
        return (y[1], -max(f, 0.0))

    def released(_t, y):  # total force back to zero (or the overlap closed) after the peak
        xi = max(y[0], 0.0)
        return xi ** 1.5 + b * xi ** 0.25 * y[1] if y[1] < 0 else 1.0
    released.terminal = True
    released.direction = -1
    sol = solve_ivp(rhs, (0.0, 20.0), (0.0, 1.0), events=released, rtol=rtol, atol=1e-14,
                    method="DOP853")
    if not sol.t_events[0].size:
        raise RuntimeError(f"hertz_restitution: no end of contact found for zeta={zeta}")
    return float(-sol.y_events[0][0][1])


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
