"""Trade-off study pages (issue 17 item 1): a :class:`~demflow.tradeoff.TradeoffStudy` of a case as a
case of its own, so `demflow validate` draws its error-vs-cost figure with the Pareto front and the
recommended setting, and shows the knob table.

Each study's checks are self-consistency: along a resolution knob (Δt) the error must shrink toward
the reference (a knob whose error does not shrink is not what limits the result, or the study is
wrong), and the recommended setting is reported with its error and cost (informative).
"""
from __future__ import annotations

from .base import Case, CaseRun, Check


class TradeoffCase(Case):
    """A study of ``study_case`` (see the module docstring); ``params`` hold the knob values as text so
    `--set` can change them: knob (one parameter), values (comma-separated, coarse to fine), reference
    (the reference value of the knob), floor_param/floor_value (the chaos-floor change)."""

    study_case = ""
    knob_is_resolution = True  # coarse → fine along the listed values: the error must shrink

    def study(self, p):
        from ..tradeoff import TradeoffStudy

        vals = [float(v) for v in str(p["values"]).split(",") if v.strip()]
        floor = {p["floor_param"]: float(p["floor_value"])} if p["floor_param"] else None
        return TradeoffStudy(self.study_case, {p["knob"]: vals}, reference={p["knob"]: float(p["reference"])},
                             floor=floor)

    def run(self, p) -> CaseRun:
        s = self.study(p).compute()
        return CaseRun(extras={"study": s})

    def checks(self, run, p):
        s = run.extras["study"]
        t = s.table
        k = t[t.knob == p["knob"]]
        out = []
        if self.knob_is_resolution and len(k) >= 2:
            errs = k.error.to_numpy()
            shrinking = bool(all(b < a for a, b in zip(errs, errs[1:])))
            out.append(Check.condition(
                f"{p['knob']}: the error shrinks toward the reference at every refinement ({', '.join(map(str, k.value))};"
                f" value: finest error / coarsest)", shrinking, errs[-1] / errs[0] if errs[0] > 0 else 0.0, self.source,
                "Convergence: a resolution knob whose error does not fall as it approaches the reference is not "
                "measured by this study.", kind="self-consistency"))
        rec = s.recommended
        why = (f"the cheapest within {s.accept:g} × the chaos floor {s.floor_error:.3g}" if s.within_floor else
               f"none is within {s.accept:g} × the chaos floor {s.floor_error:.3g}: the most accurate")
        out.append(Check.info(f"recommended: {rec['run']} (error {rec['error']:.3g}, {rec['wall_s']:.3g} s; {why})",
                              rec["error"],
                              self.source, "The recommendation, not a pass/fail: see the figure and the table."))
        return out

    def tables(self, run, p):
        t = run.extras["study"].table
        return [("Knob table: error (rms relative, vs the reference run) and cost", t)]

    def figures(self, run, p, outdir):
        import matplotlib.pyplot as plt

        from ..plotting import save_figure

        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        run.extras["study"].plot(ax)
        return [save_figure(fig, f"{outdir}/tradeoff.png")]


class ImpactTradeoff(TradeoffCase):
    name = "tradeoff-thesis-impact"
    title = "Speed vs accuracy: the time step of the two-disc impact (thesis Table 2.4)"
    source = "thesis §2.2.5.3 (knob study, issue 17)"
    study_case = "thesis-impact"
    assumptions = ("Reference: Δt = 1e-6 s (10× below the thesis's 1e-5); chaos floor: kN × 1.0001 (the impact is "
                   "not chaotic: the floor is the observables' sensitivity to a 1e-4 change of stiffness).",)
    params = dict(knob="dt", values="4e-5,2e-5,1e-5,5e-6", reference=1e-6, floor_param="kn", floor_value=1.0001e7)


__all__ = ["TradeoffCase", "ImpactTradeoff"]
