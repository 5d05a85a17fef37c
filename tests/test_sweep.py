"""Sweeps on Dask (issue 17 item 6): a sweep on a local cluster of two worker processes gives the same
table as the serial run, in the same order."""
import pandas as pd

from demflow.sweep import case_sweep, parameter_grid, run_sweep


def _square(x):
    return x * x


def test_parameter_grid_is_every_combination_in_order():
    assert parameter_grid({"a": [1, 2], "b": ["x"]}) == [dict(a=1, b="x"), dict(a=2, b="x")]


def test_a_two_worker_local_cluster_equals_the_serial_sweep():
    sets = {"kn": [1e7, 4e7], "dt": [1e-5, 2e-5]}  # 4 runs of the two-disc impact
    serial = case_sweep("thesis-impact", sets, scheduler="serial")
    dask = case_sweep("thesis-impact", sets, scheduler="local", workers=2)
    assert len(serial) == 4 * len(serial[(serial.kn == 1e7) & (serial.dt == 1e-5)]) > 0
    cols = [c for c in serial.columns if c != "wall_s"]
    pd.testing.assert_frame_equal(serial[cols], dask[cols])  # bit-identical values, same order
    assert serial.value.nunique() > 4  # the runs differ: a table of one repeated run would not


def test_run_sweep_keeps_the_items_order():
    assert run_sweep(_square, range(7), scheduler="local", workers=2) == [k * k for k in range(7)]
