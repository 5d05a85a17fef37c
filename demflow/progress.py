"""Progress bars for long runs (tqdm).

Every run loop (2D and 3D ``Simulation.run``), ``demflow validate`` (per case), ``demflow reference``
(per variant) and the studies built on them report progress through :func:`bar`.  A bar appears only
when the run lasts longer than :data:`DELAY_S` seconds and standard error is a terminal (tqdm's own
rule for ``disable=None``), so tests, CI logs and short runs print nothing.  :func:`enable` forces
bars on (True), off (False) or back to the automatic rule (None); ``demflow --no-progress`` calls
``enable(False)``.
"""
from __future__ import annotations

from contextlib import contextmanager

DELAY_S = 2.0  # a bar shows only after this long: "runs longer than a few seconds"
_enabled: bool | None = None


def enable(flag: bool | None) -> None:
    """Force progress bars on (True), off (False), or leave them to the terminal test (None)."""
    global _enabled
    if flag not in (True, False, None):
        raise ValueError(f"progress.enable({flag!r}): pass True, False or None")
    _enabled = flag


def _disable(flag: bool | None):
    flag = _enabled if flag is None else flag
    return None if flag is None else not flag  # tqdm: None = off unless a terminal


class _Null:
    n = 0

    def update(self, k=1):
        self.n += k

    def set_postfix_str(self, *a, **k):
        pass

    def close(self):
        pass


@contextmanager
def bar(total: int, desc: str, unit: str = "step", show: bool | None = None, leave: bool = False):
    """A progress bar of ``total`` units, closed on exit; ``show`` overrides :func:`enable` for this bar.
    Yields an object with ``update(k)``."""
    disable = _disable(show)
    if disable is True:
        b = _Null()
    else:
        from tqdm.auto import tqdm

        b = tqdm(total=int(total), desc=desc, unit=unit, delay=DELAY_S, disable=disable, leave=leave,
                 dynamic_ncols=True)
    try:
        yield b
    finally:
        b.close()


def iterate(items, desc: str, unit: str, show: bool | None = None):
    """``items`` with a progress bar over them (list-like)."""
    items = list(items)
    with bar(len(items), desc, unit, show, leave=True) as b:
        for it in items:
            if hasattr(b, "set_postfix_str"):
                b.set_postfix_str(str(it))
            yield it
            b.update(1)
