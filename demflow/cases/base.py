"""What every registered case provides: scenes, runs, checks and figures.

A case is a class with a stable ``name``; its ``params`` (defaults) can be overridden from
the CLI (``--set key=value``).  ``scenes(p)`` returns the scenes of its variants;
``run(p)`` runs them and returns a :class:`CaseRun` (the :class:`~demflow.results.Results`
of each variant, plus any extra data the checks need); ``checks`` compares with the source's
reference values using tolerances from :mod:`demflow.tolerances` (informative lines are
:meth:`Check.info`, never counted as passes or failures); ``figures`` draws what a person
looks at.  Hooks instead of name branches: ``reference_plan`` (``demflow reference``),
``comparison_case`` (``demflow compare``), ``tables`` and ``page_sections`` (the report page),
``observables`` (what a speed-accuracy study compares).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..tolerances import KINDS, VALIDATION_KINDS, tol

if TYPE_CHECKING:
    import pandas as pd

    from ..results import Results
    from ..scene import Scene

INFO = "info"  # the kind of an informative line (Check.info)
MISS = "miss"  # the kind of a source figure not reproduced (Check.miss)


@dataclass
class Check:
    """One validation check: value vs reference, within a tolerance from tolerances.py.

    ``kind`` says what the reference is (:data:`demflow.tolerances.KINDS`): a source's figure, an
    exact solution, another code, a self-consistency identity, a calibration (a lost parameter
    fitted to this very figure: never counted as validation) or "info" (:meth:`info`): shown on
    the report with its value, never counted as a pass or a failure.
    """

    name: str
    value: float
    reference: float
    tolerance: float
    source: str
    why: str
    relative: bool = True
    kind: str = ""
    passed: bool = field(init=False)
    error: float = field(init=False)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"check {self.name!r}: kind {self.kind!r} is not one of {KINDS}; say what its reference "
                             f"is (demflow/tolerances.py explains each kind)")
        diff = abs(self.value - self.reference)
        self.error = diff / abs(self.reference) if self.relative and self.reference != 0 else diff
        self.passed = bool(math.isfinite(self.error) and self.error <= self.tolerance)

    @classmethod
    def against(cls, name, value, reference, tolerance_name, source):
        """value vs reference within the named tolerance of tolerances.py, whose ``kind`` it takes."""
        t = tol(tolerance_name)
        return cls(name, float(value), float(reference), t.value, source, t.why, relative=not t.absolute, kind=t.kind)

    @classmethod
    def condition(cls, name, ok: bool, value: float, source: str, why: str, *, kind: str):
        """A qualitative check (e.g. 'faster loading gives larger oscillation'): value is reported."""
        c = cls(name, float(value), float(value), 0.0, source, why, relative=False, kind=kind)
        c.passed = bool(ok)
        c.error = 0.0 if ok else math.inf
        return c

    @classmethod
    def info(cls, name, value, source, why, reference=None):
        """An informative line (not pass/fail): ``value`` shown beside ``reference`` (same units;
        without one the value is its own reference), with the relative error; tolerance ∞."""
        if reference is None:
            c = cls(name, float(value), float(value), math.inf, source, why, relative=False, kind=INFO)
        else:
            c = cls(name, float(value), float(reference), math.inf, source, why, kind=INFO)
        c.passed = True
        return c

    @classmethod
    def miss(cls, name, value, reference, source, cause, relative=True):
        """A source figure demflow does not reproduce: its value beside the source's ``reference``,
        the error, and ``cause`` (what was measured to explain the difference).  Never a pass; not a
        failure of the case either (the case claims no agreement here): the report lists it as a miss."""
        c = cls(name, float(value), float(reference), math.inf, source, "NOT REPRODUCED. " + cause,
                relative=relative, kind=MISS)
        c.passed = False
        return c

    @property
    def informative(self) -> bool:
        return self.kind in (INFO, MISS)


def kind_of(check) -> str:
    """The kind of a Check or of its summary dict; a summary written before kinds existed marks an
    informative line by its infinite (or null) tolerance and leaves the others "unclassified"."""
    if isinstance(check, dict):
        return check.get("kind") or (INFO if check["tolerance"] in (math.inf, None) else "unclassified")
    return check.kind


def kind_counts(checks) -> dict[str, dict[str, int]]:
    """{kind: {"passed": n, "total": m}} over Check objects or their summary dicts, in KINDS order."""
    out = {}
    for c in checks:
        k = kind_of(c)
        row = out.setdefault(k, {"passed": 0, "total": 0})
        row["total"] += 1
        row["passed"] += bool(c["passed"] if isinstance(c, dict) else c.passed)
    order = list(KINDS) + sorted(set(out) - set(KINDS))
    return {k: out[k] for k in order if k in out}


def validation_passes(checks) -> tuple[int, int]:
    """(passed, total) over the checks that count as validation (not calibration, not info)."""
    vc = [c for c in checks if kind_of(c) in VALIDATION_KINDS]
    return sum(bool(c["passed"] if isinstance(c, dict) else c.passed) for c in vc), len(vc)


def counted(checks) -> list:
    """The pass/fail checks of a list (the informative lines and the known misses left out): Check
    objects or their summary dicts."""
    return [c for c in checks if kind_of(c) not in (INFO, MISS)]


@dataclass
class CaseRun:
    """What a case's run returns: ``results`` maps a variant's name to its result tables (the
    CLI saves each under runs/CASE/VARIANT); ``extras`` holds whatever else the checks and
    figures need (packings, statistics, BEM solutions, engine rows), by name."""

    results: dict[str, Results] = field(default_factory=dict)
    extras: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ReferencePlan:
    """How ``demflow reference CASE`` makes a case's engine reference runs: the case name the runs
    are stored under (reference_runs/STORE/), the parameters, the variants an engine can run
    (engine name → variant names), the scene of a variant (variant, parameters → Scene) and,
    optionally, the engine object that runs a variant (engine name, variant → Engine; default
    ``demflow.engines.get_engine(name)``, the 2D engines)."""

    store: str
    params: dict[str, Any]
    variants: Callable[[str], tuple[str, ...]]
    scene: Callable[[str, dict], Scene]
    engine: Callable[[str, str], Any] | None = None


class ParameterError(ValueError):
    """A case parameter given a value of another kind than its default's (the message names both and the fix)."""


def coerce_parameter(case: str, key: str, default, value):
    """``value`` as the type of the parameter's ``default``, refusing what would change its meaning: a whole number
    (int default) takes an int or a float with no fraction (1e4), never 1.5; a number (float default) takes any int
    or float; a flag (bool default) takes True/False or the words true/false/yes/no/on/off, never 'false' read as
    True; a text takes a str, or a number or a comma list the command line read as one (``--set Ks=1,3,5``: the text
    '1,3,5'); a list or tuple takes a list or tuple.  A default of None takes anything."""
    import numbers

    def refuse(kind: str, example: str):
        return ParameterError(f"case {case!r}: parameter {key}={value!r} is not {kind} (its default is {default!r}); "
                              f"give e.g. --set {key}={example}")

    if default is None:
        return value
    if isinstance(default, bool):
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        words = {"true": True, "yes": True, "on": True, "false": False, "no": False, "off": False}
        if isinstance(value, str) and value.strip().lower() in words:
            return words[value.strip().lower()]
        raise refuse("a flag (True or False)", "False")
    if isinstance(default, numbers.Integral):
        if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)):
            return int(value)
        if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)) and float(value).is_integer():
            return int(value)
        raise refuse("a whole number", str(default))
    if isinstance(default, numbers.Real):
        if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
            return float(value)
        raise refuse("a number", repr(float(default)))
    if isinstance(default, str):
        if isinstance(value, str):
            return value
        if isinstance(value, (list, tuple)) and all(isinstance(x, (numbers.Real, str)) for x in value):
            return ",".join(str(x) for x in value)  # --set Ks=1,3,5 reads as a tuple: the text it was
        if isinstance(value, numbers.Real):
            return str(value)
        raise refuse("a text", repr(default))
    if isinstance(default, (list, tuple)):
        if isinstance(value, (list, tuple)):
            return type(default)(value)
        raise refuse("a list", repr(list(default)).replace(" ", ""))
    return value if isinstance(value, type(default)) else type(default)(value)


class Case:
    name: str = ""
    title: str = ""
    source: str = ""
    assumptions: tuple[str, ...] = ()
    params: dict[str, Any] = {}
    # a slow case (minutes of BEM) is left out of a plain `demflow validate`; run it by name
    # (`demflow validate --case NAME`) or with `--all`; its last result stays on the report
    slow: bool = False

    def merged(self, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
        """The case's parameters with ``overrides`` (by name) put in, each of its default's type
        (:func:`coerce_parameter`): an unknown name is a KeyError, a value of another kind a ParameterError."""
        p = dict(self.params)
        for k, v in (overrides or {}).items():
            if k not in p:
                raise KeyError(f"case {self.name!r} has no parameter {k!r}; parameters: {sorted(p)}")
            p[k] = coerce_parameter(self.name, k, p[k], v)
        return p

    def scenes(self, p) -> dict:
        raise NotImplementedError

    def run(self, p) -> CaseRun:
        from ..build import build

        return CaseRun({name: build(scene).run().results() for name, scene in self.scenes(p).items()})

    def checks(self, run: CaseRun, p) -> list[Check]:
        return []

    def figures(self, run: CaseRun, p, outdir) -> list[str]:
        return []

    def tables(self, run: CaseRun, p) -> list[tuple[str, pd.DataFrame]]:
        """(title, table) pairs shown on the case's report page."""
        return []

    # -- hooks the CLI and the report look up instead of branching on a case's name
    def reference_plan(self) -> ReferencePlan | None:
        """How `demflow reference` makes this case's engine references; None: it has none."""
        return None

    def comparison_case(self) -> Case | None:
        """A fresh case object whose ``engines`` and ``live`` the `demflow compare` command sets;
        None: the case compares no engines."""
        return None

    def observables(self, run: CaseRun, p) -> dict[str, float] | None:
        """What a speed-accuracy study (:mod:`demflow.tradeoff`) compares between runs of this case:
        {name: value}. None (the default): the values of the case's finite counted checks."""
        return None

    @staticmethod
    def page_sections() -> list[tuple[str, str]]:
        """(title, HTML) sections added to the case's report page after its checks."""
        return []
