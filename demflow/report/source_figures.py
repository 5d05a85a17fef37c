"""Every quantitative figure of the four sources (../shared/SOURCES.md), and what demflow makes of it.

:data:`FIGURES` lists the figures, each with the checks that test it (case name and a pattern on the
check's name) or the issue that will add its case.  :func:`table` builds the table from a validation
summary: the numbers (demflow's value, the reference, the error, the tolerance and its justification)
come from the checks themselves, never from this file.  A figure's status:

- ``reproduced``: every check on it is a validation check (source, exact, cross-code, self-consistency)
  and passes;
- ``not reproduced``: at least one check on it is a known miss (:meth:`Check.miss`), shown with its
  measured cause; or a validation check on it fails;
- ``calibration``: a lost parameter was fitted to this very figure (not validation);
- ``shown``: only informative lines (no accuracy stated to judge against);
- ``not run on this report``: a slow case, not in this summary;
- ``no case yet``: the issue that will add it.
"""
from __future__ import annotations

import html
import math
import re
from dataclasses import dataclass

from ..cases.base import INFO, MISS, kind_of
from ..tolerances import VALIDATION_KINDS


@dataclass(frozen=True)
class Figure:
    source: str  # thesis, C&S, Miyata, ch3
    where: str  # table, section or figure number
    what: str  # the figure as the source states it
    checks: tuple = ()  # ((case, regular expression on the check name), ...)
    pending: str = ""  # "issue N: what" when no case covers it yet


FIGURES = (
    Figure("thesis", "Table 2.1", "one disc on a plate: final force 72703.36 N (global damping 1e4), 75398.66 N "
           "(contact damping), 75397.49 N (both)", (("thesis-one-disc", r"force at t = 5 s"),
                                                   ("thesis-one-disc", r"peak force / \(2 W\)"))),
    Figure("thesis", "Table 2.2", "five frictionless discs: per-contact forces (thesis's predicted values)",
           (("thesis-five-discs", r"^Table 2\.2 .*(predicted|statics|rigid)"),)),
    Figure("thesis", "Table 2.3", "five discs, φ = 15°: per-contact normal and shear forces",
           (("thesis-five-discs", r"^Table 2\.3"),)),
    Figure("thesis", "Table 2.4", "two-disc elastic impact: post-impact velocities (2.598, 1.500), (−2.598, 4.500) "
           "m/s, < 1 % error", (("thesis-impact", r"vs (exact linear-spring|Table 2\.4)"),)),
    Figure("thesis", "§4.4.1", "cylinder midway in a channel: T/μU = 24.20 (literature 24.15, 24.55, 24.23)",
           (("thesis-bem-cylinder-poiseuille", r"T/μU"),)),
    Figure("thesis", "§4.4.2", "cylinder between planes moving at U: T/μU = 97.29 (literature 98.8, 99.4); the "
           "channel width is only in the lost figure", (("thesis-bem-cylinder-moving-planes", r"T/μU vs|thesis value"),)),
    Figure("thesis", "§4.4.3", "free rectangle in Poiseuille flow: U_p/U = 1.3017 (literature 1.3041, 1.31)",
           (("thesis-bem-free-rectangle", r"U_p/U vs|finite elements"),)),
    Figure("thesis", "§5.1", "disc falling between walls: terminal velocity −0.9535 cm/s (Takaisi), thesis −0.9306",
           (("thesis-falling-disc", r"terminal velocity|Takaisi|thesis"),)),
    Figure("thesis", "§5.2", "three discs sedimenting: ~20 cm/s, Re ≈ 0.4 (the stated densities cannot sediment)",
           (("thesis-sedimentation", r"."),)),
    Figure("thesis", "§5.3", "artificial liquefaction: contacts broken and the load carried by the pore pressure",
           (("thesis-liquefaction", r"contacts broken|pore pressure on wall 1"),)),
    Figure("thesis", "§5.4-5.6", "simple shear specimens: void ratios 26.11 % (loose) and 24.65 % (dense)",
           (("thesis-simple-shear", r"specimen void ratio"),)),
    Figure("thesis", "§5.4-5.6", "dry simple shear: loose contracts, dense contracts then dilates",
           (("thesis-simple-shear", r"contracts"),)),
    Figure("thesis", "§5.4-5.6", "dry simple shear: peak S/F_y ≈ 0.2 (loose) and 0.19 (dense)",
           (("thesis-simple-shear", r"peak S/F_y"),)),
    Figure("thesis", "§5.4-5.6", "saturated simple shear: loose pore pressure rises then eases; dense rises then "
           "drops", (("thesis-simple-shear", r"saturated: pore pressure"),)),
    Figure("C&S", "nine-disc, Fig. 6", "undamped oscillation ≈ 0.15 F_eq; damping does not change F_eq",
           (("cs-nine-disc", r"undamped oscillation amplitude|Feq at C"),)),
    Figure("C&S", "nine-disc, Fig. 7", "faster loading gives a larger oscillation (0.12 vs 0.04; 0.36 vs 0.12), about "
           "the same equilibrium force and the same frequencies", (("cs-nine-disc", r"loading speed|faster loading"),)),
    Figure("C&S", "nine-disc, Fig. 9", "distortion: ks/kn hardly matters at φ = 15°; at φ = 30° Fn at C is lower "
           "for ks/kn = 1 after compression and peaks higher (≈ 25.6e8)", (("cs-nine-disc", r"distortion|compression"),)),
    Figure("C&S", "Tables 1-3, stage A", "F_H/F_V = 0.39 (experiment), 0.41-0.46 (C&S numerics); ΔF/F 0.1-2.6 %",
           (("cs-photoelastic", r"stage A: (F_H/F_V in|ΔF/F)|table[23] seed \d+, stage A"),)),
    Figure("C&S", "Tables 1-3, stage B", "F_H/F_V = 0.33 (experiment), 0.40-0.47 (C&S numerics): the ratio falls "
           "from A to B; the wall forces grow 3.4-5.8×", (("cs-photoelastic", r"stage B: (F_H/F_V in|ΔF/F)|table[23] "
                                                          r"seed \d+, stage B|stage B / stage A|falls from stage A"),)),
    Figure("C&S", "experiment, stress control", "the experiment's forces: F_H/F_V 0.39, then 0.33",
           (("cs-photoelastic", r"^servo"),)),
    Figure("Miyata", "§3.2, Tables 1-2", "2D uniaxial compression: circles r = 15 cm and n = 4 superquadrics "
           "(a = 19.5, b = 9.76 cm) of equal mass; ρ 1650, k 1e7 (1e8 with walls), e 0.01, μ 0.51, Δt 1.7078e-4 s",
           (("miyata-uniaxial-2d", r"^Table [12]"),)),
    Figure("Miyata", "§3.2, Fig. 26", "stress-settlement: regimes 0-50, 50-250, > 250 kPa (almost linear); stress "
           "drops for circles only; rough samples settle more, final regimes parallel",
           (("miyata-uniaxial-2d", r"^Fig\. 26"),)),
    Figure("Miyata", "§3.2, Fig. 29", "plate/floor contact ratio rises fast, then slower, then slowest; floor "
           "contacts almost constant; rough samples have fewer plate contacts at 50-250 kPa",
           (("miyata-uniaxial-2d", r"^Fig\. 29 .*(rises|constant|fewer)"),)),
    Figure("Miyata", "§3.2, Fig. 30", "load share at 900 kPa of the contacts formed first: initial + transition > "
           "70 %, final <= 20 %; superquadrics initial > 50 %, final < 15 %",
           (("miyata-uniaxial-2d", r"^Fig\. 30"),)),
    Figure("Miyata", "§3.3, Fig. 32", "3D uniaxial compression of 1500 ellipsoids (10 × 10 m): large settlement at "
           "0-100 kPa, the stress rising more rapidly at 100-400 kPa, almost linear over 400 kPa",
           (("miyata-uniaxial-3d-full", r"^Fig\. 32|rises with settlement"),
                                    ("miyata-uniaxial-3d-ellipsoids-full", r"^Fig\. 32|rises with settlement"))),
    Figure("Miyata", "§3.3, Fig. 33", "plate contacts rise fast, then slower, then slowest; floor contacts almost "
           "constant at about 257", (("miyata-uniaxial-3d-full", r"^Fig\. 33"),
                                    ("miyata-uniaxial-3d-ellipsoids-full", r"^Fig\. 33"))),
    Figure("Miyata", "§3.3, Fig. 35", "per-particle force PDFs at 400-600 kPa: plate ≈ q-model N = 3, floor ≈ Mueth "
           "et al. (a = 3, b = 0.75, β = 1.5)", (("miyata-uniaxial-3d-full", r"^Fig\. 35"),
                                    ("miyata-uniaxial-3d-ellipsoids-full", r"^Fig\. 35"))),
    Figure("Miyata", "§3.3, Fig. 37", "load support: forces below 0.5<F> carry a small share, medium and large ones "
           "a larger share", (("miyata-uniaxial-3d-full", r"^Fig\. 37"),
                                    ("miyata-uniaxial-3d-ellipsoids-full", r"^Fig\. 37"))),
    Figure("Miyata / Chung & Ooi", "eqs 13-33", "Hertz-Mindlin impacts: contact time, overlap, force, restitution, "
           "sliding (the law the 3D cases use)", (("hertz-impacts", r"."),)),
    Figure("ch3", "§3.5.4.1", "elastic stack of 9 balls: total energy 554.74 J, conserved",
           (("ch3-elastic-stack", r"."),)),
    Figure("ch3", "§3.5.4.2", "damped stack settles (top ball ≈ 7.86 after 1000 iterations); adaptive dynamic "
           "relaxation gets there faster", (("ch3-damped-stack", r"."),)),
    Figure("ch3", "§3.5.4.3", "impulse through a 100-ball chain (e = 0.3): arrival delay and attenuation",
           (("ch3-impulse-chain", r"."),)),
)

SLOW_NOTE = "not run on this report"


def matched(fig: Figure, summary: dict) -> tuple[list, list]:
    """(checks on this figure found in the summary as (case, check) pairs, its cases missing from it)."""
    found, missing = [], []
    for case, pattern in fig.checks:
        c = summary["cases"].get(case)
        if c is None:
            missing.append(case)
            continue
        found += [(case, ch) for ch in c["checks"] if re.search(pattern, ch["name"])]
    return found, missing


def status(fig: Figure, summary: dict) -> str:
    found, missing = matched(fig, summary)
    if not found:
        if missing and not fig.pending:
            return f"{SLOW_NOTE} (demflow validate --case {missing[0]})"
        return f"no case yet: {fig.pending}" if fig.pending else "no check matches (a defect of this table)"
    kinds = [kind_of(ch) for _, ch in found]
    if MISS in kinds or any(k in VALIDATION_KINDS and not ch["passed"] for k, (_, ch) in zip(kinds, found)):
        return "not reproduced"
    if all(k == "calibration" for k in kinds if k != INFO) and "calibration" in kinds:
        return "calibration"
    if all(k == INFO for k in kinds):
        return "shown"
    if any(k == "calibration" for k in kinds):
        return "reproduced (with calibrations)"
    return "reproduced"


def rows(summary: dict) -> list[dict]:
    """One row per figure: the figure, its status and its checks (from the summary)."""
    out = []
    for fig in FIGURES:
        found, _ = matched(fig, summary)
        out.append(dict(source=fig.source, where=fig.where, what=fig.what, status=status(fig, summary),
                        checks=[dict(case=case, kind=kind_of(ch), **{k: ch[k] for k in ("name", "value", "reference",
                                                                                         "error", "tolerance", "passed",
                                                                                         "why")})
                                for case, ch in found]))
    return out


def counts(summary: dict) -> dict:
    out = {}
    for r in rows(summary):
        key = r["status"].split(" (")[0].split(":")[0]
        out[key] = out.get(key, 0) + 1
    return out


def _num(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):  # summary.json writes ∞ and NaN as null
        return "—"
    return f"{v:.4g}" if isinstance(v, float) else html.escape(str(v))


def render(summary: dict) -> str:
    """The table as an HTML page body (the report's source-figures page)."""
    body = []
    for r in rows(summary):
        cls = {"reproduced": "pass", "not reproduced": "fail"}.get(r["status"].split(" (")[0], "small")
        checks = "".join(
            f"<tr class='small'><td></td><td colspan='2'>{html.escape(c['case'])}: {html.escape(c['name'])}</td>"
            f"<td>{html.escape(c['kind'])}</td><td>{_num(c['value'])}</td><td>{_num(c['reference'])}</td>"
            f"<td>{_num(c['error'])}</td><td>{_num(c['tolerance'])}</td><td>{html.escape(c['why'])}</td></tr>"
            for c in r["checks"])
        body.append(f"<tr><td>{html.escape(r['source'])}</td><td>{html.escape(r['where'])}</td>"
                    f"<td>{html.escape(r['what'])}</td><td class='{cls}' colspan='6'>{html.escape(r['status'])}</td>"
                    f"</tr>{checks}")
    n = counts(summary)
    head = " · ".join(f"{k}: {v}" for k, v in sorted(n.items()))
    return (f"<p>Every quantitative figure of the four sources (../shared/SOURCES.md) and what demflow makes of "
            f"it: {html.escape(head)}. The numbers are the checks' own (demflow/report/source_figures.py maps "
            f"figures to checks); 'not reproduced' rows give the measured cause in the last column.</p>"
            f"<table><tr><th>source</th><th>where</th><th>figure</th><th>kind</th><th>demflow</th><th>reference</th>"
            f"<th>error</th><th>tolerance</th><th>status / justification or cause</th></tr>{''.join(body)}</table>")


def markdown(summary: dict) -> str:
    """The table in Markdown (one line per figure; the README embeds it)."""
    lines = ["| source | where | figure | status | demflow vs reference (worst check) |", "|---|---|---|---|---|"]
    for r in rows(summary):
        # the figure's own checks first (miss, source, calibration), then the others; the worst of them
        judged = ([c for c in r["checks"] if c["kind"] in (MISS, "source", "calibration")]
                  or [c for c in r["checks"] if c["kind"] != INFO] or r["checks"])
        if judged:
            def badness(c):
                err = c["error"] if c["error"] is not None and math.isfinite(c["error"]) else 0.0
                tol = c["tolerance"] if c["tolerance"] is not None and math.isfinite(c["tolerance"]) else 0.0
                return (c["kind"] == MISS, not c["passed"], err if c["kind"] == MISS else err / (tol or 1.0))

            worst = max(judged, key=badness)
            num = (f"{_num(worst['value'])} vs {_num(worst['reference'])} (error {_num(worst['error'])}, "
                   f"tolerance {_num(worst['tolerance'])})")
        else:
            num = "—"
        lines.append(f"| {r['source']} | {r['where']} | {r['what']} | {r['status']} | {num} |")
    return "\n".join(lines)


__all__ = ["FIGURES", "Figure", "rows", "status", "render", "markdown", "counts"]
