"""Structure of the code base (issue 12): small kernel signatures, no reads of another object's
private state, the law and box selected by type."""
from __future__ import annotations

import ast
from pathlib import Path

import demflow

ROOT = Path(demflow.__file__).parent
NAMEDTUPLE_API = {"_replace", "_fields", "_asdict", "_make"}
MAX_PARAMETERS = 25


def _functions():
    for p in sorted(ROOT.rglob("*.py")):
        for n in ast.walk(ast.parse(p.read_text())):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield p, n


def _n_params(fn: ast.FunctionDef) -> int:
    a = fn.args
    return (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None)
            + (a.kwarg is not None))


def test_no_function_takes_more_than_25_parameters():
    big = [f"{p.relative_to(ROOT)}:{fn.lineno} {fn.name} ({_n_params(fn)})" for p, fn in _functions()
           if _n_params(fn) > MAX_PARAMETERS]
    assert not big, f"functions with more than {MAX_PARAMETERS} parameters: {big}"


def test_the_parameter_walk_sees_a_long_signature():
    """Negative control: the walk counts every kind of parameter."""
    fn = ast.parse("def f(a, /, b, *c, d, e=1, **g): pass").body[0]
    assert _n_params(fn) == 6


def test_no_module_reads_private_attributes_of_another_object():
    """Only an object's own class touches its private attributes (``obj._x`` with obj not self/cls)."""
    found = []
    for p in sorted(ROOT.rglob("*.py")):
        for n in ast.walk(ast.parse(p.read_text())):
            if not (isinstance(n, ast.Attribute) and n.attr.startswith("_") and not n.attr.startswith("__")):
                continue
            if n.attr in NAMEDTUPLE_API:
                continue
            v = n.value
            if isinstance(v, ast.Name) and v.id in ("self", "cls"):
                continue
            if p.name == "simulation.py" and isinstance(v, ast.Name) and v.id == "other":
                continue  # Simulation.continue_from(other) reads another Simulation
            found.append(f"{p.relative_to(ROOT)}:{n.lineno} {ast.unparse(n)}")
    assert not found, f"reads of private attributes: {found}"
