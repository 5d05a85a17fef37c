"""Building blocks the cases share: a box of four walls, random sequential addition, run until.

Each was written once per case before; the cases now call these, and their results are the
same to the bit (the same walls, the same random-number calls in the same order, the same
stepping).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from ..scene import Phase, Servo, Wall

WALLS = ("bottom", "right", "top", "left")  # the order every box lists its walls in


def box_walls(x0: float, x1: float, y0: float, y1: float, *, half_length: float | tuple[float, float] | None = None,
              counter_clockwise: bool = True, material: str = "wall",
              phases: Mapping[str, Sequence[Phase]] | None = None,
              servos: Mapping[str, Servo] | None = None) -> list[Wall]:
    """The four walls (bottom, right, top, left) of the box [x0, x1] × [y0, y1] [length].

    Each wall's reference point is the middle of its side; the wall runs from −h to +h along
    its direction.  ``half_length`` h [length]: None closes the box exactly (half the side's
    length), a number gives every wall that h, a pair gives (h of bottom and top, h of right and
    left), e.g. walls longer than the box so that it stays closed while the walls move in.
    ``counter_clockwise`` directions go round the box (bottom +x, right +y, top −x, left −y: the
    thesis's convention, normals pointing out of the enclosed fluid); otherwise bottom and top
    point +x, right and left +y (C&S's box).  ``phases`` and ``servos`` map a wall's name to its
    prescribed motion and servo control.
    """
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"box_walls: box [{x0}, {x1}] × [{y0}, {y1}] is empty; give x0 < x1 and y0 < y1")
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    if half_length is None:
        h_xy = (0.5 * (x1 - x0), 0.5 * (y1 - y0))
    elif isinstance(half_length, tuple):
        h_xy = half_length
    else:
        h_xy = (half_length, half_length)
    s = -1.0 if counter_clockwise else 1.0
    geo = {"bottom": ((cx, y0), (1.0, 0.0), h_xy[0]), "right": ((x1, cy), (0.0, 1.0), h_xy[1]),
           "top": ((cx, y1), (s, 0.0), h_xy[0]), "left": ((x0, cy), (0.0, s), h_xy[1])}
    phases, servos = phases or {}, servos or {}
    unknown = sorted(set(phases) - set(WALLS)) + sorted(set(servos) - set(WALLS))
    if unknown:
        raise ValueError(f"box_walls: no wall named {unknown}; the walls are {WALLS}")
    return [Wall(w, geo[w][0], geo[w][1], -geo[w][2], geo[w][2], material, phases=tuple(phases.get(w, ())),
                 servo=servos.get(w)) for w in WALLS]


def random_sequential_addition(radii: np.ndarray | Callable[[np.random.Generator], float], box, rng: np.random.Generator,
                               *, n: int | None = None, gap: float = 0.0, tries: int = 100_000,
                               restarts: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Discs placed one after another, each uniformly at random where it overlaps none before it.

    ``radii`` [length]: the radii in placement order, or a function of ``rng`` drawn afresh at
    every try (then ``n`` discs).  ``box`` = (x0, x1, y0, y1) [length]: a disc of radius r lies
    inside it.  ``gap`` [length]: the smallest surface gap kept between discs.  Each disc gets
    ``tries`` tries; when one finds no place the arrangement is jammed and, up to ``restarts``
    times, placing starts again from the first disc (the generator's stream goes on).  Every try
    draws (x, y) with one ``rng.uniform`` call (after the radius, when drawn).

    Returns x, y, r (arrays [length]); raises RuntimeError when every restart jams.
    """
    x0, x1, y0, y1 = box
    draw = radii if callable(radii) else None
    if draw is None:
        r = np.asarray(radii, dtype=float)
    elif n is None:
        raise ValueError("random_sequential_addition: radii is a function, so give the number of discs n")
    else:
        r = np.empty(n)
    x, y = np.empty(r.size), np.empty(r.size)
    for _attempt in range(restarts + 1):
        for i in range(r.size):
            for _ in range(tries):
                ri = draw(rng) if draw is not None else r[i]
                xi, yi = rng.uniform((x0 + ri, y0 + ri), (x1 - ri, y1 - ri))
                if i == 0 or np.all((x[:i] - xi) ** 2 + (y[:i] - yi) ** 2 >= (r[:i] + ri + gap) ** 2):
                    break
            else:
                break  # jammed: start again
            x[i], y[i], r[i] = xi, yi, ri
        else:
            return x, y, r
    area = float(np.pi * np.sum(r * r) / ((x1 - x0) * (y1 - y0))) if draw is None else float("nan")
    raise RuntimeError(f"random sequential addition jammed: {r.size} discs (area fraction {area:.3g}) found no place "
                       f"in box {tuple(box)} within {tries} tries per disc and {restarts} restarts; "
                       f"use a larger box (lower area fraction), more tries or another seed")


def run_until(sim, condition: Callable[[object], bool], *, max_step: int, chunk: int = 1,
              raise_at_limit: bool = True, what: str = "the condition"):
    """Run ``sim`` ``chunk`` steps at a time until ``condition(sim)`` holds after a chunk, or until
    ``sim.step`` reaches ``max_step`` [steps].

    Returns True when the condition held, False at the limit; with ``raise_at_limit`` the limit
    raises RuntimeError instead (``what`` names the condition in the message).
    """
    if chunk < 1:
        raise ValueError(f"run_until: chunk = {chunk} steps; it must be at least 1")
    while sim.step < max_step:
        sim.run(chunk)
        if condition(sim):
            return True
    if raise_at_limit:
        raise RuntimeError(f"{what} did not hold by step {sim.step} (limit max_step = {max_step}); "
                           f"raise the limit or check the scene")
    return False
