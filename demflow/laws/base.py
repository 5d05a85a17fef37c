"""The contact-law interface: what a law declares, and the compiled calls every pair pass makes.

A law family (linear, Hertz-Mindlin, ...) has two halves.

*Python side* — a :class:`LawFamily` subclass, one instance per built scene:

- ``accepts(law)``: whether it implements a scene's law declaration (e.g. :class:`demflow.scene.LinearLaw`);
- ``params(...)``: its parameters per material pair, checked (clear errors), as a namedtuple of
  (n_materials × n_materials) tables plus mode flags — the only thing that enters a kernel;
- ``history_width(dim)``: the per-contact history columns it keeps in ``dim`` dimensions;
- ``stiffness_bound(law)``: the largest contact stiffness [force/length] of one declared law, for
  the single-spring critical time step (the base of ``dt_fraction``);
- ``time_step_constants(law)``: its normal and tangential springs and dashpots, for the safe
  critical time step of a packing (:func:`demflow.integrate.safe_time_step`);
- ``elastic_energy``: compiled, see :func:`law_energy_add`;
- ``continue_from(hist, width)``: how history written by another stage (possibly another law or
  width) carries over;
- ``engines``: how YADE and LIGGGHTS express it (or that they cannot), for the capabilities table.

*Compiled side* — implementations of the generic functions below, registered with
:func:`numba.extending.overload` for the law's params type.  Numba picks the implementation from
the *type* of the params tuple when the cycle is compiled, so a law costs no per-pair branch and
the kernels keep Numba's on-disk cache (measured: ``benchmarks/results/law_dispatch.md``).  Each is
inlined into the pair pass and is a pure function of scalars and the contact's history row.

- ``law_force(law, hist, k, ma, mb, overlap, ndot, sdot, dt) -> (Fn, Fs, sliding)``: advance
  contact k's history row by one step and return its total normal and shear force;
- ``law_force_dissipation(...) -> (Fn, Fs, sliding, dissipated, Fn_work, Fs_work)``: the same, plus
  the energy its dashpots and friction dissipated in the step and the forces that worked over it (the
  energy balance of :mod:`demflow.simulation`);
- ``law_separate(law, hist, k)``: the pair is apart: clear its history;
- ``law_energy_add(law, e, hist, k, ma, mb) -> e``: add the energy stored in contact k's springs.

To add a law: a module in ``demflow/laws/`` with its scene declaration, its params namedtuple, a
``LawFamily`` subclass and the three overloads; list the family in :data:`FAMILIES`
(``demflow/laws/__init__.py``); its tests are the law-interface class in ``tests/test_laws.py``.
"""
from __future__ import annotations

import numpy as np


def law_force(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
    """Advance contact k by one step; returns (Fn, Fs, sliding).  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled law for parameters of type {type(law).__name__}")


def law_force_dissipation(law, hist, k, ma, mb, overlap, ndot, sdot, dt):
    """:func:`law_force` plus, for the energy balance, the energy the contact dissipated in this step
    [force·length] (its dashpots and its friction slip) and the normal and shear forces that did work
    over the step (Fn_work, Fs_work: the work of a relative displacement d is Fn_work·dₙ + Fs_work·dₛ,
    so that a moving wall's work is counted with the forces its move produced); returns
    (Fn, Fs, sliding, dissipated, Fn_work, Fs_work), Fn, Fs and the history exactly as :func:`law_force`
    gives them.  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled law for parameters of type {type(law).__name__}")


def law_separate(law, hist, k):
    """Contact k is apart: clear its history.  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled law for parameters of type {type(law).__name__}")


def law_energy_add(law, e, hist, k, ma, mb):
    """e plus the elastic energy of contact k [force·length].  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled law for parameters of type {type(law).__name__}")


def is_params_of(numba_type, cls) -> bool:
    """True when ``numba_type`` is the Numba type of a ``cls`` namedtuple (for overload selection)."""
    return getattr(numba_type, "instance_class", None) is cls


class LawFamily:
    """Python side of a contact-law family (see the module docstring)."""

    name: str = ""
    # engine -> how the engine expresses this law ("" when it cannot)
    engines: dict = {}

    def __init__(self, scene, laws_by_pair, material_index):
        self.scene = scene
        self.laws_by_pair = laws_by_pair  # {(material a, material b): declared law}
        self.material_index = material_index

    @classmethod
    def accepts(cls, law) -> bool:
        """True when this family implements the declared scene law ``law``."""
        raise NotImplementedError

    def history_width(self, dim: int) -> int:
        raise NotImplementedError

    def params(self):
        raise NotImplementedError

    def stiffness_bound(self, law) -> float:
        raise NotImplementedError

    def time_step_constants(self, law) -> tuple[float, float, float, float]:
        """(kN, kT, cN, cT) of one declared law for the safe critical time step
        (:func:`demflow.integrate.safe_time_step`): the largest normal and tangential spring
        stiffness [force/length] and dashpots [force·time/length] a contact can show, kT = cT = 0
        when the tangential force can never be elastic."""
        raise NotImplementedError

    def continue_from(self, hist: np.ndarray, width: int) -> np.ndarray:
        """History of another stage's contacts (key order) as this law's: the common leading columns
        are kept, the rest start at zero (a stage without shear springs keeps only the normal column)."""
        out = np.zeros((hist.shape[0], width))
        c = min(width, hist.shape[1])
        out[:, :c] = hist[:, :c]
        return out


# --------------------------------------------------------------------------- the 3D pair calls
# A 3D contact's history row starts with its tangential vector (columns 0-2: a force or a
# displacement, the law says which); the sphere pair pass rotates that vector into the current
# tangent plane before it calls the law (keeping its length), so a law sees history in the plane
# of the contact — unless the law turns it itself (:func:`law_turns_history`).  Further columns are
# the law's own (scalars; a law that keeps vectors there projects them itself).

def law_turns_history(law):
    """True when the law carries its tangential history into the current tangent plane itself (the Hertz-Mindlin
    law's ``history_rotation='project'``: after its increment, LIGGGHTS's rule); then the pair pass does not turn it
    before the call.  Read once per pass (the value is scene-wide).
    Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled 3D law for parameters of type {type(law).__name__}")


def law_force3(law, hist, k, ma, mb, meff, rstar, overlap, vn, vtx, vty, vtz, nx, ny, nz, dt):
    """Advance 3D contact k by one step; returns (Fn, Tx, Ty, Tz, sliding, dissipated, row, n_row): the
    caller writes ``row[c]`` to ``hist[k, c]`` for c < n_row (the law only reads ``hist``).

    ``vn`` = (v_i - v_j)·n > 0 while approaching, (vtx, vty, vtz) the tangential relative velocity
    of i's contact point against j's, n the unit normal from i to j, ``meff`` m_i m_j/(m_i + m_j)
    (the body mass against a plane), ``rstar`` R_i R_j/(R_i + R_j) (R_i against a plane).  Fn >= 0
    is the total normal force (it pushes i along -n); T is the total tangential force on i; ``dissipated``
    the energy the contact's dashpots and Coulomb slip took in the step [force·length] (>= 0; the energy
    balance of :class:`demflow.simulation3d.Simulation3D`).  ``row`` (a tuple of floats) is contact k's history
    after the step.  Why the caller writes it: Numba (0.68) keeps an atomic reference-count increment and
    decrement per call of an array that an inlined law holds across its branches; a law that reads its row
    at once and returns the new one leaves none (hertz_mindlin.hertz_contact3).  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled 3D law for parameters of type {type(law).__name__}")


def law_energy3(law, e, hist, k, ma, mb, rstar, overlap):
    """e plus the elastic energy of 3D contact k [force·length].  Compiled per law (overload)."""
    raise NotImplementedError(f"no compiled 3D law for parameters of type {type(law).__name__}")
