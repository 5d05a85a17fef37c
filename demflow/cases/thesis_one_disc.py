"""thesis-one-disc: one disc settling on a plate under gravity (thesis §2.2.5.1, Table 2.1).

R = 1 m, ρ = 2400 kg/m² (m = 7539.823 kg), g = 10 m/s², kN = 1e7 N/m, Δt = 1 ms, 5000
steps.  Four damping cases.  Table 2.1's two damping columns are swapped against its text
for cases 2 and 3 (SOURCES.md); we follow the text and the physics: case 2 has global
damping C = 1e4 only (ζ = 1.8 %, leaving 3.57 % at t = 5 s), case 3 contact damping
cN = 1e5 only, case 4 cN = 1e5 and C = 4.5e5 (their sum ≈ critical).

The disc starts touching the plate at rest.  "The force at t = 5 s" is the force of the
5000th calculation cycle (cycles counted from 1, the first evaluating forces at t = 0),
i.e. step index 4999; the force one step later differs by 0.02 % in case 2 (stated in
the report).
"""
from __future__ import annotations


from ..scene import Discs, GlobalDamping, LinearLaw, Material, Outputs, Scene, Wall
from .base import Case, Check, ParameterError
from ..plotting import finish_figure

WEIGHT = 75398.23  # N, thesis §2.2.5.1 (m g with m = 7539.823 kg)
T_READ = 5.0  # s: Table 2.1's forces are read at t = 5 s, the 5000th cycle of Δt = 1e-3 s (step index 4999)
SRC = "thesis Table 2.1, §2.2.5.1"

CASES = {
    "case1-undamped": dict(C=0.0, cn=0.0),
    "case2-global-damping": dict(C=1e4, cn=0.0),
    "case3-contact-damping": dict(C=0.0, cn=1e5),
    "case4-contact-and-global": dict(C=4.5e5, cn=1e5),
}
REFERENCE = {"case2-global-damping": 72703.36, "case3-contact-damping": WEIGHT,
             "case4-contact-and-global": WEIGHT}


class OneDisc(Case):
    name = "thesis-one-disc"
    title = "One disc settling on a plate (thesis Table 2.1)"
    source = SRC
    assumptions = (
        "Table 2.1's damping columns for cases 2 and 3 are swapped against the text; the text is followed "
        "(case 2: global C = 1e4; case 3: contact cN = 1e5).",
        "The disc starts touching the plate, at rest; the reported force is that of the 5000th cycle (cycles "
        "counted from 1, the first evaluating forces at t = 0): step index 4999. The case-2 check depends on this "
        "reading: the informative line below gives the force's change over one step there, to be set against the "
        "0.01 % tolerance.",
    )
    params = dict(dt=1e-3, n_steps=5000, kn=1e7)

    @staticmethod
    def read_step(p) -> int:
        """The step whose force Table 2.1 gives: the cycle at t = 5 s counted from 1 (step index 5/Δt - 1)."""
        return int(round(T_READ / p["dt"])) - 1

    def scenes(self, p):
        k = self.read_step(p)
        if p["dt"] > 0 and (k < 1 or p["n_steps"] < k + 1):  # (dt <= 0: the scene refuses it, naming dt)
            raise ParameterError(
                f"case {self.name!r}: dt={p['dt']!r} and n_steps={p['n_steps']!r} do not reach t = {T_READ:g} s, where "
                f"Table 2.1's forces are read (step {k}; the checks also read the step before it): give "
                f"n_steps >= {max(k + 1, 2)} for this dt, or dt <= {T_READ / 2:g}")
        out = {}
        for name, d in CASES.items():
            out[name] = Scene(
                name=f"one-disc-{name}",
                discs=Discs(x=[0.0], y=[1.0], radius=[1.0], material="disc", mass=[7539.823]),
                materials={"disc": Material(density=2400.0), "plate": Material()},
                laws={("disc", "plate"): LinearLaw(kn=p["kn"], cn=d["cn"])},
                walls=[Wall("plate", (0.0, 0.0), (1.0, 0.0), -5.0, 5.0, "plate")],
                damping=GlobalDamping(C=d["C"]), gravity=(0.0, -10.0), dt=p["dt"],
                n_steps=p["n_steps"], outputs=Outputs(every=1),
                description="Table 2.1 " + name)
        return out

    @staticmethod
    def plate_force(res):
        w = res.wall("plate")
        return -w.fy.to_numpy(), w.time.to_numpy()

    @staticmethod
    def force_at(res, step: int) -> float:
        """The plate's force at step ``step`` [N] (from the step column: the records of every step)."""
        w = res.wall("plate")
        return float(-w.fy.to_numpy()[w.step.to_numpy() == step][0])

    def checks(self, run, p):
        results = run.results
        out = []
        k = self.read_step(p)
        for name, ref in REFERENCE.items():
            fk = self.force_at(results[name], k)
            out.append(Check.against(f"{name}: force at t = 5 s (the 5000th cycle, step 4999) [N]", fk, ref,
                                     "one-disc.final-force", SRC))
            if name == "case2-global-damping":
                out.append(Check.info(f"{name}: relative change of the force over the last step (how much reading "
                                      "t = 5 s as step 4999 rather than 4998 or 5000 moves it)",
                                      abs(fk - self.force_at(results[name], k - 1)) / fk, SRC,
                                      "The reading of 't = 5 s' as a step index is an assumption (see above); compare "
                                      "this change with the 1e-4 tolerance."))
        f, _ = self.plate_force(results["case1-undamped"])
        out.append(Check.against("case1-undamped: peak force / (2 W)", f.max() / (2 * WEIGHT), 1.0,
                                 "one-disc.undamped-peak", "damped-oscillator solution (thesis eq 2.39, C = 0)"))
        return out

    def figures(self, run, p, outdir):
        results = run.results
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4))
        for name, res in results.items():
            f, t = self.plate_force(res)
            ax.plot(t, f, label=name, lw=1)
        ax.axhline(WEIGHT, color="k", ls=":", lw=0.8, label="weight")
        return [finish_figure(fig, ax, f"{outdir}/plate_force.png", xlabel="time [s]",
                              ylabel="normal force on the plate [N]", title="One disc on a plate (thesis Fig. 2.10)",
                              legend_fontsize=8)]
