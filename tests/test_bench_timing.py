"""The engines' speed benchmarks time LIGGGHTS in its own process (benchmarks/bench_engines.py): the deck's one
``run 2S`` becomes ``run S`` and ``run S pre no`` and the second run's "Loop time" is the time of steps S..2S.  These tests hold
the rewrite and the log parsing to that, and (live) that the split run is the same simulation as the single one."""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from bench_engines import liggghts_loop_times, split_run  # noqa: E402

# LIGGGHTS 3.8.0's lines after a run (the format of its Finish::end, as in the logs the benchmarks read)
LOG = """Step Atoms KinEng c_csum
       0     1200 0.00012 7038
     200     1200 0.00011 7030
Loop time of 0.528553 on 1 procs for 200 steps with 1200 atoms, 99.9% CPU use with 1 MPI tasks x no OpenMP threads

Pair  time (%) = 0.3 (56.7)
Step Atoms KinEng c_csum
     200     1200 0.00011 7030
     400     1200 0.0001 7020
Loop time of 0.51 on 1 procs for 200 steps with 1200 atoms, 99.8% CPU use with 1 MPI tasks x no OpenMP threads
"""


def test_loop_times_are_read_in_order_with_their_step_counts():
    assert liggghts_loop_times(LOG) == [(0.528553, 200), (0.51, 200)]
    assert liggghts_loop_times("Loop time of 1.5e+01 on 1 procs for 7 steps with 3 atoms") == [(15.0, 7)]
    assert liggghts_loop_times("Pair time (%) = 0.3\nNeighbor list builds = 4\n") == []


def test_benchmark_reader_gives_the_end_of_the_run_asked_for(tmp_path):
    """The engine's reader of the benchmark log: run=-1 (default) the last thermo line, run=0 the first run's last
    (the state at step S of a split deck); a run the log does not hold is refused by name."""
    from demflow.engines.base import EngineOutputError
    from demflow.engines.liggghts3d import read_benchmark_output

    (tmp_path / "log.liggghts").write_text(LOG.replace("c_csum", "csum") + "DEMFLOW-COMPLETE\n")
    last, first = read_benchmark_output(tmp_path), read_benchmark_output(tmp_path, run=0)
    assert (last["steps"], last["kinetic"], last["sphere_contacts"]) == (400, 0.0001, 3510.0)
    assert (first["steps"], first["kinetic"], first["sphere_contacts"]) == (200, 0.00011, 3515.0)
    assert read_benchmark_output(tmp_path, run=1) == last
    with pytest.raises(EngineOutputError, match="run=2 asked of .* holds 2 run"):
        read_benchmark_output(tmp_path, run=2)


def test_split_run_rewrites_the_one_run_of_2S_and_nothing_else(tmp_path):
    deck = tmp_path / "deck.in"
    deck.write_text("thermo 1000\nrun 400\nprint \"DEMFLOW-COMPLETE\"\n")
    split_run(deck, 200)
    assert deck.read_text() == "thermo 1000\nrun 200\nrun 200 pre no\nprint \"DEMFLOW-COMPLETE\"\n"


@pytest.mark.parametrize("text", ["run 300\n", "run 400\nrun 400\n", "thermo 400\n"])
def test_split_run_refuses_a_deck_without_exactly_one_run_of_2S(tmp_path, text):
    deck = tmp_path / "deck.in"
    deck.write_text(text)
    with pytest.raises(RuntimeError, match="expected one 'run 400' line"):
        split_run(deck, 200)
    assert deck.read_text() == text  # left as it was


@pytest.mark.engines
def test_live_split_run_is_the_single_run(tmp_path):
    """The 3D benchmark deck run as ``run S`` and ``run S pre no`` ends as the ``run 2S`` deck does.  The benchmark's
    equivalence table compares the engines at a few 1e-3 (touching contacts, kinetic energy); the split must
    change the run far less than that: kinetic energy within 1e-6 relative and the same touching-contact count at
    step 2S, and the time of steps S..2S is the second loop time.  (With a plain second ``run S`` LIGGGHTS sets up
    again and the kinetic energy differed by 2.4e-4: this test failed; ``pre no`` skips that setup.)"""
    from packing3d import dense_fcc

    from demflow import build
    from demflow.engines.liggghts3d import Liggghts3DEngine, read_benchmark_output
    from bench_engines import ExternalRunner
    from bench_engines3d import liggghts_scene

    S = 40
    sc = liggghts_scene(dense_fcc(1200))
    single = tmp_path / "single"
    single.mkdir()
    E = Liggghts3DEngine(benchmark=True)
    E.run(dataclasses.replace(sc, n_steps=2 * S), single, timeout=600, sim=build(dataclasses.replace(sc, n_steps=2 * S)))
    runner = ExternalRunner("liggghts", sc, S, tmp_path, 600, E=Liggghts3DEngine(benchmark=True))
    m = runner.measure()
    a = read_benchmark_output(single)
    b = read_benchmark_output(runner.dirs[2])
    assert a["steps"] == b["steps"] == 2 * S
    assert a["sphere_contacts"] == b["sphere_contacts"]
    assert abs(a["kinetic"] - b["kinetic"]) <= 1e-6 * abs(a["kinetic"])
    loops = liggghts_loop_times((runner.dirs[2] / "log.liggghts").read_text())
    assert [s for _, s in loops] == [S, S] and m["dt_wall"] == loops[1][0] and m["loop_S"] == loops[0][0]
