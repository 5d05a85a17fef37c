"""Study pages of issue 17's acceptance: the photoelastic test, the falling disc and the reduced 3D
uniaxial compression, each a :class:`~demflow.cases.tradeoff_studies.TradeoffCase` (the saturated
simple shear's is :mod:`demflow.cases.thesis_simple_shear_study`).

Each fixes the studied case's parameters that make one run affordable (``fixed``), names its knobs,
its reference (the finest setting a ten-minute study affords on this machine: not a converged
solution), its chaos floor (a physically irrelevant change of the reference) and its observables
(the studied case's ``observables`` hook).  Measured numbers are on each page.
"""
from __future__ import annotations

from .tradeoff_studies import TradeoffCase


class PhotoelasticTradeoff(TradeoffCase):
    name = "tradeoff-cs-photoelastic"
    title = "Speed vs accuracy: time step and relaxation of the C&S photoelastic test"
    source = "C&S (1979) verification test (knob study, issue 17)"
    study_case = "cs-photoelastic"
    slow = True
    assumptions = (
        "One packing (seed 1) instead of the case's eight; no Table 2/3 or fixed-side-wall runs, no stored engine "
        "runs (fixed: n_seeds=1, other_tables=0, engine_refs=0): the Table 1 strain-controlled run and the servo "
        "variant, as on the cs-photoelastic page.",
        "Knobs: the time-step fraction dt_fraction (Δt = fraction × 2√(m_min/kn); the cycle counts scale with "
        "0.1/fraction, so the walls move as far in the same time; 0.1 is the case's, 1.35-1.66× the safe "
        "estimate) and the relaxation after each stage, rest (cycles at fraction 0.1).",
        "Reference = dt_fraction 0.025 with rest 8000 (the case's): the finest affordable here, not a converged "
        "solution; the rest runs are at dt_fraction 0.025.",
        "Chaos floor: the reference with the dashpot ratio ζ × 1.0001 (the case has no density or stiffness "
        "parameter; a 1e-4 change of damping is as irrelevant physically): a dense packing's force network "
        "rearranges differently after any perturbation, and a knob's error is only meaningful above the floor.",
        "Observables (cs-photoelastic's observables hook): per stage F_H/F_V, the vertical wall force, z without "
        "rattlers, the fabric anisotropy and the q-model N; the servo walls' held ratio and the assembly's "
        "F_H/F_V per stage. Error: rms of the relative differences from the reference.",
    )
    params = dict(knob="dt_fraction", values="0.1,0.07,0.05", reference=0.025, knobs="rest=2000,4000",
                  fixed="n_seeds=1;other_tables=0;engine_refs=0;rest=8000", floor_param="zeta", floor_value=0.10001,
                  resolution="dt_fraction,rest", warmup="dt_fraction=0.1")


class FallingDiscTradeoff(TradeoffCase):
    name = "tradeoff-thesis-falling-disc"
    title = "Speed vs accuracy: elements per disc and time step of the falling disc (thesis §5.1)"
    source = "thesis §5.1, eqs 5.1-5.6 (knob study, issue 17)"
    study_case = "thesis-falling-disc"
    slow = True
    assumptions = (
        "Only the stride-1 run, to t_end = 0.01 s (5 drag relaxation times m/K; the case runs 0.02 s), without the "
        "case's strides 4 and 16 and its Δt/2 twin (fixed: strides=1, dt_study=0, t_end=0.01); the mesh study of "
        "the case (16, 32, 64, 128 elements) is kept, so its Richardson check stays valid at every setting.",
        "Knobs: BEM elements on the disc (16, 32, 64 → 128; the case's 64) and the time step dt (1.5e-4, 1e-4 → "
        "5e-5 s; the case's 1e-4; the fluid is solved every step, and the fluid drag limit safety·2m/K with a wall "
        "at the minimum gap, 1.59e-4 s, refuses larger steps).",
        "Reference = 128 elements, dt = 5e-5 s: the finest affordable here, not a converged solution (the lagged "
        "explicit drag is first order in Δt: the dt knob's errors are relative to Δt = 5e-5, not to Δt → 0).",
        "Chaos floor: the reference with the disc density × 1.0001; the fall is not chaotic, so the floor is the "
        "observables' sensitivity to a 1e-4 change of the driving density difference (about 1e-4 by eq 5.6).",
        "Observables (thesis-falling-disc's observables hook): the disc velocity at t_end/8, t_end/4, t_end/2 and "
        "t_end, and the BEM drag K. Error: rms of the relative differences from the reference.",
    )
    params = dict(knob="elements", values="16,32,64", reference=128, knobs="dt=1.5e-4,1e-4",
                  fixed="strides=1;dt_study=0;t_end=0.01;dt=5e-5", floor_param="rho_s", floor_value=2.0002,
                  resolution="elements,dt", warmup="t_end=0.0005")


class MiyataUniaxialTradeoff(TradeoffCase):
    name = "tradeoff-miyata-uniaxial-3d"
    title = "Speed vs accuracy: clump resolution, time step and plate speed of the reduced 3D uniaxial compression"
    source = "Miyata §3.3 (knob study, issue 17)"
    study_case = "miyata-uniaxial-3d"
    slow = True
    assumptions = (
        "Loading to 400 kPa instead of 600 kPa (fixed: stress_max=400000): the seed's regimes 0-100, 100-400 kPa.",
        "Knobs: spheres per clump K (2, 4 → 8), the plate speed (8, 4 → 2 cm/s) and the time-step fraction "
        "dt_fraction (0.3 against 0.2, of the case's critical estimate).",
        "Reference = the case's own settings (K = 8, 2 cm/s, fraction 0.2): a finer reference (K = 16, about twice "
        "the cost) does not fit a ten-minute study here; it is not a converged solution.",
        "Chaos floor: the reference with Young's modulus (particles and plate) × 1.0001 (Δt moves by 5e-5): 1-5 "
        "particles touch the plate in the 2 × 2 m box and the stress rises and collapses as they slip, so any "
        "perturbation moves the curve; a knob's error is only meaningful above the floor.",
        "Observables (miyata-uniaxial-3d's observables hook): the settled floor stress, the particles left after "
        "trimming, and the settlement where the plate stress first reaches each 100 kPa. Error: rms of the relative "
        "differences from the reference.",
    )
    params = dict(knob="K", values="2,4", reference=8, knobs="plate_speed=0.08,0.04;dt_fraction=0.3",
                  fixed="stress_max=400000.0;band_seeds=1;engine_refs=0", floor_param="young", floor_value=7.0007e10,
                  resolution="K,plate_speed", warmup="plate_speed=0.08;dt_fraction=0.3")


__all__ = ["PhotoelasticTradeoff", "FallingDiscTradeoff", "MiyataUniaxialTradeoff"]
