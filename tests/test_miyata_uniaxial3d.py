"""The uniaxial compression case's particles (issue 14, issue 16 item 2): clumps of the seed's ellipsoid or the
ellipsoid itself, each 191 kg; a particle's top (where the plate starts) and a clear error for an unknown shape.
The case itself is slow (``demflow validate --case miyata-uniaxial-3d``)."""
import math
import warnings

import numpy as np
import pytest

import demflow as df
from demflow.cases import get_case
from demflow.cases.miyata_uniaxial3d import insertion_scene, particle_tops
from demflow.shapes.clump import MIYATA_AXES, MIYATA_MASS


def _built(shape, n_insert=4):
    p = get_case("miyata-uniaxial-3d").merged({"shape": shape, "n_insert": n_insert})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", df.UnsafeTimeStepWarning)
        return df.build(insertion_scene(p))


@pytest.mark.parametrize("shape", ["clumps", "ellipsoids"])
def test_every_particle_weighs_191_kg(shape):
    sim = _built(shape)
    np.testing.assert_allclose(sim.bodies.mass, MIYATA_MASS, rtol=1e-12)


def test_an_ellipsoids_top_is_its_support_along_z():
    """Identity orientation: the top is z + a3; turned 90° about x (body y along world z): z + a2; a clump's top
    is its highest member's."""
    sim = _built("ellipsoids", n_insert=2)
    s = math.sqrt(0.5)
    sim.bodies.quat[:] = [[1.0, 0.0, 0.0, 0.0], [s, s, 0.0, 0.0]]
    from demflow.shapes.ellipsoid import rotations
    rotations(sim.bodies.quat, sim.ell.rot)
    z = sim.spheres.pos[:, 2]
    np.testing.assert_allclose(particle_tops(sim) - z, [MIYATA_AXES[2], MIYATA_AXES[1]], rtol=1e-12)
    c = _built("clumps", n_insert=2)
    assert np.all(particle_tops(c) <= c.spheres.pos[:, 2].max() + c.spheres.r.max())


def test_an_unknown_shape_is_refused_naming_it():
    case = get_case("miyata-uniaxial-3d")
    with pytest.raises(df.SceneError, match=r"shape='spheres'.*'clumps'.*'ellipsoids'"):
        case.run(case.merged({"shape": "spheres"}))


def test_bed_figures_write_a_vtk_bed_and_a_plate_force_map(tmp_path):
    """The figure page's bed picture (matplotlib), its VTK file (member centres with radius and body) and
    the plate force map of the last snapshot."""
    from demflow.cases.miyata_uniaxial3d import bed_figures

    rng = np.random.default_rng(0)
    pos = rng.uniform(0.0, 2.0, (16, 3))
    bed = {"pos": pos, "r": np.full(16, 0.15), "body": np.repeat(np.arange(2), 8), "plate_z": 2.1, "box": 2.0}
    snaps = [{"stress": 4e5, "plate": np.array([1e5, 2e5]), "floor": np.array([1e5]),
              "plate_xy": np.array([[0.5, 0.5], [2.5, 1.0]])}]  # an unwrapped centre is drawn inside the box
    paths = bed_figures({"bed": bed, "snapshots": snaps}, tmp_path)
    vtu = (tmp_path / "bed_end.vtu").read_text(errors="replace")
    assert str(tmp_path / "bed_end.vtu") in paths and 'NumberOfPoints="16"' in vtu and "radius" in vtu and "body" in vtu
    assert (tmp_path / "bed_and_plate_map.png").stat().st_size > 10000
