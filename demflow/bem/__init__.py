"""2D boundary-element solver for Stokes flow (thesis ch. 4).

    from demflow.bem import circle, channel, Domain, Problem, FINE
    dom = Domain([channel(40.0, 5.0, 160, 20), circle((0, 0), 1.0, 64)])
    pb = Problem(dom, mu=1.0).velocity(("channel", "inlet"), poiseuille).velocity(("channel", "outlet"), poiseuille)
    sol = pb.solve()                  # Table 4.1 quadrature; quad=FINE for near contact
    sol.force("particle"), sol.moment("particle"), sol.interior(points), sol.boundary_pressure()

Modules: ``geometry`` (boundaries, elements, orientation check), ``kernels`` (stress kernels,
eqs 4.94-4.95), ``quadrature`` (Gauss, Table 4.1, logarithmic rule), ``assembly`` (Numba: H, G
with u*, t* of eqs 4.20-4.21 inline, [A]Y = R, interior sums), ``solve`` (boundary conditions, null space, LU solve, results),
``exact`` (exact Stokes solutions used for validation).
"""
from .geometry import Boundary, Domain, channel, circle, polygon, rectangle
from .quadrature import FINE, TABLE
from .solve import IncompatibleFluxError, Problem, Solution

__all__ = ["Boundary", "Domain", "channel", "circle", "polygon", "rectangle", "FINE", "TABLE",
           "IncompatibleFluxError", "Problem", "Solution"]
