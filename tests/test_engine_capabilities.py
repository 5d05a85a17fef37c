"""The capabilities table (demflow.engines.capabilities): every row renders on the model-equivalence
page, the deck writers refuse what an engine cannot express, and the decks of the stored reference
runs are written byte for byte as stored (no engine needed)."""
import dataclasses
import json
import math
import html

import numpy as np
import pytest

from demflow import ContactModel, GlobalDamping, Servo, build
from demflow.cases.cs_nine_disc import NineDisc
from demflow.cases.cs_nine_disc_engines import CASE, engine_scene
from demflow.engines import EngineUnsupported, LiggghtsEngine, YadeEngine, reference
from demflow.engines.capabilities import CANNOT, ENGINE_NAMES, FEATURES, MATCHING, VERDICTS, feature
from demflow.engines.equivalence import as_html
from demflow.scene import Box, Fluid

P = NineDisc().merged()
ENGINES = {"yade": YadeEngine, "liggghts": LiggghtsEngine}


def test_every_feature_row_renders():
    page = as_html()
    assert page.count("<tr>") == len(FEATURES) + 1
    for f in FEATURES:
        for text in (f.item, f.demflow, f.yade.construct, f.liggghts.construct, f.measured):
            assert html.escape(text) in page, (f.key, text)
        for e in ("yade", "liggghts"):
            ex = f.expression(e)
            assert ex.verdict in VERDICTS, (f.key, e, ex.verdict)
            if ex.verdict in (CANNOT, MATCHING):  # refused somewhere: the table knows when and what to do
                assert f.uses is not None and f.remedy, (f.key, e)
    assert len({f.key for f in FEATURES}) == len(FEATURES)


def _servo(sc):
    w = sc.walls[0]
    sc.walls = [dataclasses.replace(w, phases=(), servo=Servo(force=1.0, direction=(0.0, 1.0), gain=1e-9,
                                                              v_max=1.0))] + list(sc.walls[1:])
    return sc


def _superquadrics(d):
    from demflow import Superquadrics

    n = len(d.x)
    r = np.broadcast_to(np.asarray(d.radius, dtype=float), (n,))
    return Superquadrics(x=d.x, y=d.y, a=r, b=r, n=np.full(n, 4.0), material=d.material)


USING = {  # feature key -> a nine-disc scene that uses it (starting from the engine-matching undamped scene)
    "normal-spring": lambda sc: dataclasses.replace(sc, contact_model=ContactModel(normal="incremental")),
    "sliding-rule": lambda sc: dataclasses.replace(sc, contact_model=ContactModel(normal="overlap",
                                                                                  sliding="thesis")),
    "cohesion": lambda sc: dataclasses.replace(sc, laws={k: dataclasses.replace(v, cohesion=1.0)
                                                         for k, v in sc.laws.items()}),
    "global-damping": lambda sc: dataclasses.replace(sc, damping=GlobalDamping(alpha=1.0)),
    "servo-walls": _servo,
    "pore-fluid": lambda sc: dataclasses.replace(sc, fluid=Fluid(viscosity=1.0)),
    "superquadrics-2d": lambda sc: dataclasses.replace(sc, discs=_superquadrics(sc.discs)),
    "periodic-y-2d": lambda sc: dataclasses.replace(sc, box=Box(periodic_y=(-1000.0, 1000.0))),
}
REFUSED = [(f.key, e) for f in FEATURES for e in ENGINES if f.uses and f.expression(e).verdict in (CANNOT, MATCHING)]


def test_every_refusable_feature_has_a_test_scene():
    assert {k for k, _ in REFUSED} == set(USING)


@pytest.mark.parametrize("key, engine", REFUSED, ids=[f"{k}-{e}" for k, e in REFUSED])
def test_deck_writer_refuses_what_the_engine_cannot_express(key, engine, tmp_path):
    sc = USING[key](engine_scene("undamped", P))
    assert feature(key).uses(sc)
    with pytest.raises(EngineUnsupported) as err:
        ENGINES[engine]().write_deck(sc, None, tmp_path)  # refused before anything is built or written
    msg = str(err.value)
    f = feature(key)
    assert ENGINE_NAMES[engine] in msg and f.item in msg and repr(key) in msg and f.remedy in msg
    assert not any(tmp_path.iterdir())


def test_global_damping_expressed_by_yade_refused_by_liggghts(tmp_path):
    sc = engine_scene("damped", P)
    sim = build(sc)
    YadeEngine().write_deck(sc, sim, tmp_path / "yade")
    with pytest.raises(EngineUnsupported, match="LIGGGHTS cannot express global damping.*undamped variant"):
        LiggghtsEngine().write_deck(sc, sim, tmp_path / "liggghts")


def test_pair_values_beyond_the_series_rule_are_set_per_contact(tmp_path):
    """A disc-wall friction above the disc-disc one (YADE takes the smaller angle of two materials): the deck gives
    the disc-wall contacts the pair's values itself (capabilities row pair-stiffness); a disc-disc pair stays on
    the material rule."""
    sc = engine_scene("undamped", P)
    laws = dict(sc.laws)
    (dd, dw) = sorted(laws, key=lambda k: k[0] == k[1])[::-1][:2]  # a disc-disc and a disc-wall pair
    laws[dw] = dataclasses.replace(laws[dw], friction=2.0 * laws[dd].friction + 0.1)
    sc = dataclasses.replace(sc, laws=laws)
    YadeEngine().write_deck(sc, build(sc), tmp_path)
    S = json.loads((tmp_path / "scene.json").read_text())
    disc, wall = dw if dw[0] == dd[0] else dw[::-1]
    assert S["wall_phys"][wall][disc]["mu"] == laws[dw].friction
    assert math.tan(S["yade_materials"][disc]["phi"]) == pytest.approx(laws[dd].friction, rel=1e-15)


@pytest.mark.parametrize("variant, engine", [(v, e) for v, es in reference.available(CASE).items() for e in es])
def test_decks_of_stored_references_are_rewritten_byte_for_byte(variant, engine, tmp_path):
    """The deck, scene.json and meshes the writer produces now equal those stored with the reference."""
    stored = reference.location(CASE, variant, engine)
    sc = engine_scene(variant, P)
    written = ENGINES[engine]().write_deck(sc, build(sc), tmp_path)
    names = {p.name for p in written}
    assert names == {p.name for p in stored.iterdir() if p.name.startswith("deck") or p.suffix == ".stl"
                     or p.name == "scene.json"}
    for name in names:
        assert (tmp_path / name).read_bytes() == (stored / name).read_bytes(), name
