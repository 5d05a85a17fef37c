"""The speed-accuracy study object (issue 17 item 1): a knob study of the two-disc impact, its table,
Pareto front, recommendation and figure; the CLI; bad knobs refused."""
import subprocess
import sys

import numpy as np
import pytest

from demflow.tradeoff import TradeoffStudy, pareto_front


def test_pareto_front_keeps_the_non_dominated_points():
    cost = [1, 2, 3, 4, 2]
    err = [5, 3, 4, 1, 6]
    assert pareto_front(cost, err).tolist() == [True, True, False, True, False]


@pytest.fixture(scope="module")
def study():
    return TradeoffStudy("thesis-impact", {"dt": [4e-5, 1e-5, 2.5e-6]}, reference={"dt": 1e-6},
                         floor={"kn": 1.0001e7}).compute()


def test_the_study_measures_error_and_cost_per_knob_value(study):
    t = study.table
    assert list(t.run) == ["reference", "chaos floor", "dt = 4e-05", "dt = 1e-05", "dt = 2.5e-06"]
    assert t.error.iloc[0] == 0.0 and 0 < study.floor_error < 1e-5
    errs = t[t.knob == "dt"].error.to_numpy()
    assert np.all(np.diff(errs) < 0)  # the error falls as Δt approaches the reference's
    assert np.all(t.wall_s > 0) and np.all(np.isfinite(t.particle_steps_per_s))  # the cost of every run is there
    assert t.pareto.any() and t.recommended.sum() == 1
    rec = study.recommended
    assert rec["knob"] == "dt" and (study.within_floor or rec["error"] == errs.min())


def test_the_plot_draws_every_run(study):
    import matplotlib

    matplotlib.use("Agg")
    ax = study.plot()
    n_points = sum(len(c.get_offsets()) for c in ax.collections if hasattr(c, "get_offsets"))
    assert n_points >= len(study.table)


def test_a_knob_the_case_does_not_have_is_refused():
    with pytest.raises(KeyError, match="has no parameter 'dtt'"):
        TradeoffStudy("thesis-impact", {"dtt": [1e-5]})
    with pytest.raises(ValueError, match="at least one value"):
        TradeoffStudy("thesis-impact", {"dt": []})


def test_the_cli_writes_table_and_figure(tmp_path):
    out = subprocess.run([sys.executable, "-m", "demflow.cli", "--no-progress", "tradeoff", "thesis-impact",
                          "--knob", "dt=2e-5,1e-5", "--reference", "dt=5e-6", "--floor", "kn=1.0001e7",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "recommended:" in out.stdout
    assert {p.name for p in tmp_path.iterdir()} >= {"tradeoff.parquet", "tradeoff.txt", "tradeoff.png"}
