"""The hinged simple-shear box of thesis §5.3.3 and §5.4-5.6, as wall phases.

"The velocity of the bottom wall is deduced from the motion of the lateral walls because the
bottom wall connections are hinged": the lateral walls rotate counter-clockwise at γ̇ [1/s] about
their top ends (hinged to the top wall), so their lower ends move in +x at γ̇H, and the bottom wall
translates in +x at γ̇H.  The box stays a parallelogram of height H and constant area, and the wall
velocities agree at the four corners.
"""
from __future__ import annotations

from ..scene import Phase


def hinged_shear_phases(x_left: float, x_right: float, y_top: float, height: float, rate: float,
                        n_steps: int) -> dict:
    """{wall name: (Phase,)} for walls "bottom", "right", "left" shearing at ``rate`` for ``n_steps``."""
    return {"bottom": (Phase(n_steps, velocity=(rate * height, 0.0)),),
            "right": (Phase(n_steps, omega=rate, pivot=(x_right, y_top)),),
            "left": (Phase(n_steps, omega=rate, pivot=(x_left, y_top)),)}
