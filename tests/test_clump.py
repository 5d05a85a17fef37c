"""Clump templates: the ellipsoid cover and the mass properties of overlapping sphere unions."""
from __future__ import annotations

import math

import numpy as np
import pytest

from demflow.shapes.clump import (MIYATA_AXES, ClumpTemplate, ellipsoid_cover, ellipsoid_moments,
                                  ellipsoid_surface_distance, ellipsoid_volume, union_mass_properties)


def test_distance_to_the_ellipsoid_surface_matches_dense_sampling():
    ax = np.array(MIYATA_AXES)
    u, v = np.meshgrid(np.linspace(0, np.pi, 801), np.linspace(0, 2 * np.pi, 1601), indexing="ij")
    surf = np.stack([ax[0] * np.sin(u) * np.cos(v), ax[1] * np.sin(u) * np.sin(v), ax[2] * np.cos(u)], -1).reshape(-1, 3)
    pts = np.array([[0.0, 0.0, 0.0], [0.2, 0.05, -0.03], [-0.3, 0.0, 0.1], [0.0, 0.2, 0.0]])
    d = ellipsoid_surface_distance(pts, ax)
    brute = np.array([np.min(np.linalg.norm(surf - p, axis=1)) for p in pts])
    assert d[0] == pytest.approx(ax[2], rel=1e-12)
    np.testing.assert_allclose(d, brute, rtol=0, atol=2e-4)  # the sampled surface is 1e-3 rad apart
    assert np.all(d <= brute + 1e-12)


def test_union_mass_converges_and_counts_an_overlap_once():
    r, d, rho = 0.1, 0.12, 2000.0
    v1 = 4 / 3 * math.pi * r ** 3
    lens = math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12  # two equal spheres, centres d apart
    exact = rho * (2 * v1 - lens)
    errs = []
    for f in (10, 20, 40):
        p = union_mass_properties([[0, 0, 0], [d, 0, 0]], [r, r], rho, h=r / f)
        errs.append(abs(p["mass"] / exact - 1))
    assert errs[2] < errs[0] and errs[2] < 1e-3
    assert p["com"] == pytest.approx([d / 2, 0, 0], abs=1e-12 + 1e-4 * r)
    one = union_mass_properties([[0.3, -0.2, 0.1]], [r], rho, h=r / 40)
    m1 = rho * v1
    assert one["mass"] == pytest.approx(m1, rel=1e-3)
    np.testing.assert_allclose(one["inertia"], 0.4 * m1 * r * r * np.eye(3), rtol=0, atol=3e-3 * 0.4 * m1 * r * r)


def test_ellipsoid_cover_stays_inside_and_converges_with_K():
    ax = np.array(MIYATA_AXES)
    fracs, moments = [], []
    for K in (4, 16, 64):
        c, r = ellipsoid_cover(ax, K)
        assert np.all(ellipsoid_surface_distance(c, ax) >= r - 1e-12)  # inscribed: never outside
        T = ClumpTemplate.from_spheres(c, r, mass=191.0)
        fracs.append(union_mass_properties(c, r, 1.0)["volume"] / ellipsoid_volume(ax))
        moments.append(T.moments / ellipsoid_moments(ax, 191.0))
    assert fracs[0] < fracs[1] < fracs[2] < 1.0
    assert fracs[2] > 0.9
    assert np.all(np.diff(np.abs(1 - np.array(moments)), axis=0) < 0)  # every moment closer with K
    assert np.all(np.abs(1 - moments[2]) < 0.06)


def test_template_is_in_its_principal_frame_with_the_given_mass():
    T = ClumpTemplate.ellipsoid_like(8)
    assert T.mass == pytest.approx(191.0, rel=1e-12)
    p = union_mass_properties(T.centres, T.radii, 1.0)
    assert np.linalg.norm(p["com"]) < 1e-12 + 1e-3 * T.radii.min()
    I = p["inertia"] * (191.0 / p["volume"])
    off = I - np.diag(np.diag(I))
    assert np.abs(off).max() < 1e-3 * np.abs(I).max()
    assert np.all(np.diff(T.moments) >= 0)  # ascending: the long axis has the smallest moment
    with pytest.raises(ValueError, match="K=0"):
        ellipsoid_cover(MIYATA_AXES, 0)
