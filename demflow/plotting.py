"""Figures a person looks at; every function takes ``ax=None`` and returns the Axes."""
from __future__ import annotations

import numpy as np


def contact_force_diagram(results, step=None, ax=None, max_width=None, color="k"):
    """C&S contact-force diagram (C&S Fig. 5b): a rectangle through each contact, along the
    contact force, of length the sum of the radii (the disc radius for a wall contact) and
    width proportional to the force magnitude; discs and walls drawn thinly.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon

    if ax is None:
        _, ax = plt.subplots()
    parts = results.particles
    cons = results.contacts
    if step is None:
        step = int(parts.step.max())
    p = parts[parts.step == step]
    c = cons[cons.step == step]
    for x, y, r in zip(p.x, p.y, p.radius):
        ax.add_patch(Circle((x, y), r, fill=False, lw=0.4, color="0.5"))
    geo = results.walls.get("geometry")
    if geo is not None and len(geo):
        g = geo[geo.step == step]
        for _, w in g.iterrows():
            ax.plot([w.px + w.h1 * w.ex, w.px + w.h2 * w.ex], [w.py + w.h1 * w.ey, w.py + w.h2 * w.ey],
                    color="0.3", lw=1.5)
    rad = dict(zip(p.id, p.radius))
    if len(c):
        tx, ty = c.ny.to_numpy(), -c.nx.to_numpy()
        Fx = c.fn.to_numpy() * c.nx.to_numpy() + c.fs.to_numpy() * tx
        Fy = c.fn.to_numpy() * c.ny.to_numpy() + c.fs.to_numpy() * ty
        F = np.hypot(Fx, Fy)
        Fmax = F.max() if F.max() > 0 else 1.0
        wmax = max_width if max_width is not None else 0.4 * float(p.radius.mean())
        for k in range(len(c)):
            if F[k] <= 0:
                continue
            ux, uy = Fx[k] / F[k], Fy[k] / F[k]
            i, j = int(c.i.iloc[k]), int(c.j.iloc[k])
            L = rad[i] + (rad[j] if j >= 0 else 0.0)
            wdt = wmax * F[k] / Fmax
            cx, cy = c.px.iloc[k], c.py.iloc[k]
            hx, hy = 0.5 * L * ux, 0.5 * L * uy
            vx, vy = -0.5 * wdt * uy, 0.5 * wdt * ux
            ax.add_patch(Polygon([(cx - hx - vx, cy - hy - vy), (cx + hx - vx, cy + hy - vy),
                                  (cx + hx + vx, cy + hy + vy), (cx - hx + vx, cy - hy + vy)],
                                 closed=True, color=color, lw=0))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xticks([])
    ax.set_yticks([])
    return ax


def save_figure(fig, path, dpi=110) -> str:
    """Lay out, write and close a figure; returns the path (for a case's list of figures)."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return str(path)


def finish_figure(fig, ax, path, *, xlabel, ylabel, title, legend_fontsize=None):
    """Label ``ax``, add its legend (if ``legend_fontsize``), save ``fig`` to ``path``; returns ``path``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if legend_fontsize:
        ax.legend(fontsize=legend_fontsize)
    save_figure(fig, path)
    return path
