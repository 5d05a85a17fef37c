"""The README's current-state speed table is generated from benchmarks/results (issue 18 item 5:
"README figures equal the latest results file"); these tests hold the README to the results files and
the table's arithmetic to a hand-worked example."""
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _module():
    spec = importlib.util.spec_from_file_location("update_speed_table", ROOT / "scripts" / "update_speed_table.py")
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def test_the_readme_carries_the_generated_speed_table():
    u = _module()
    readme = (ROOT / "README.md").read_text()
    inside = readme[readme.index(u.BEGIN) + len(u.BEGIN):readme.index(u.END)].strip()
    assert inside == u.block(), "README's speed table is stale: run scripts/update_speed_table.py"


def test_every_listed_run_has_its_results_files():
    u = _module()
    for tag, *_ in u.RUNS_3D + u.RUNS_2D:
        assert (u.RESULTS / f"{tag}.json").is_file(), tag
        assert (u.RESULTS / f"{tag}.md").is_file(), tag


def _row(num_rounds, den_rounds):
    """A size's row as the benchmarks write it: best wall rate and the per-round rates."""
    def eng(rates):
        return dict(rate_wall=max(rates), rounds=[dict(round=i, rate_wall=r) for i, r in enumerate(rates)])
    return dict(engines={"demflow-1": eng(num_rounds), "liggghts": eng(den_rounds)})


def test_ratios_pair_rounds_by_their_index_not_by_rank():
    u = _module()
    # rounds: 6/3 = 2, 4/4 = 1, 9/3 = 3 -> median 2; best against best 9/4 = 2.25
    best, med = u.ratios(_row([6.0, 4.0, 9.0], [3.0, 4.0, 3.0]), "demflow-1", "liggghts")
    assert best == pytest.approx(2.25)
    assert med == pytest.approx(2.0)
    assert u.ratios(_row([1.0], [1.0]), "demflow-1", "yade") is None


def test_a_cell_is_marked_by_the_best_ratio_against_the_target():
    u = _module()
    assert u.cell((1.5, 1.2), 1.5) == "1.50× (1.20×) met"
    assert u.cell((1.49, 1.6), 1.5) == "1.49× (1.60×) missed"
    assert u.cell(None, 1.5) == "—"
