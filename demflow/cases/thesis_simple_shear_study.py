"""tradeoff-thesis-simple-shear: what the saturated simple shear's speed knobs cost in accuracy (slow).

The port of the hand-made ``thesis-simple-shear-study`` onto :class:`~demflow.tradeoff.TradeoffStudy`
(issue 17 item 1); the old name still runs it (``demflow validate --case thesis-simple-shear-study``,
``get_case``: :data:`demflow.cases.ALIASES`).

The loose saturated shear of :mod:`demflow.cases.thesis_simple_shear` (one seed, no dry ensemble, sheared
to γ = 5 %) is run once at the reference (the finest settings
affordable in a ten-minute study on this machine), then with one knob at a time moved from it: density
scaling (thesis §5.5.3.1: quasi-static, so a denser disc allows a larger Δt and a longer fluid stride
m/K), elements per disc, and the fluid stride (safety fraction of the drag limit 2τ).  The observables
(:meth:`SimpleShear.observables`) are the mean pore pressure on walls 1 and 3 in units of F_y/W and the
shear force S in units of F_y, each at 12 shear strains; with ``scale`` = 1 a run's error is the rms
over them of the absolute difference from the reference (the old study's rms over γ, both curves
together).  The DEM is chaotic at slip events (20 discs), so the errors measure how far a knob moves
the whole history, not a smooth truncation error; the chaos floor (the reference with the density
× 1.0001, so Δt and the fluid stride move by 5e-5) measures that directly.

Measured with the hand-made study (loose, seed 1, to γ = 10.5 %, 2026-11-21; errors: rms over γ of the
pore pressure in F_y/W / of S in F_y): reference ×10, 32 elements, safety 0.5 took 2156 s (938 solves);
chaos floor 0.029 / 0.008; density ×100 and ×30: 0.071 / 0.006 and 0.041 / 0.004; 8 and 16 elements
(density ×10): 0.027 and 0.022, below the floor; safety 1.0: 0.149 / 0.015; default (×100, 16 elements,
safety 0.5): 0.063 / 0.008 in 42 s.  That reference does not fit a ten-minute study: this one's is
coarser (its ``params``), and its page gives today's numbers.
"""
from __future__ import annotations

from .thesis_simple_shear import SimpleShear
from .tradeoff_studies import TradeoffCase

SRC = "thesis §5.5.3.1, §5.5.4 (issues 4 and 17: saturated shear with a quantified error)"


class SimpleShearTradeoff(TradeoffCase):
    name = "tradeoff-thesis-simple-shear"
    title = "Speed vs accuracy: density scaling, elements per disc and fluid stride of the saturated simple shear"
    source = SRC
    slow = True
    study_case = "thesis-simple-shear"
    assumptions = SimpleShear.assumptions + (
        "Study: the loose saturated variant only, seed 1, no dry seed ensemble, sheared to γ = 5 % (the thesis's "
        "pore-pressure jump near γ ≈ 4 % is inside; the shear to 10.5 % costs twice as much).",
        "Reference = the finest run affordable in a ten-minute study on this machine, not a converged solution: "
        "density ×50, 16 elements per disc, stride safety 0.5 (the hand-made study's reference, ×10 and 32 "
        "elements, took 36 min to γ = 10.5 %; ×30 to γ = 6 % took about 3 min a run here, too much for ten "
        "minutes in all).",
        "Observables: mean pore pressure on walls 1 and 3 [F_y/W] and shear force S [F_y] at 12 strains; error = "
        "rms of the absolute differences from the reference (scale 1).",
        "Chaos floor: the reference with the disc density × 1.0001 (Δt and the fluid stride move by 5e-5): 20 "
        "discs through slip events are chaotic, and a knob's error is only meaningful above this floor.",
        "Density scaling (300, 100 → 50), elements per disc (8, 12 → 16) and the stride safety (1.0, 0.75 → 0.5) "
        "are resolution knobs, listed coarse to fine toward the reference: each one's error must shrink (the "
        "hand-made study found the elements' effect below its chaos floor: such a knob fails this check).",
    )
    params = dict(knob="sat_density_scale", values="300,100", reference=50.0, knobs="elements=8,12;safety=1.0,0.75",
                  fixed="variants=loose-saturated;ensemble=;gamma_max=0.05;elements=16;safety=0.5",
                  floor_param="sat_density_scale", floor_value=50.005, resolution="sat_density_scale,elements,safety",
                  scale=1.0, warmup="gamma_max=0.003")


# the hand-made study's name: the same study, kept working for users (demflow.cases.ALIASES)
SimpleShearStudy = SimpleShearTradeoff

__all__ = ["SimpleShearTradeoff", "SimpleShearStudy"]
