"""demflow: discrete element simulation of dry and saturated granular media.

Scene → build → Simulation → results → analysis → report.
"""
import os

# Before Numba is first imported: no SVML in compiled loops (it rounds per CPU; see demflow.jit and demflow.libm).
os.environ.setdefault("NUMBA_DISABLE_INTEL_SVML", "1")

from .scene import (Box, ContactModel, Discs, GlobalDamping, LinearLaw, Material, Outputs, Phase, Scene,  # noqa: E402
                    SceneError, Servo, Superquadrics, UnsafeTimeStepWarning, EnergyBalanceWarning, PeriodicMeshWarning, Wall)
from .build import build
from .simulation import BlowUpError, Simulation
from .results import Results
from .laws.hertz_mindlin import HertzMindlinLaw
from .scene3d import Clumps, Ellipsoids, Outputs3D, Plane, PlanePhase, PlateServo, Scene3D, Spheres, TriangleMesh
from .shapes.clump import ClumpTemplate

__version__ = "0.1.0"

__all__ = ["Scene", "Box", "Discs", "Wall", "Phase", "Servo", "Material", "LinearLaw", "ContactModel",
           "GlobalDamping", "Outputs", "SceneError", "UnsafeTimeStepWarning", "EnergyBalanceWarning", "PeriodicMeshWarning", "build",
           "Simulation", "BlowUpError", "Results",
           "Scene3D", "Spheres", "Plane", "PlanePhase", "PlateServo", "Outputs3D", "HertzMindlinLaw", "TriangleMesh",
           "Clumps", "ClumpTemplate", "Ellipsoids", "Superquadrics"]
