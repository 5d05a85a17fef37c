"""The stability matrix (issue 17 item 2): a test per row (2D and 3D), every cell stable or a clear error, and
the observer's negative controls (an unstable run with the detector silenced is garbage; the drift bound
fails for a run that loses energy).  The drift row runs 1e5 steps here (the case's default is 1e6)."""
import math

import pytest

from demflow.cases import get_case
from demflow.cases.stability_matrix import (cells, drift_check, drift_control, garbage_control, garbage_control3d,
                                           run_cell)

DRIFT_STEPS = 100_000
ROWS = sorted({c.row for c in cells(DRIFT_STEPS)})


@pytest.mark.parametrize("row", ROWS)
def test_row(row, tmp_path, monkeypatch):
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    for cell in (c for c in cells(DRIFT_STEPS) if c.row == row):
        out = run_cell(cell)
        assert out.outcome == cell.expect, (cell.setting, out.outcome, out.detail)
        if cell.row == "energy drift":
            d, bound = drift_check(out)
            assert d <= bound, (d, bound)


def test_every_row_of_the_issue_is_in_the_matrix():
    assert set(ROWS) == {"time step", "stiffness ratio", "radius ratio", "friction", "BEM gap", "viscosity",
                         "energy drift", "3D time step", "3D friction", "ellipsoid time step"}
    # every row has a stable cell, and the rows with a limit have a clear-error cell too
    for row in ROWS:
        kinds = {c.expect for c in cells(DRIFT_STEPS) if c.row == row}
        assert "stable" in kinds, row
    for row in ("time step", "BEM gap", "viscosity", "3D time step", "ellipsoid time step"):
        assert {"refused", "stopped"} <= {c.expect for c in cells(DRIFT_STEPS) if c.row == row}, row


def test_observer_sees_garbage_when_the_detector_is_silenced(tmp_path, monkeypatch):
    """Negative control: at 1.05 × the critical step with energy_check='warn' the run completes; the
    observer must call it garbage (the kinetic energy grows ~1e7-fold)."""
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    out = garbage_control()
    assert out.outcome == "garbage", out.detail
    assert "kinetic energy" in out.detail


def test_observer_sees_garbage_in_3d_when_the_detector_is_silenced(tmp_path, monkeypatch):
    """The 3D negative control: the FCC packing at 1.1 × its critical step with energy_check='warn' completes,
    and the observer calls it garbage (its kinetic energy grows by orders of magnitude)."""
    monkeypatch.setenv("DEMFLOW_BLOWUP_DIR", str(tmp_path))
    out = garbage_control3d()
    assert out.outcome == "garbage", out.detail
    assert "kinetic energy" in out.detail


def test_drift_bound_fails_for_a_dissipative_run():
    out = drift_control(DRIFT_STEPS)
    d, bound = drift_check(out)
    assert math.isfinite(d) and d > bound, (d, bound)


def test_case_is_registered_with_its_checks():
    case = get_case("stability-matrix")
    assert case.params["drift_steps"] == 1_000_000 and not case.slow
