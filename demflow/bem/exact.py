"""Exact 2D Stokes solutions used to validate the solver (μ [Pa s], lengths [m], U [m/s]).

* Circular Couette flow: inner cylinder (radius a) rotating at Ω inside a fixed concentric
  cylinder (radius b): u_θ = A r + B/r, A = -Ω a²/(b² - a²), B = Ω a² b²/(b² - a²), p = const;
  torque on the inner cylinder M = -4πμ Ω a² b²/(b² - a²) per unit length.
  (Landau & Lifshitz, Fluid Mechanics, §18, problem 2; Batchelor 1967 §4.5.)
* Cylinder (radius a) translating at U inside a fixed concentric cylinder (radius b): drag per
  unit length F = -4πμU / (ln(b/a) - (b² - a²)/(b² + a²)).  (Happel & Brenner, Low Reynolds number
  hydrodynamics, 1965, §4-? "cylinder in a cylindrical container"; also Finn & Noll 1957 and
  Pozrikidis 1992 problem 2.9 - the b → ∞ limit is the 4πμU/(ln(b/a) - 1) of the Stokes paradox.)
* Plane Poiseuille flow with pressure gradient G = -dp/dx in |y| ≤ h:
  u = G (h² - y²)/(2μ), p = p_0 - G x, wall shear traction μ|du/dy| = G h.  (Batchelor §4.2.)
* Plane straining flow u = (E x, -E y), p = p_0: σ = 2μ E diag(1, -1) - p_0 I.
* Quadratic flow u = (y² + xy, -y²/2), p = μ (2x - y) (any solenoidal quadratic field with
  μ∇²u = ∇p), used for the interior-stress check of eqs 4.93-4.95.
"""
from __future__ import annotations

import numpy as np


def couette_torque(a, b, omega, mu):
    """Torque per unit length [N] of the fluid on the rotating inner cylinder."""
    return -4 * np.pi * mu * omega * a * a * b * b / (b * b - a * a)


def couette_velocity(x, y, a, b, omega, cx=0.0, cy=0.0):
    A = -omega * a * a / (b * b - a * a)
    B = omega * a * a * b * b / (b * b - a * a)
    r = np.hypot(x - cx, y - cy)
    ut = A * r + B / r
    return np.stack([-ut * (y - cy) / r, ut * (x - cx) / r], -1)


def annulus_translation_drag(a, b, U, mu):
    """x-force per unit length [N/m] of the fluid on the inner cylinder moving at U in +x."""
    return -4 * np.pi * mu * U / (np.log(b / a) - (b * b - a * a) / (b * b + a * a))


def poiseuille(x, y, h, G, mu, p0=0.0):
    """Velocity (P, 2) and pressure of plane Poiseuille flow."""
    u = np.stack([G * (h * h - y * y) / (2 * mu), 0 * y], -1)
    return u, p0 - G * x


def quadratic_flow(x, y, mu):
    """Velocity (P, 2), stress (P, 3) = (σxx, σxy, σyy) and pressure of u = (y²+xy, -y²/2)."""
    u = np.stack([y * y + x * y, -0.5 * y * y], -1)
    p = mu * (2 * x - y)
    sxx = -p + 2 * mu * y
    syy = -p - 2 * mu * y
    sxy = mu * (2 * y + x)
    return u, np.stack([sxx, sxy, syy], -1), p
