"""thesis-five-discs: five discs settling in a three-walled box (thesis §2.2.5.2, Tables 2.2-2.3).

Fig. 2.12 (the geometry) is lost.  Reconstruction from the statics of Table 2.2's
"theoretical" column (R = 1 m, W = 75398.23 N per disc):

* each floor contact carries 2.5 W (188495.6 N) = half the total weight, so the side walls
  carry no vertical load: walls 2 and 3 are vertical, wall 1 is the floor;
* disc 4 rests on disc 3 and against wall 2: F34 sin θ = W and F34 cos θ = 85498.4 N give
  cos θ = 0.75 (F34 = 113997.9 N ✓);
* disc 3 carries 3 W on discs 1 and 2: 2 F31 sin φ = 3 W gives sin φ = 0.6614, i.e. again
  cos φ = 0.75, and the wall-2 reaction of disc 1 is F31 cos φ = 128247.7 N ✓.

Hence: floor y = 0; discs 1, 2 at (∓1.5, 1); disc 3 at (0, 1 + h); discs 4, 5 at
(∓1.5, 1 + 2h) with h = √(4 - 1.5²) = 1.3229; walls 2, 3 at x = ∓2.5.  All contacts
touch at zero overlap at the start.  Table 2.3's (F_x, F_y) are each contact's normal
and tangential components (they reproduce with that reading).
"""
from __future__ import annotations

import math

import numpy as np

from ..scene import Discs, GlobalDamping, LinearLaw, Material, Outputs, Scene, Wall
from .base import Case, Check
from ..plotting import save_figure

W = 2400.0 * np.pi * 10.0  # one disc's weight [N]
H = float(np.sqrt(4.0 - 1.5 ** 2))
X = [-1.5, 1.5, 0.0, -1.5, 1.5]
Y = [1.0, 1.0, 1.0 + H, 1.0 + 2 * H, 1.0 + 2 * H]
SRC2 = "thesis Table 2.2, §2.2.5.2"
SRC3 = "thesis Table 2.3, §2.2.5.2"

# (thesis label, disc index a, disc index b or wall name)
CONTACTS = [("Disc 1 - Wall 1", 0, "wall1"), ("Disc 1 - Wall 2", 0, "wall2"),
            ("Disc 2 - Wall 1", 1, "wall1"), ("Disc 2 - Wall 3", 1, "wall3"),
            ("Disc 3 - Disc 1", 2, 0), ("Disc 3 - Disc 2", 2, 1), ("Disc 3 - Disc 4", 2, 3),
            ("Disc 3 - Disc 5", 2, 4), ("Disc 4 - Wall 2", 3, "wall2"), ("Disc 5 - Wall 3", 4, "wall3")]
TABLE_2_2_PREDICTED = [188492.5, 133648.0, 188491.3, 133647.8, 175075.0, 175079.4, 115750.6,
                       115760.0, 87832.7, 87828.2]
TABLE_2_2_THEORETICAL = [188495.6, 128247.7, 188495.6, 128247.7, 170996.9, 170996.9, 113997.9,
                         113997.9, 85498.4, 85498.4]
TABLE_2_3 = [(167269.7, 38775.2), (28609.2, -7665.5), (167269.7, -38774.5), (28610.1, 7664.9),
             (116104.0, -31109.8), (116103.1, 31109.6), (78747.3, 13561.1), (78749.6, -13561.0),
             (50610.7, -13561.0), (50611.1, 13561.0)]


def _walls():
    return [Wall("wall1", (0.0, 0.0), (1.0, 0.0), -2.5, 2.5, "wall"),
            Wall("wall2", (-2.5, 0.0), (0.0, 1.0), 0.0, 8.0, "wall"),
            Wall("wall3", (2.5, 0.0), (0.0, 1.0), 0.0, 8.0, "wall")]


def contact_row(contacts, a, b):
    """The row of the contact table for disc a with disc b or wall b (at the last snapshot)."""
    c = contacts[contacts.step == contacts.step.max()]
    if isinstance(b, str):
        sel = (c.i == a) & (c.wall == b)
    else:
        sel = ((c.i == a) & (c.j == b)) | ((c.i == b) & (c.j == a))
    rows = c[sel]
    if len(rows) != 1:
        raise RuntimeError(f"expected one contact between {a} and {b}, found {len(rows)}")
    return rows.iloc[0]


def frictionless_statics(normals_by_contact):
    """Solve the 10 equilibrium equations of the 5 discs for the 10 normal forces.

    normals_by_contact: list (in CONTACTS order) of unit vectors n from the first body to the
    second (the force on the first body is -F n).  The system is statically determinate.
    """
    A = np.zeros((10, 10))
    b = np.zeros(10)
    for k, ((_, a, other), n) in enumerate(zip(CONTACTS, normals_by_contact)):
        A[2 * a, k] -= n[0]
        A[2 * a + 1, k] -= n[1]
        if not isinstance(other, str):
            A[2 * other, k] += n[0]
            A[2 * other + 1, k] += n[1]
    b[1::2] = W  # Σ forces = weight upward on each disc
    return np.linalg.solve(A, b)


def rigid_normals():
    pos = np.c_[X, Y]
    wall_n = {"wall1": np.array([0.0, -1.0]), "wall2": np.array([-1.0, 0.0]), "wall3": np.array([1.0, 0.0])}
    out = []
    for _, a, b in CONTACTS:
        if isinstance(b, str):
            out.append(wall_n[b])
        else:
            d = pos[b] - pos[a]
            out.append(d / np.linalg.norm(d))
    return out


class FiveDiscs(Case):
    name = "thesis-five-discs"
    title = "Five discs settling under gravity (thesis Tables 2.2-2.3)"
    source = "thesis §2.2.5.2"
    assumptions = (
        "Geometry of the lost Fig. 2.12 reconstructed from the statics of Table 2.2's theoretical column: "
        "vertical side walls 5R apart, all disc-disc contacts at cos θ = 0.75 from the horizontal (module docstring).",
        "Δt = 1 ms (not stated for this test; the one-disc test used it), t = 5 s.",
        "Table 2.3's F_x, F_y are read as each contact's normal and tangential components.",
        "The stiff variant scales kN by 100, Δt by 1/10 and both dashpots by 10 (same damping ratios) "
        "to show the rigid-statics limit.",
    )
    params = dict(dt=1e-3, t_end=5.0, stiff_factor=100.0)

    def _scene(self, name, kn, ks, cn, cs, C, Cr, mu, dt, t_end):
        law = LinearLaw(kn=kn, ks=ks, cn=cn, cs=cs, friction=mu)
        n = int(round(t_end / dt))
        return Scene(name=name, discs=Discs(x=X, y=Y, radius=[1.0] * 5, material="disc", mass=[7539.823] * 5),
                     materials={"disc": Material(density=2400.0), "wall": Material()},
                     laws={("disc", "disc"): law, ("disc", "wall"): law}, walls=_walls(),
                     damping=GlobalDamping(C=C, C_rot=Cr), gravity=(0.0, -10.0), dt=dt, n_steps=n,
                     outputs=Outputs(every=10, snapshots=(n,)))

    def scenes(self, p):
        s = p["stiff_factor"]
        return {
            "frictionless": self._scene("five-discs-frictionless", 1e7, 0.0, 1e5, 0.0, 4.5e5, 0.0, 0.0,
                                        p["dt"], p["t_end"]),
            "frictionless-stiff": self._scene("five-discs-frictionless-stiff", 1e7 * s, 0.0, 1e5 * s ** 0.5, 0.0,
                                              4.5e5 * s ** 0.5, 0.0, 0.0, p["dt"] / s ** 0.5, p["t_end"]),
            "friction": self._scene("five-discs-friction", 1e7, 7e6, 1e5, 7e4, 4.5e5, 4.5e5,
                                    math.tan(math.radians(15.0)), p["dt"], p["t_end"]),
        }

    def checks(self, run, p):
        results = run.results
        out = []
        c = results["frictionless"].contacts
        rows = [contact_row(c, a, b) for _, a, b in CONTACTS]
        normals = []
        for (_, a, b), r in zip(CONTACTS, rows):
            n = np.array([r.nx, r.ny])
            normals.append(n if r.i == a else -n)
        deformed = frictionless_statics(normals)
        for (label, _, _), r, ref, thesis in zip(CONTACTS, rows, deformed, TABLE_2_2_PREDICTED):
            out.append(Check.against(f"Table 2.2 {label}: force vs statics of the final geometry [N]", r.fn, ref,
                                     "five-discs.deformed-statics", SRC2))
            out.append(Check.against(f"Table 2.2 {label}: force vs the thesis's predicted value [N]", r.fn, thesis,
                                     "five-discs.thesis-predicted", SRC2))
        rigid = frictionless_statics(rigid_normals())
        cs_ = results["frictionless-stiff"].contacts
        for (label, a, b), ref, theo in zip(CONTACTS, rigid, TABLE_2_2_THEORETICAL):
            r = contact_row(cs_, a, b)
            # the thesis evaluated sin θ to 4 digits (0.6614): its column agrees with exact statics to 6e-5
            assert abs(ref - theo) / theo < 1e-4, "reconstructed geometry must reproduce Table 2.2 theoretical"
            out.append(Check.against(f"Table 2.2 {label}: stiff variant vs rigid statics [N]", r.fn, ref,
                                     "five-discs.rigid-statics-stiff", SRC2))
        cf = results["friction"].contacts
        for (label, a, b), (fn_ref, fs_ref) in zip(CONTACTS, TABLE_2_3):
            r = contact_row(cf, a, b)
            out.append(Check.against(f"Table 2.3 {label}: normal force [N]", r.fn, fn_ref,
                                     "five-discs.thesis-predicted", SRC3))
            out.append(Check.against(f"Table 2.3 {label}: |shear force| [N]", abs(r.fs), abs(fs_ref),
                                     "five-discs.thesis-predicted", SRC3))
        wf = results["friction"].wall_forces
        last = wf[wf.step == wf.step.max()]
        out.append(Check.against("Table 2.3: Σ wall reactions (vertical) / total weight", -last.fy.sum() / (5 * W), 1.0,
                                 "five-discs.weight-balance", SRC3))
        return out

    def figures(self, run, p, outdir):
        results = run.results
        from ..plotting import contact_force_diagram
        import matplotlib.pyplot as plt

        paths = []
        for name in ("frictionless", "friction"):
            fig, ax = plt.subplots(figsize=(4.5, 5))
            contact_force_diagram(results[name], ax=ax)
            ax.set_title(f"five discs, {name}: contact forces at t = {p['t_end']} s", fontsize=9)
            path = f"{outdir}/forces_{name}.png"
            save_figure(fig, path)
            paths.append(path)
        return paths
