"""Registered cases: every named case of the sources, one module each.

``CASES`` maps the stable name (used by ``demflow run NAME``) to the case object.  The case interface
(``Case``, ``CaseRun``, ``Check``, ``ReferencePlan``) is re-exported from :mod:`demflow.cases.base`.
"""
from __future__ import annotations

__all__ = ["ALIASES", "CASES", "Case", "CaseRun", "Check", "ReferencePlan", "comparison_cases", "get_case",
           "reference_cases"]

from .base import Case, CaseRun, Check, ReferencePlan
from .thesis_one_disc import OneDisc
from .thesis_five_discs import FiveDiscs
from .thesis_impact import Impact
from .cs_nine_disc import NineDisc
from .cs_nine_disc_engines import NineDiscEngines
from .cs_photoelastic import Photoelastic
from .thesis_bem import CylinderMovingPlanes, CylinderPoiseuille, FreeRectangle
from .thesis_falling_disc import FallingDisc
from .thesis_sedimentation import Sedimentation
from .thesis_liquefaction import Liquefaction
from .thesis_simple_shear import SimpleShear
from .thesis_simple_shear_study import SimpleShearTradeoff
from .hertz_impacts import HertzImpacts
from .ch3_stack import DampedStack, ElasticStack
from .conformance_3d import Conformance3D
from .tradeoff_studies import ImpactTradeoff
from .tradeoff_cases import FallingDiscTradeoff, MiyataUniaxialTradeoff, PhotoelasticTradeoff
from .ch3_chain import ImpulseChain
from .miyata_uniaxial3d import (MiyataUniaxial3D, MiyataUniaxial3DEllipsoids, MiyataUniaxial3DEllipsoidsFull,
                                MiyataUniaxial3DFull)
from .miyata_uniaxial2d import MiyataUniaxial2D
from .miyata_uniaxial2d_engines import MiyataUniaxial2DEngines
from .miyata_ksweep import MiyataUniaxialKSweep
from .stability_matrix import StabilityMatrix

CASES: dict[str, Case] = {c.name: c for c in (OneDisc(), FiveDiscs(), Impact(), NineDisc(), NineDiscEngines(), Photoelastic(),
                                              CylinderPoiseuille(), CylinderMovingPlanes(), FreeRectangle())}
CASES[FallingDisc.name] = FallingDisc()
CASES[Sedimentation.name] = Sedimentation()
CASES[Liquefaction.name] = Liquefaction()
CASES[SimpleShear.name] = SimpleShear()
CASES[HertzImpacts.name] = HertzImpacts()
CASES[ElasticStack.name] = ElasticStack()
CASES[DampedStack.name] = DampedStack()
CASES[ImpulseChain.name] = ImpulseChain()
CASES[MiyataUniaxial3D.name] = MiyataUniaxial3D()
CASES[MiyataUniaxial3DEllipsoids.name] = MiyataUniaxial3DEllipsoids()
CASES[MiyataUniaxial3DFull.name] = MiyataUniaxial3DFull()
CASES[MiyataUniaxial3DEllipsoidsFull.name] = MiyataUniaxial3DEllipsoidsFull()
CASES[MiyataUniaxialKSweep.name] = MiyataUniaxialKSweep()
CASES[MiyataUniaxial2D.name] = MiyataUniaxial2D()
CASES[MiyataUniaxial2DEngines.name] = MiyataUniaxial2DEngines()
CASES[Conformance3D.name] = Conformance3D()
CASES[ImpactTradeoff.name] = ImpactTradeoff()
for _study in (PhotoelasticTradeoff, FallingDiscTradeoff, SimpleShearTradeoff, MiyataUniaxialTradeoff):
    CASES[_study.name] = _study()

# names that still work for users after a case was renamed or folded into another: old → current
ALIASES: dict[str, str] = {"thesis-simple-shear-study": SimpleShearTradeoff.name}
CASES[StabilityMatrix.name] = StabilityMatrix()


def get_case(name: str) -> Case:
    name = ALIASES.get(name, name)
    if name not in CASES:
        raise KeyError(f"unknown case {name!r}; `demflow cases` lists them: {', '.join(CASES)}")
    return CASES[name]


def reference_cases() -> dict[str, Case]:
    """The cases `demflow reference` can make engine reference runs for (a ``reference_plan``)."""
    return {n: c for n, c in CASES.items() if c.reference_plan() is not None}


def comparison_cases() -> dict[str, Case]:
    """The cases `demflow compare` can compare engines on (a ``comparison_case``)."""
    return {n: c for n, c in CASES.items() if c.comparison_case() is not None}
