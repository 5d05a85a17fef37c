"""3D golden test: the 3D cycle's results to the bit (a guard for optimising the 3D kernels).

The scene (``tests/golden3d_scenes.py``) touches every part of the 3D cycle: Hertz-Mindlin with
friction and dashpots, local damping, periodic x/y, a floor, a servo plate, a triangle-mesh ramp,
orientations, records.  Every array of its final state and of its records must equal the stored
file bit for bit.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import golden3d_laws as gl  # noqa: E402
import golden3d_scenes as g3  # noqa: E402
from test_golden import assert_same_bits  # noqa: E402


def test_golden3d_bits():
    _, got = g3.run("bed3d")
    with np.load(g3.GOLDEN / "bed3d.npz", allow_pickle=False) as want:
        assert_same_bits("bed3d", got, want)


def test_golden3d_ellipsoid_bits():
    """The ellipsoid cycle (Lin & Ng pairs, ellipsoid-plane and -triangle contacts, the aspherical body step),
    written before its geometry helpers were inlined (session 13)."""
    _, got = g3.run("ell3d")
    with np.load(g3.GOLDEN / "ell3d.npz", allow_pickle=False) as want:
        assert_same_bits("ell3d", got, want)


def test_ellipsoid_pair_geometry_bits():
    """The Lin & Ng pair geometry, every output to the bit on 3000 configurations (cold and warm starts, the
    fallback): tests/golden_ellipsoid_pairs.py, written before the geometry was computed lane by lane, under
    OpenBLAS's Haswell kernels, which the comparison runs with (the fallback's LAPACK call rounds otherwise
    under the SkylakeX kernels of an AVX-512 host: this test failed there until 2026-11-27)."""
    from blas_kernels import can_run, run_under

    if not can_run("Haswell"):
        pytest.skip("the file was written under OpenBLAS's Haswell kernels, which need AVX2 and FMA")
    code = f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); import golden_ellipsoid_pairs as gp; " \
           "print(gp.compare())"
    done = run_under("Haswell", ["-c", code])
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().splitlines()[-1] == "same", done.stdout[-2000:]


@pytest.mark.parametrize("name", gl.VARIANTS)
def test_golden3d_law_variant_bits(name):
    """The 3D law variants the golden bed does not run (tests/golden3d_laws.py), to the bit against the code of
    91c46a5: Mindlin-Deresiewicz's 8-column history, the total shear spring, the linear 3D law."""
    import demflow

    sim = demflow.build(gl.scene(name))
    sim.run(gl.STEPS)
    got = gl.state(sim)
    with np.load(g3.GOLDEN / "laws3d.npz", allow_pickle=False) as want:
        for k, a in got.items():
            b = want[f"{name}/{k}"]
            assert a.shape == b.shape and a.dtype == b.dtype, f"{name} {k}: {a.shape} {a.dtype} != {b.shape} {b.dtype}"
            assert a.tobytes() == b.tobytes(), f"{name} {k}: bits differ from the code of 91c46a5"
    assert (got["ovl"] > 0).sum() > 400  # the variant's contacts are exercised, not an empty pass
