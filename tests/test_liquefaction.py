"""thesis-liquefaction (§5.3): the column buckles, the contacts break and the pore pressure rises to F_y/L."""
import numpy as np
import pytest

from demflow.cases import CASES


@pytest.fixture(scope="module")
def case():
    return CASES["thesis-liquefaction"]


def test_liquefaction_passes_every_check(case, tmp_path):
    p = case.merged({})
    res = case.run(p)
    failed = [c.name for c in case.checks(res, p) if not c.passed]
    assert not failed
    # compressive pressure is positive (demflow.bem): the walls are pushed outward by F_y/L
    assert case.wall_pressure(res["wet"].pore_pressure)["bottom"][0] > 0.9 * p["Fy"] / p["box"]
    assert case.figures(res, p, str(tmp_path))


def test_without_load_transfer_the_pore_pressure_stays_near_zero(case):
    p = case.merged(dict(load=False, study="64"))
    res = case.run(p)
    q = p["Fy"] / p["box"]
    end = case.wall_pressure(res["wet"].pore_pressure)
    assert abs(end["bottom"][0]) < 0.01 * q  # no WallLoad: nothing hands the unbalanced load to the fluid
    checks = {c.name.split(":")[0]: c for c in case.checks(res, p)}
    assert not checks["pore pressure on wall 1 (BEM, mean along the wall) at γ = 0.7 % vs F_y/L"].passed
    assert checks["contacts broken"].passed  # the solid phase behaves the same
