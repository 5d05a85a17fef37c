"""Trade-off study pages (issue 17 item 1): a :class:`~demflow.tradeoff.TradeoffStudy` of a case as a
case of its own, so `demflow validate` draws its error-vs-cost figure with the Pareto front and the
recommended setting, and shows the knob table.

A study's ``params`` are text, so that `--set` can change them:

- ``knob``, ``values`` (comma-separated, coarse to fine), ``reference``: the main knob, its values and
  its value in the reference run;
- ``knobs``: more knobs, ``"name=v1,v2;name2=w1,w2"`` (their reference values are those of ``fixed``,
  else the studied case's defaults);
- ``fixed``: parameters of the studied case set in every run, ``"name=value;name=value"`` (one seed
  instead of eight, a shorter run: what makes a study affordable);
- ``floor_param``, ``floor_value``: the chaos floor, one parameter set on top of the reference;
- optional: ``resolution`` (the knobs whose values run coarse to fine toward the reference: their
  error must shrink; default the main knob when the class says ``knob_is_resolution``),
  ``observables`` (keep the observables whose names contain one of these ``;``-separated strings),
  ``scale`` (the smallest reference magnitude a relative error divides by), ``warmup`` ("last": the
  last knob run compiles the kernels untimed; "none"; or ``"name=value;..."``: a cheap run, the
  reference with these overrides).

Every value is converted to the type of the studied case's default (:func:`parse_assignments`).
Each study's checks are self-consistency: along a resolution knob the error must shrink toward the
reference at every refinement (a knob whose error does not shrink is not what limits the result, or
the study is wrong: it shows as a failed check; a check whose errors all lie within ``accept`` × the
chaos floor says so, passed or failed); the reference runs once more as the study's last run and must give
the same observables to the bit (self-consistency: determinism; the two runs' costs give the study's timing
noise, :func:`demflow.tradeoff.timing_noise`); the chaos floor and the recommended setting are reported
(informative), the floor with how far its cost is from the reference's (:func:`demflow.tradeoff.cost_floor`: with
the timing noise, what makes two settings equally cheap).
"""
from __future__ import annotations

import math

from ..tradeoff import REPEAT, took
from .base import Case, CaseRun, Check


def _floor_cost(fl, ref, s) -> str:
    """The chaos floor's cost against the reference's, as the floor's line states it: the relative difference of the
    cost compared and, where both record them, the particle-steps each did (the work itself may follow the chaos)."""
    if s.cost_floor is None:  # a study without a floor run
        return ""
    text = f"; its {'simulation' if s.cost == 'sim_s' else 'wall'} time is {s.cost_floor:.0%} from the reference's"
    a, b = float(fl.get("particle_steps", math.nan)), float(ref.get("particle_steps", math.nan))
    if math.isfinite(a) and math.isfinite(b) and b > 0:
        text += (f" (the same work: {a:.4g} particle-steps" if a == b else
                 f" (it did {a:.4g} particle-steps against the reference's {b:.4g}, {abs(a - b) / b:.0%} apart")
        text += ")"
    return text


def typed(text, default):
    """``text`` converted to the type of ``default`` (bool from 1/0/true/false/yes/no; an int from
    "16" or "16.0"; a float; None or a str default: the text itself)."""
    if not isinstance(text, str):
        text = str(text)
    s = text.strip()
    if isinstance(default, bool):
        low = s.lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"{text!r}: expected a boolean (1/0, true/false, yes/no)")
    if isinstance(default, int):
        f = float(s)
        if not f.is_integer():
            raise ValueError(f"{text!r}: expected an integer (the default is {default!r})")
        return int(f)
    if isinstance(default, float):
        return float(s)
    return s


def parse_assignments(text: str, defaults: dict, what: str = "fixed") -> dict:
    """``"name=value;name=value"`` → {name: value}, each value converted to the type of ``defaults[name]``
    (the studied case's parameters); an unknown name or a value of the wrong type is refused with the
    case's parameter list."""
    out = {}
    for item in str(text or "").split(";"):
        if not item.strip():
            continue
        if "=" not in item:
            raise ValueError(f"{what}={text!r}: write name=value;name=value (got {item.strip()!r})")
        k, v = (x.strip() for x in item.split("=", 1))
        if k not in defaults:
            raise KeyError(f"{what}: the studied case has no parameter {k!r}; parameters: {sorted(defaults)}")
        try:
            out[k] = typed(v, defaults[k])
        except ValueError as e:
            raise ValueError(f"{what}: {k}={e.args[0]}") from None
    return out


def parse_knobs(text: str, defaults: dict) -> dict:
    """``"name=v1,v2;name2=w1,w2"`` → {name: [v1, v2], ...}, typed as :func:`parse_assignments`."""
    out = {}
    for item in str(text or "").split(";"):
        if not item.strip():
            continue
        if "=" not in item:
            raise ValueError(f"knobs={text!r}: write name=v1,v2;name2=w1,w2 (got {item.strip()!r})")
        k, vals = (x.strip() for x in item.split("=", 1))
        if k not in defaults:
            raise KeyError(f"knobs: the studied case has no parameter {k!r}; parameters: {sorted(defaults)}")
        out[k] = [typed(v, defaults[k]) for v in vals.split(",") if v.strip()]
    return out


class TradeoffCase(Case):
    """A study of ``study_case`` (see the module docstring)."""

    study_case = ""
    knob_is_resolution = True  # coarse → fine along the main knob's values: the error must shrink

    def settings(self, p) -> dict:
        """The study's settings parsed from its text params: knobs, reference, floor, fixed, observables,
        resolution knobs, scale, warmup."""
        from . import get_case

        d = get_case(self.study_case).params
        fixed = parse_assignments(p.get("fixed", ""), d, "fixed")
        # `--set values=1e-5,5e-6` arrives as the text of a tuple: "(1e-05, 5e-06)"
        values = str(p["values"]).strip().strip("()[]")
        knobs = {p["knob"]: [typed(v, d[p["knob"]]) for v in values.split(",") if v.strip()]}
        knobs.update(parse_knobs(p.get("knobs", ""), d))
        reference = dict(fixed, **{p["knob"]: typed(p["reference"], d[p["knob"]])})
        floor = {p["floor_param"]: typed(p["floor_value"], d[p["floor_param"]])} if p.get("floor_param") else None
        res = p.get("resolution")
        resolution = ([p["knob"]] if self.knob_is_resolution else []) if res is None else \
            [k.strip() for k in str(res).split(",") if k.strip()]
        unknown = [k for k in resolution if k not in knobs]
        if unknown:
            raise KeyError(f"resolution: {unknown} are not knobs of this study ({sorted(knobs)})")
        obs = [o.strip() for o in str(p.get("observables", "")).split(";") if o.strip()] or None
        w = str(p.get("warmup", "last")).strip()
        warmup = True if w in ("last", "") else False if w == "none" else parse_assignments(w, d, "warmup")
        return dict(knobs=knobs, reference=reference, floor=floor, fixed=fixed, resolution=resolution,
                    observables=obs, scale=float(p.get("scale", 1e-12)), warmup=warmup)

    def study(self, p):
        from ..tradeoff import TradeoffStudy

        s = self.settings(p)
        return TradeoffStudy(self.study_case, s["knobs"], reference=s["reference"], floor=s["floor"], scale=s["scale"],
                             warmup=s["warmup"], observables=s["observables"])

    def run(self, p) -> CaseRun:
        s = self.study(p).compute()
        return CaseRun(extras={"study": s})

    def checks(self, run, p):
        s = run.extras["study"]
        t = s.table
        out = []
        for knob in self.settings(p)["resolution"]:
            k = t[t.knob == knob]
            if len(k) < 2:
                continue
            errs = k.error.to_numpy()
            shrinking = bool(all(b < a for a, b in zip(errs, errs[1:])))
            note = ""
            if s.floor_error > 0 and bool((errs <= s.accept * s.floor_error).all()):
                note = (f"; every error is within {s.accept:g} × the chaos floor {s.floor_error:.3g}: this knob's "
                        "effect is not resolved above the chaos")
            out.append(Check.condition(
                f"{knob}: the error shrinks toward the reference at every refinement ({', '.join(map(str, k.value))};"
                f" errors {', '.join(f'{e:.3g}' for e in errs)}{note}; value: finest error / coarsest)", shrinking,
                errs[-1] / errs[0] if errs[0] > 0 else 0.0, self.source,
                "Convergence: a resolution knob whose error does not fall as it approaches the reference is not "
                "measured by this study (its effect is below the chaos floor, or the reference is not fine enough).",
                kind="self-consistency"))
        if s.floor:
            fl = t[t.run == "chaos floor"].iloc[0]
            # a measured time goes in the text, never in the name: names identify a check across runs
            out.append(Check.info(f"chaos floor: {', '.join(f'{k} = {v}' for k, v in s.floor.items())} on top of the "
                                  f"reference (error {s.floor_error:.3g})", s.floor_error,
                                  self.source, "How far a physically irrelevant change moves the observables: a knob's "
                                  f"error is only meaningful above it. Its run took {took(fl, s.cost)}"
                                  f"{_floor_cost(fl, t[t.run == 'reference'].iloc[0], s)}."))
        rep = t[t.run == REPEAT].iloc[0]
        out.append(Check.condition(
            "reference (repeat): the reference run once more as the study's last run gives the same observables to "
            "the bit (value: its error against the reference)", s.repeat_identical, float(rep.error), self.source,
            "Determinism (same scene, same parameters, same bits): the repeat measures the host's timing noise over the "
            f"study and nothing else. Its run took {took(rep, s.cost)}, the reference's "
            f"{took(t[t.run == 'reference'].iloc[0], s.cost)}.", kind="self-consistency"))
        rec = s.recommended
        why, tie = s.reason()
        out.append(Check.info(f"recommended: {rec['run']} (error {rec['error']:.3g}; {why})", rec["error"], self.source,
                              f"The recommendation, not a pass/fail: see the figure and the table. Its run took "
                              f"{took(rec, s.cost)}.{' ' + tie if tie else ''}"))
        return out

    def tables(self, run, p):
        s = run.extras["study"]
        t = s.table.copy()
        t["value"] = t.value.astype(str).where(t.knob != "", "")
        ref = ", ".join(f"{k} = {v}" for k, v in s.reference.items())
        return [(f"Knob table: error (rms relative, vs the reference run: {ref}) and cost", t)]

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


__all__ = ["TradeoffCase", "ImpactTradeoff", "parse_assignments", "parse_knobs", "typed"]
