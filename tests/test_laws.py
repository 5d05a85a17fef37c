"""The contact-law interface (demflow.laws.base): every law family passes this class.

A family declares its parameters per material pair, its history width, a stiffness bound, its
elastic energy, how its history carries across a change of law, and how the engines express it;
its compiled calls (law_force, law_separate, law_energy_add) are selected by the params type.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from demflow import ContactModel, Discs, LinearLaw, Material, Scene, build
from demflow.laws import FAMILIES, law_energy_add, law_force, law_separate
from demflow.laws.linear import Linear, linear_contact


@njit(cache=False)
def _one_contact(law, hist, overlap, ndot, sdot, dt):
    Fn, Fs, sliding = law_force(law, hist, 0, 0, 0, overlap, ndot, sdot, dt)
    e = law_energy_add(law, 0.0, hist, 0, 0, 0)
    return Fn, Fs, sliding, e


@njit(cache=False)
def _separate(law, hist):
    law_separate(law, hist, 0)


SCENE_LAWS = {Linear: [LinearLaw(kn=2e5, ks=1e5, cn=3.0, cs=1.0, friction=0.4)]}


def _family(fam, law, cm=ContactModel()):
    sc = Scene(name="t", discs=Discs(x=[0.0, 3.0], y=[0.0, 0.0], radius=[1.0, 1.0], material="a"),
               materials={"a": Material(1.0)}, laws={("a", "a"): law}, contact_model=cm)
    return fam(sc, {("a", "a"): law}, {"a": 0})


@pytest.mark.parametrize("fam", FAMILIES, ids=lambda f: f.name)
class TestLawFamily:
    def test_accepts_its_declarations_only(self, fam):
        for law in SCENE_LAWS[fam]:
            assert fam.accepts(law)
        assert not fam.accepts(object())

    def test_params_hold_only_arrays_and_numbers(self, fam):
        p = _family(fam, SCENE_LAWS[fam][0]).params()
        assert hasattr(p, "_fields")
        for name in p._fields:
            v = getattr(p, name)
            assert isinstance(v, (np.ndarray, int, float, bool, np.integer, np.floating)), name

    def test_history_width_and_stiffness_bound(self, fam):
        law = SCENE_LAWS[fam][0]
        f = _family(fam, law)
        assert f.history_width(2) >= 1
        assert f.stiffness_bound(law) > 0

    def test_engines_declared(self, fam):
        assert set(fam.engines) >= {"yade", "liggghts"}

    def test_apart_clears_history(self, fam):
        f = _family(fam, SCENE_LAWS[fam][0])
        hist = np.ones((1, f.history_width(2)))
        _separate(f.params(), hist)
        assert not hist.any()

    def test_continue_from_keeps_leading_columns(self, fam):
        f = _family(fam, SCENE_LAWS[fam][0])
        w = f.history_width(2)
        old = np.arange(6.0).reshape(2, 3)
        new = f.continue_from(old, w)
        assert new.shape == (2, w)
        assert np.array_equal(new[:, :min(w, 3)], old[:, :min(w, 3)])


def test_linear_law_compiled_call_equals_the_reference_function():
    """The interface call computes exactly linear_contact (eqs 2.11-2.20) and updates the history."""
    law = SCENE_LAWS[Linear][0]
    for normal, sliding in (("incremental", "cs"), ("overlap", "thesis")):
        f = _family(Linear, law, ContactModel(normal=normal, sliding=sliding))
        p = f.params()
        hist = np.array([[50.0, 30.0]])
        Fn, Fs, sl, e = _one_contact(p, hist, 1e-3, 0.2, -0.7, 1e-3)
        N, S, Fn0, Fs0, sl0 = linear_contact(1e-3, 0.2, -0.7, 50.0, 30.0, 1e-3, law.kn, law.ks, law.cn, law.cs,
                                             law.friction, 0.0, p.normal_mode, p.sliding_mode, True)
        assert (Fn, Fs, sl) == (Fn0, Fs0, sl0)
        assert hist[0, 0] == N and hist[0, 1] == S
        assert e == 0.5 * N ** 2 / law.kn + 0.5 * S ** 2 / law.ks


def test_linear_energy_is_the_spring_energy():
    """Overlap spring at rest: N = kN δ, energy N²/2kN = kN δ²/2 (a wrong factor fails)."""
    law = LinearLaw(kn=4e4)
    p = _family(Linear, law, ContactModel(normal="overlap")).params()
    hist = np.zeros((1, 1))
    Fn, Fs, sl, e = _one_contact(p, hist, 0.01, 0.0, 0.0, 1e-3)
    assert Fn == 400.0 and Fs == 0.0
    assert math.isclose(e, 0.5 * 4e4 * 0.01 ** 2, rel_tol=1e-15)


def test_build_refuses_a_law_no_family_implements():
    from demflow import SceneError

    class Odd:
        def check(self, pair):
            pass

    sc = Scene(name="t", discs=Discs(x=[0.0, 3.0], y=[0.0, 0.0], radius=[1.0, 1.0], material="a"),
               materials={"a": Material(1.0)}, laws={("a", "a"): Odd()}, dt=1e-3)
    with pytest.raises(SceneError, match="no law family implements"):
        build(sc)
