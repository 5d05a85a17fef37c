"""The physics manifest (issue 17 item 5): what build allocated and selected, in Results.meta and
meta.json; a scene pays only for the physics it declares."""
import json

import numpy as np

import golden3d_scenes as g3
import golden_scenes as g2
from demflow import build
from demflow.manifest import describe, physics_manifest
from demflow.results import Results
from helpers import gas_scene, random_packing


def _gas(**kw):
    x, y, r, _ = random_packing(40, 3)
    return gas_scene(x, y, r, np.zeros((len(x), 2)), **kw)


def test_a_frictionless_scene_gets_no_shear_history_and_a_frictional_one_does():
    smooth = physics_manifest(build(_gas()))
    rough = physics_manifest(build(_gas(ks=5e4, mu=0.5)))
    assert smooth["law"]["history_columns_per_contact"] == 1 and smooth["law"]["has_shear"] is False
    assert rough["law"]["history_columns_per_contact"] == 2 and rough["law"]["has_shear"] is True
    assert smooth["contact_history"]["columns"] == 1 and rough["contact_history"]["columns"] == 2


def test_a_dry_scene_builds_no_fluid_and_a_saturated_one_does():
    dry = physics_manifest(build(g2.frictional_box()))
    wet = physics_manifest(build(g2.saturated_stage()))
    assert dry["fluid"] is None and dry["external_force"] is False
    assert wet["fluid"]["model"].startswith("Stokes BEM") and wet["fluid"]["n_disc"] == 16 and wet["external_force"]
    assert "no fluid" in describe(dry) and "fluid: Stokes BEM" in describe(wet)


def test_3d_manifest_names_the_law_history_and_periodic_axes():
    m = physics_manifest(build(g3.settling_bed()))
    assert m["dim"] == 3 and m["law"]["family"] == "hertz-mindlin" and m["periodic"] == ["x", "y"]
    assert m["mesh_triangles"] == 2 and m["planes"] >= 2 and m["damping"]["local"] is True


def test_the_manifest_is_in_meta_json(tmp_path):
    sim = build(g2.frictional_box())
    sim.run(50)
    res = Results.from_simulation(sim)
    res.save(tmp_path / "r")
    meta = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert meta["physics"] == json.loads(json.dumps(physics_manifest(sim)))
    assert Results.load(tmp_path / "r").meta["physics"]["law"]["family"] == "linear"
