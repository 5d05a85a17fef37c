"""What every registered case provides: scenes, runs, checks and figures.

A case is a class with a stable ``name``; its ``params`` (defaults) can be overridden from
the CLI (``--set key=value``).  ``scenes(p)`` returns the scenes of its variants;
``run(p)`` runs them (returning :class:`~demflow.results.Results` per variant, plus any
extra data the checks need); ``checks`` compares with the source's reference values using
tolerances from :mod:`demflow.tolerances`; ``figures`` draws what a person looks at.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..tolerances import tol


@dataclass
class Check:
    """One validation check: value vs reference, within a tolerance from tolerances.py."""

    name: str
    value: float
    reference: float
    tolerance: float
    source: str
    why: str
    relative: bool = True
    passed: bool = field(init=False)
    error: float = field(init=False)

    def __post_init__(self):
        diff = abs(self.value - self.reference)
        self.error = diff / abs(self.reference) if self.relative and self.reference != 0 else diff
        self.passed = bool(math.isfinite(self.error) and self.error <= self.tolerance)

    @classmethod
    def against(cls, name, value, reference, tolerance_name, source):
        t = tol(tolerance_name)
        return cls(name, float(value), float(reference), t.value, source, t.why, relative=not t.absolute)

    @classmethod
    def condition(cls, name, ok: bool, value: float, source: str, why: str):
        """A qualitative check (e.g. 'faster loading gives larger oscillation'): value is reported."""
        c = cls(name, float(value), float(value), 0.0, source, why, relative=False)
        c.passed = bool(ok)
        c.error = 0.0 if ok else math.inf
        return c


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
        p = dict(self.params)
        for k, v in (overrides or {}).items():
            if k not in p:
                raise KeyError(f"case {self.name!r} has no parameter {k!r}; parameters: {sorted(p)}")
            p[k] = type(p[k])(v) if p[k] is not None and not isinstance(v, type(p[k])) else v
        return p

    def scenes(self, p) -> dict:
        raise NotImplementedError

    def run(self, p) -> dict:
        from ..build import build

        return {name: build(scene).run().results() for name, scene in self.scenes(p).items()}

    def checks(self, results, p) -> list[Check]:
        return []

    def figures(self, results, p, outdir) -> list[str]:
        return []
