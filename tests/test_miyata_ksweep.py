"""miyata-uniaxial-3d-ksweep (issue 16 item 3): the comparison, the Pareto front and the recommendation rule on
made-up seed statistics whose answers are known; the case's parameter errors.  The protocol runs themselves are
the miyata-uniaxial-3d case's (tests/test_miyata_uniaxial3d.py); the whole sweep is a slow report page."""
from __future__ import annotations

import math

import numpy as np
import pytest

from demflow.cases import get_case
from demflow.cases.miyata_ksweep import (ALPHA, KEY_STATISTICS, compare_shapes, indistinguishable,
                                         largest_relative_difference, pareto_front, recommend)
from demflow.scene import SceneError

OTHER = ("q-model N, plate", "particles on the plate (mean of snapshots)")


def _seeds(values_per_key: dict[str, list[float]]) -> dict[int, dict]:
    n = len(next(iter(values_per_key.values())))
    return {s: {k: float(v[s]) for k, v in values_per_key.items()} for s in range(n)}


def _shape(shift: dict[str, float] | None = None, scale: float = 1.0) -> dict[int, dict]:
    base = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0])  # mean 4.5, s.d. 2.449
    shift = shift or {}
    return _seeds({k: list(10.0 + scale * base + shift.get(k, 0.0)) for k in KEY_STATISTICS + OTHER})


def test_a_copy_of_the_reference_is_indistinguishable_and_a_shifted_one_is_not():
    stats = {"ellipsoids": _shape(), "K = 5": _shape(), "K = 1": _shape({"particles after trimming": 10.0})}
    t = compare_shapes(stats)
    assert all(t["K = 5"][k]["diff"] == 0.0 and t["K = 5"][k]["welch p"] == pytest.approx(1.0) for k in KEY_STATISTICS)
    assert indistinguishable(t["K = 5"])
    row = t["K = 1"]["particles after trimming"]
    assert row["diff"] == pytest.approx(10.0)
    assert row["relative"] == pytest.approx(10.0 / 14.5)
    assert row["in reference s.d."] == pytest.approx(10.0 / np.std(np.arange(1, 9), ddof=1))
    assert row["welch p"] < ALPHA
    assert not indistinguishable(t["K = 1"])
    assert largest_relative_difference(t["K = 1"]) == ("particles after trimming", pytest.approx(10.0 / 14.5))


def test_a_shift_in_a_shown_statistic_does_not_count():
    """Only KEY_STATISTICS decide: the plate's count and q-model N are shown, not used."""
    stats = {"ellipsoids": _shape(), "K = 3": _shape({"q-model N, plate": 50.0})}
    t = compare_shapes(stats)
    assert t["K = 3"]["q-model N, plate"]["welch p"] < ALPHA
    assert indistinguishable(t["K = 3"])


def test_the_welch_test_is_scipys():
    from scipy import stats as st

    stats = {"ellipsoids": _shape(), "K = 8": _shape({"bed top before loading [m]": 2.0}, scale=1.5)}
    t = compare_shapes(stats)
    a = [s["bed top before loading [m]"] for s in stats["K = 8"].values()]
    b = [s["bed top before loading [m]"] for s in stats["ellipsoids"].values()]
    assert t["K = 8"]["bed top before loading [m]"]["welch p"] == pytest.approx(
        st.ttest_ind(a, b, equal_var=False).pvalue, rel=1e-12)


def test_nan_seeds_are_left_out_and_a_statistic_without_a_test_is_distinguishable():
    e = _shape()
    k = _shape()
    k[0]["plate height at 600 kPa [m]"] = math.nan
    t = compare_shapes({"ellipsoids": e, "K = 12": k})
    assert t["K = 12"]["plate height at 600 kPa [m]"]["n"] == 7
    assert indistinguishable(t["K = 12"])
    for s in k.values():
        s["plate height at 600 kPa [m]"] = math.nan
    t = compare_shapes({"ellipsoids": e, "K = 12": k})
    assert not indistinguishable(t["K = 12"])


def test_the_recommendation_is_the_cheapest_indistinguishable_cover():
    stats = {"ellipsoids": _shape(), "K = 1": _shape({"bed top before loading [m]": 30.0}),
             "K = 5": _shape({"plate height at 400 kPa [m]": 0.5}), "K = 12": _shape()}
    t = compare_shapes(stats)
    cost = {"ellipsoids": 70.0, "K = 1": 1.0, "K = 5": 8.0, "K = 12": 20.0}
    assert indistinguishable(t["K = 5"]) and not indistinguishable(t["K = 1"])
    r = recommend(t, cost)
    assert r["choice"] == "K = 5" and r["indistinguishable"]
    # negative control: when every cover differs, the closest one is named and not called a reproduction
    stats["K = 5"] = _shape({"plate height at 400 kPa [m]": 20.0})
    stats["K = 12"] = _shape({"plate height at 400 kPa [m]": 15.0})
    r = recommend(compare_shapes(stats), cost)
    assert r["choice"] == "K = 12" and not r["indistinguishable"]
    assert "no cover reproduces" in r["why"]


def test_pareto_front():
    pts = {"ellipsoids": (70.0, 0.0), "K = 1": (1.0, 0.5), "K = 3": (2.0, 0.6), "K = 8": (15.0, 0.2),
           "K = 24": (40.0, 0.25)}
    assert pareto_front(pts) == ["K = 1", "K = 8", "ellipsoids"]


@pytest.mark.parametrize("over, match", [(dict(Ks="0,3"), "K >= 1"), (dict(Ks="three"), "sphere counts"),
                                         (dict(band_seeds=2), ">= 3")])
def test_bad_parameters_are_refused_with_the_fix(over, match):
    case = get_case("miyata-uniaxial-3d-ksweep")
    with pytest.raises(SceneError, match=match):
        case.run(case.merged(over))
