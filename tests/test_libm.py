"""What a simulation starts from does not depend on numpy's CPU-specific code (demflow.libm).

numpy picks, per CPU, among versions of several float64 ufuncs that round differently (SVML on AVX-512 CPUs, its
own AVX2 code for tanh): a sphere's mass from ``r ** 3`` came out one bit apart on AVX-512 and AVX2-only hosts, and
the 3D golden bed and the stored 3D conformance decks with it.  ``tests/libm_probe.py`` hashes what demflow computes
from scenes before and during a short run; here it runs in two fresh processes, with numpy as it comes and with
every CPU-specific version switched off (``NPY_DISABLE_CPU_FEATURES``), and the hashes must agree.  On an AVX-512
CPU that covers SVML; on an AVX2-only CPU the versions numpy has for it (tanh, and exp, log, sin, cos, which
measured equal to libm there).  The negative control shows the harness sees a numpy function that has such a
version on this CPU.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from demflow import libm

PROBE = Path(__file__).parent / "libm_probe.py"


def cpu_specific_features() -> list[str]:
    """The CPU features numpy dispatches to beyond its baseline that this CPU has (what to switch off)."""
    from numpy._core import _multiarray_umath as m

    have = m.__cpu_features__
    return [f for f in m.__cpu_dispatch__ if have.get(f)]


def run_probe(simd: bool, control: bool = False) -> dict:
    env = dict(os.environ)
    env.pop("NPY_DISABLE_CPU_FEATURES", None)
    if not simd:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(cpu_specific_features())
    done = subprocess.run([sys.executable, str(PROBE)] + (["--control"] if control else []), capture_output=True,
                          text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def probes():
    if not cpu_specific_features():
        pytest.skip("numpy dispatches to no CPU-specific code on this CPU")
    return run_probe(True, control=True), run_probe(False, control=True)


def test_scenes_come_out_the_same_without_numpy_cpu_specific_code(probes):
    with_simd, without = probes
    differ = [k for k in with_simd if not k.startswith("control") and with_simd[k] != without[k]]
    assert not differ, f"these depend on numpy's CPU-specific code (use demflow.libm): {differ}"


def test_negative_control_a_numpy_function_with_a_cpu_specific_version_is_seen(probes):
    """np.tanh (float64) has an AVX2 and an AVX-512 version (numpy 2.4); where this CPU runs one, the harness
    must see it.  Skipped where numpy runs its baseline tanh on this CPU."""
    from numpy._core import _multiarray_umath as m

    tanh = m.__cpu_targets_info__.get("tanh", {}).get("dd", {}) if hasattr(m, "__cpu_targets_info__") else {}
    if not tanh or tanh.get("current", "").startswith("baseline"):
        pytest.skip("numpy runs its baseline float64 tanh on this CPU: no CPU-specific version to see")
    with_simd, without = probes
    assert with_simd["control: np.tanh"] != without["control: np.tanh"]


@pytest.mark.parametrize("name, f, args", [
    ("cube", lambda v: math.pow(v, 3.0), (np.random.default_rng(1).uniform(1e-4, 10.0, 5000),)),
    ("power", math.pow, (np.random.default_rng(2).uniform(1e-3, 10.0, 5000), np.random.default_rng(3).uniform(-3, 3, 5000))),
    ("sin", math.sin, (np.random.default_rng(4).uniform(-20, 20, 5000),)),
    ("cos", math.cos, (np.random.default_rng(5).uniform(-20, 20, 5000),)),
    ("log", math.log, (np.random.default_rng(6).uniform(1e-6, 1e3, 5000),)),
    ("arcsin", math.asin, (np.random.default_rng(7).uniform(-1, 1, 5000),)),
    ("arccosh", math.acosh, (np.random.default_rng(8).uniform(1, 50, 5000),)),
    ("tanh", math.tanh, (np.random.default_rng(9).uniform(-5, 5, 5000),)),
])
def test_each_function_is_the_c_librarys_element_by_element(name, f, args):
    got = getattr(libm, name)(*args)
    want = np.array([f(*v) for v in zip(*args)])
    assert got.dtype == np.float64 and got.shape == args[0].shape
    assert np.array_equal(got.view(np.int64), want.view(np.int64))


def test_shapes_and_scalars_are_kept():
    assert libm.cube(2.0).shape == () and float(libm.cube(2.0)) == 8.0
    x = np.arange(6.0).reshape(2, 3) + 1.0
    assert libm.cube(x).shape == (2, 3)
    assert libm.power(x, np.array([1.0, 2.0, 3.0])).shape == (2, 3)
