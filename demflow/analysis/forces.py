"""Contact-force statistics of one or more snapshots (Miyata §3, eqs 61-62, Figs 35 and 37).

Works on any engine's :class:`~demflow.results.Results` (or on its ``contacts`` table alone):
only the common columns ``step, i, j, wall, fn`` are used here.

- :func:`normalized_forces`  f = F/<F> of the normal force, per snapshot (Miyata §3, Fig. 35)
- :func:`force_pdf`          P(f) on common linear or logarithmic bins
- :func:`fit_exponential_tail`  P(f) ∝ exp(-β f) for f > f0 (maximum likelihood, exact CI)
- :func:`fit_q_model`        q-model, Miyata eq 62: a gamma law with mean 1 (shape N, scale 1/N);
                             N by maximum likelihood, profile-likelihood CI
- :func:`fit_mueth`          Mueth et al. (1998), Miyata eq 61: P(f) = a(1 - b e^{-f²}) e^{-βf};
                             b, β by maximum likelihood, a fixed by the normalisation
- :func:`load_support`       share of the total load carried by each class of f (Miyata Fig. 37)

Units: F in the engine's force unit; f, β, N, a, b are dimensionless. The micro-mechanical
averages (coordination number, fabric tensor, average stress, ch3 eq 3.17) are in
:mod:`demflow.analysis.micro`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from .. import libm

#: common bins so that distributions of different engines/runs can be compared bin by bin
LINEAR_BINS = np.round(np.arange(0.0, 6.0 + 1e-12, 0.2), 10)
LOG_BINS = np.logspace(-3.0, 1.0, 25)
#: Mueth et al. (1998) parameters as quoted by Miyata after eq 61: a = 3, b = 0.75, β = 1.5
MUETH_1998 = dict(a=3.0, b=0.75, beta=1.5)
#: Miyata's classes of f in the load-support discussion (Fig. 37): small, medium, large
LOAD_CLASSES = ((0.0, 0.5), (0.5, 2.0), (2.0, np.inf))


# ----------------------------------------------------------------------------- selection
def _contacts_table(data) -> pd.DataFrame:
    return data.contacts if hasattr(data, "contacts") else data


def snapshot_steps(contacts: pd.DataFrame, step=None) -> np.ndarray:
    """Steps selected by ``step``: None = the last snapshot, "all" = every snapshot, an int or a list."""
    steps = np.unique(contacts["step"].to_numpy())
    if step is None:
        if steps.size == 0:
            raise ValueError("the contacts table is empty")
        return steps[-1:]
    if isinstance(step, str):
        if step != "all":
            raise ValueError(f"step must be None, 'all', an int or a list of ints, not {step!r}")
        return steps
    want = np.atleast_1d(np.asarray(step))
    missing = np.setdiff1d(want, steps)
    if missing.size:
        raise ValueError(f"no snapshot at step(s) {missing.tolist()}; snapshots: {steps.tolist()}")
    return want


def select_contacts(data, step=None, where="all") -> pd.DataFrame:
    """Rows of the contacts table at the selected snapshot(s) and of the selected kind.

    ``where``: "all"; "particles" (disc-disc, j >= 0); "walls" (every disc-wall contact, j = -1);
    or a wall name / list of wall names (Miyata's loading plate / bottom plate statistics).
    """
    c = _contacts_table(data)
    c = c[c["step"].isin(snapshot_steps(c, step))]
    is_wall = c["j"].to_numpy() < 0
    if isinstance(where, str) and where == "all":
        return c
    if isinstance(where, str) and where == "particles":
        return c[~is_wall]
    if isinstance(where, str) and where == "walls":
        return c[is_wall]
    names = [where] if isinstance(where, str) else list(where)
    return c[is_wall & c["wall"].isin(names).to_numpy()]


# ----------------------------------------------------------------------------- f = F/<F>
@dataclass
class NormalizedForces:
    """f = F/<F> of the normal contact forces F > 0, pooled over the selected snapshots.

    <F> is the mean over the F > 0 contacts of each snapshot (Miyata §3: "dividing each contact
    force by the average contact force on the plate at each vertical stress level").
    """

    f: np.ndarray  # dimensionless, mean 1 within each snapshot
    steps: np.ndarray  # snapshot of each f
    mean_force: dict  # step -> <F> [force]
    n_zero: int  # contacts listed with F == 0 (|F| <= tol): excluded
    n_negative: int  # contacts with F < -tol (cohesive tension): excluded
    n_total: int  # all rows considered

    @property
    def n(self) -> int:
        return int(self.f.size)


def normalized_forces(data, step=None, where="all", tol=0.0) -> NormalizedForces:
    """f = F/<F> of the normal force fn [force] (Miyata §3, Fig. 35), per snapshot then pooled.

    Contacts with |F| <= tol (F = 0: touching but unloaded, or listed but apart) and with
    F < -tol (tension) are excluded and counted. ``step``/``where`` as in :func:`select_contacts`.
    """
    c = select_contacts(data, step, where)
    fn = c["fn"].to_numpy(dtype=float)
    st = c["step"].to_numpy()
    pos = fn > tol
    n_zero = int(np.sum(np.abs(fn) <= tol))
    n_neg = int(np.sum(fn < -tol))
    fs, ss, means = [], [], {}
    for s in np.unique(st[pos]):
        F = fn[pos & (st == s)]
        m = float(F.mean())
        means[s.item() if hasattr(s, "item") else s] = m
        fs.append(F / m)
        ss.append(np.full(F.size, s))
    f = np.concatenate(fs) if fs else np.zeros(0)
    steps = np.concatenate(ss) if ss else np.zeros(0, dtype=st.dtype)
    return NormalizedForces(f=f, steps=steps, mean_force=means, n_zero=n_zero, n_negative=n_neg,
                            n_total=int(fn.size))


# a bare array of f = F/<F> must have mean 1 to this relative tolerance (round-off of the division
# and of the mean over up to ~1e7 forces is below 1e-12; a forgotten normalisation is off by far more)
NORMALISED_MEAN_TOLERANCE = 1e-9


def _as_f(f_or_data, step=None, where="all", mean_one=False) -> np.ndarray:
    """f = F/<F> from a NormalizedForces, a results or contacts table (normalised here), or a bare array
    (with ``mean_one``, as for the q-model whose scale is 1/N, it must already be normalised: mean 1,
    refused otherwise with the fix)."""
    if isinstance(f_or_data, NormalizedForces):
        return f_or_data.f
    if hasattr(f_or_data, "contacts") or isinstance(f_or_data, pd.DataFrame):
        return normalized_forces(f_or_data, step, where).f
    f = np.asarray(f_or_data, dtype=float)
    if f.size and not np.all(np.isfinite(f)):
        raise ValueError("the forces contain a non-finite value; give finite f = F/<F>")
    mean = float(f.mean()) if f.size else 1.0
    if mean_one and abs(mean - 1.0) > NORMALISED_MEAN_TOLERANCE:
        raise ValueError(
            f"the forces given have mean {mean:.6g}, but the statistics take f = F/<F> (mean 1): pass F / F.mean(), "
            "a NormalizedForces (normalized_forces(...)), or a results/contacts table to normalise here")
    return f[f > 0]


# ----------------------------------------------------------------------------- PDF
def _edges(bins):
    if isinstance(bins, str):
        if bins == "linear":
            return LINEAR_BINS, False
        if bins == "log":
            return LOG_BINS, True
        raise ValueError("bins must be 'linear', 'log' or an array of edges")
    e = np.asarray(bins, dtype=float)
    if e.ndim != 1 or e.size < 2 or np.any(np.diff(e) <= 0):
        raise ValueError("bin edges must be increasing")
    return e, False


@dataclass
class ForcePDF:
    """Histogram estimate of P(f): density[k] = count[k] / (n · width[k])."""

    edges: np.ndarray
    centers: np.ndarray  # arithmetic (linear bins) or geometric (log bins) centres
    density: np.ndarray  # [1/unit f]
    counts: np.ndarray
    n: int  # sample size (including values outside the bins)
    n_below: int
    n_above: int


def force_pdf(f, bins="linear", step=None, where="all") -> ForcePDF:
    """P(f) on common bins. ``bins``: "linear" (:data:`LINEAR_BINS`, 0-6 by 0.2), "log"
    (:data:`LOG_BINS`, 1e-3-10, 24 bins) or explicit edges. ``f``: an array of f, a
    :class:`NormalizedForces`, a Results or a contacts table (then normalised here).

    Normalised by the whole sample size, so the density integrates to the fraction inside.
    """
    f = _as_f(f, step, where)
    edges, log = _edges(bins)
    counts, _ = np.histogram(f, edges)
    n = f.size
    width = np.diff(edges)
    dens = counts / (n * width) if n else np.zeros(width.size)
    centers = np.sqrt(edges[:-1] * edges[1:]) if log else 0.5 * (edges[:-1] + edges[1:])
    return ForcePDF(edges=edges, centers=centers, density=dens, counts=counts, n=int(n),
                    n_below=int(np.sum(f < edges[0])), n_above=int(np.sum(f > edges[-1])))


# ----------------------------------------------------------------------------- exponential tail
@dataclass
class TailFit:
    """P(f) ∝ exp(-β f) for f > f0 (Miyata §3: "exponential decay at large f > 1.0")."""

    beta: float
    ci: tuple  # exact (1 - alpha) CI of β
    f0: float
    n: int  # tail sample size
    fraction: float  # share of the sample with f > f0
    amplitude: float  # A in P(f) = A exp(-β f) for f > f0, so that ∫_{f0}^∞ P = fraction


def fit_exponential_tail(f, f0=1.0, alpha=0.05, step=None, where="all") -> TailFit:
    """Maximum likelihood β of P(f) ∝ exp(-β f) on the sample truncated to f > f0.

    For f > f0, f - f0 ~ Exp(β) (memoryless), so β̂ = 1/mean(f - f0). With S = Σ (f - f0),
    2βS ~ χ²(2n) exactly, which gives the CI [χ²_{α/2}(2n), χ²_{1-α/2}(2n)] / (2S).
    """
    f = _as_f(f, step, where)
    t = f[f > f0] - f0
    n = t.size
    if n < 2:
        raise ValueError(f"only {n} values above f0 = {f0}")
    S = float(t.sum())
    beta = n / S
    ci = (stats.chi2.ppf(alpha / 2, 2 * n) / (2 * S), stats.chi2.ppf(1 - alpha / 2, 2 * n) / (2 * S))
    frac = n / f.size
    return TailFit(beta=float(beta), ci=(float(ci[0]), float(ci[1])), f0=float(f0), n=int(n),
                   fraction=float(frac), amplitude=float(frac * beta * np.exp(beta * f0)))


# ----------------------------------------------------------------------------- q-model
def q_model_pdf(f, N):
    """Miyata eq 62: P(f) = N^N / (N-1)! f^(N-1) e^(-N f), i.e. gamma(shape N, scale 1/N), mean 1.
    (N-1)! is read as Γ(N), so non-integer N is allowed."""
    return stats.gamma.pdf(f, N, scale=1.0 / N)


def _q_loglik(N, n, mean_log, mean_f):
    return n * (N * math.log(N) - special.gammaln(N) + (N - 1.0) * mean_log - N * mean_f)


@dataclass
class QModelFit:
    """q-model (Miyata eq 62) fitted by maximum likelihood."""

    N: float
    ci: tuple  # profile-likelihood (likelihood-ratio) CI at level 1 - alpha
    se: float  # 1/sqrt(n (ψ'(N) - 1/N)): Fisher information with the scale profiled out
    loglik: float
    n: int
    ks_pvalue: float  # Kolmogorov-Smirnov of the sample against the fitted law (indicative)


def fit_q_model(f, alpha=0.05, step=None, where="all") -> QModelFit:
    """Maximum likelihood N of the q-model, Miyata eq 62 (gamma, shape N, scale 1/N).

    The 1-D log-likelihood ℓ(N) = n[N ln N - ln Γ(N) + (N-1) <ln f> - N <f>] is maximised with
    Brent's method on ln N. Because f = F/<F> is divided by the sample mean, ℓ(N) equals (up to
    a constant) the profile log-likelihood of N for a gamma law of F with a free scale, so the
    interval {N : 2[ℓ(N̂) - ℓ(N)] <= χ²₁(1-α)} is the profile-likelihood CI and it accounts for
    the normalisation. ``se`` is from the matching Fisher information n(ψ'(N) - 1/N).
    A bare array must be f = F/<F> (mean 1): one that is not is refused (its N would be wrong).
    """
    f = _as_f(f, step, where, mean_one=True)
    n = f.size
    if n < 3:
        raise ValueError(f"only {n} positive forces")
    # the C library's log and exp, not numpy's CPU-specific versions (demflow.libm): the likelihood is flat at its
    # maximum, so Brent's stopping point, N to ~1e-8, followed the last bit of <ln f>, and N differed between an
    # AVX-512 and an AVX2-only host by up to 3e-8 relative (measured 2026-12-01 on miyata-uniaxial-3d's fits)
    ml, mf = float(np.mean(libm.log(f))), float(np.mean(f))
    nll = lambda u: -_q_loglik(math.exp(u), n, ml, mf)
    # ln N - ψ(N) = ln <f> - <ln f> has one root; Brent on a bracket in ln N
    s = math.log(mf) - ml
    if s <= 0:
        raise ValueError("all forces are equal: N is infinite")
    res = optimize.minimize_scalar(nll, bracket=(math.log(0.5 / s), math.log(1.0 / s)), method="brent",
                                   options=dict(xtol=1e-12))
    u_hat = float(res.x)
    N = math.exp(u_hat)
    l_hat = -float(res.fun)
    crit = 0.5 * stats.chi2.ppf(1 - alpha, 1)
    g = lambda u: (l_hat - (-nll(u))) - crit
    lo_u, hi_u = u_hat - 0.1, u_hat + 0.1
    while g(lo_u) < 0:
        lo_u -= 0.5
    while g(hi_u) < 0:
        hi_u += 0.5
    lo = math.exp(optimize.brentq(g, lo_u, u_hat, xtol=1e-12))
    hi = math.exp(optimize.brentq(g, u_hat, hi_u, xtol=1e-12))
    se = float(1.0 / np.sqrt(n * (special.polygamma(1, N) - 1.0 / N)))
    ks = stats.kstest(f, "gamma", args=(N, 0.0, 1.0 / N)).pvalue
    return QModelFit(N=N, ci=(lo, hi), se=se, loglik=l_hat, n=int(n), ks_pvalue=float(ks))


# ----------------------------------------------------------------------------- Mueth et al.
def _mueth_I(beta):
    """∫_0^∞ exp(-f² - βf) df = (√π/2) erfcx(β/2)."""
    return 0.5 * np.sqrt(np.pi) * special.erfcx(0.5 * beta)


def mueth_norm(b, beta):
    """a such that ∫_0^∞ a(1 - b e^{-f²}) e^{-βf} df = 1: a = 1 / (1/β - b (√π/2) erfcx(β/2))."""
    return 1.0 / (1.0 / beta - b * _mueth_I(beta))


def mueth_mean(b, beta, a=None):
    """<f> = a [1/β² - b (1 - β I(β))/2] with I(β) = ∫_0^∞ e^{-f²-βf} df; a defaults to mueth_norm."""
    a = mueth_norm(b, beta) if a is None else a
    return a * (1.0 / beta ** 2 - 0.5 * b * (1.0 - beta * _mueth_I(beta)))


def mueth_pdf(f, b, beta, a=None):
    """Miyata eq 61 (Mueth et al. 1998): P(f) = a (1 - b e^{-f²}) e^{-βf}, f >= 0.
    a defaults to the normalising value :func:`mueth_norm` (b <= 1, β > 0)."""
    a = mueth_norm(b, beta) if a is None else a
    f = np.asarray(f, dtype=float)
    return np.where(f >= 0, a * (1.0 - b * np.exp(-f * f)) * np.exp(-beta * f), 0.0)


def mueth_cdf(f, b, beta, a=None):
    """∫_0^f of :func:`mueth_pdf`: a [(1 - e^{-βf})/β - b ∫_0^f e^{-x²-βx} dx]."""
    a = mueth_norm(b, beta) if a is None else a
    f = np.maximum(np.asarray(f, dtype=float), 0.0)
    h = 0.5 * beta
    # ∫_0^f e^{-x²-βx} dx = (√π/2) [erfcx(h) - e^{-f²-βf} erfcx(f + h)]
    J = 0.5 * np.sqrt(np.pi) * (special.erfcx(h) - np.exp(-f * f - beta * f) * special.erfcx(f + h))
    return a * (-np.expm1(-beta * f) / beta - b * J)


@dataclass
class MuethFit:
    """Mueth et al. form (Miyata eq 61) fitted by maximum likelihood, a from the normalisation."""

    a: float
    b: float
    beta: float
    se: dict  # standard errors of a, b, beta (observed Fisher information; a by the delta method)
    ci: dict  # Wald CIs at level 1 - alpha: value ± z se
    mean: float  # <f> of the fitted law (1 when impose_mean)
    loglik: float
    n: int
    impose_mean: bool
    at_bound: bool  # b hit its bound (b = 1: P(0) = 0); then se/ci are not reliable


def fit_mueth(f, impose_mean=False, alpha=0.05, step=None, where="all", b_bounds=(-10.0, 1.0)) -> MuethFit:
    """Maximum likelihood fit of Miyata eq 61, P(f) = a(1 - b e^{-f²}) e^{-βf} on f >= 0.

    Choice: P is treated as a probability density, so a is not a free parameter: a = a(b, β) =
    :func:`mueth_norm`. (Miyata quotes a = 3, b = 0.75, β = 1.5; normalisation then gives
    a = 3.03 and <f> = 0.977, so the quoted a is the normalising one to 1 %.) The mean <f> = 1 is
    NOT imposed by default: the sample is already normalised to mean 1 and the free fit of (b, β)
    reports the model mean as a check. With ``impose_mean=True``, β is tied to b by <f>(b, β) = 1
    and only b is fitted (one parameter).

    b is bounded by 1 (P(0) >= 0) and below by ``b_bounds[0]``; β > 0. Standard errors come from
    the observed Fisher information (numerical Hessian of -ℓ at the optimum), a's by the delta
    method; CIs are Wald intervals (value ± z_{1-α/2} se).
    """
    f = _as_f(f, step, where)
    n = f.size
    if n < 5:
        raise ValueError(f"only {n} positive forces")
    f2 = f * f

    def loglik(b, beta):
        if beta <= 0 or b > 1:
            return -np.inf
        a = mueth_norm(b, beta)
        if not np.isfinite(a) or a <= 0:
            return -np.inf
        g = 1.0 - b * np.exp(-f2)
        if np.any(g <= 0):
            return -np.inf
        return float(n * np.log(a) + np.sum(np.log(g)) - beta * np.sum(f))

    def beta_of_b(b):  # <f>(b, β) = 1 solved for β (mean decreases with β)
        return optimize.brentq(lambda be: mueth_mean(b, be) - 1.0, 1e-3, 1e3, xtol=1e-13)

    z = stats.norm.ppf(1 - alpha / 2)
    lo_b, hi_b = b_bounds
    hi_b = min(hi_b, 1.0 - 1e-9)
    if impose_mean:
        nll1 = lambda b: -loglik(b, beta_of_b(b))
        res = optimize.minimize_scalar(nll1, bounds=(lo_b, hi_b), method="bounded", options=dict(xatol=1e-10))
        b = float(res.x)
        beta = beta_of_b(b)
        h = 1e-4
        d2 = (nll1(b + h) - 2 * nll1(b) + nll1(b - h)) / h ** 2 if b + h <= 1 else np.nan
        se_b = 1.0 / np.sqrt(d2) if d2 > 0 else np.nan
        dbeta = (beta_of_b(b + h) - beta_of_b(b - h)) / (2 * h) if b + h <= 1 else np.nan
        se_beta = abs(dbeta) * se_b
        da = (mueth_norm(b + h, beta_of_b(b + h)) - mueth_norm(b - h, beta_of_b(b - h))) / (2 * h) \
            if b + h <= 1 else np.nan
        se_a = abs(da) * se_b
        l_hat = -float(res.fun)
    else:
        nll = lambda p: -loglik(p[0], p[1])
        # start from the tail: β ≈ 1/<f - 1 | f > 1>
        t = f[f > 1.0] - 1.0
        beta0 = 1.0 / t.mean() if t.size > 2 else 1.5
        best = None
        for b0 in (0.0, 0.5, 0.9):
            r = optimize.minimize(nll, x0=[b0, beta0], method="L-BFGS-B",
                                  bounds=[(lo_b, hi_b), (1e-3, 1e3)])
            if np.isfinite(r.fun) and (best is None or r.fun < best.fun):
                best = r
        r = optimize.minimize(nll, x0=best.x, method="Nelder-Mead",
                              options=dict(xatol=1e-10, fatol=1e-12, maxiter=4000))
        if not (r.fun <= best.fun and r.x[0] <= 1.0):
            r = best
        b, beta = float(r.x[0]), float(r.x[1])
        l_hat = -float(r.fun)
        H = _hessian(nll, np.array([b, beta]))
        try:
            cov = np.linalg.inv(H)
            ok = np.all(np.diag(cov) > 0)
        except np.linalg.LinAlgError:
            ok = False
        if ok:
            se_b, se_beta = np.sqrt(np.diag(cov))
            h = 1e-6
            grad_a = np.array([(mueth_norm(b + h, beta) - mueth_norm(b - h, beta)) / (2 * h),
                               (mueth_norm(b, beta + h) - mueth_norm(b, beta - h)) / (2 * h)])
            se_a = float(np.sqrt(grad_a @ cov @ grad_a))
        else:
            se_b = se_beta = se_a = np.nan
    a = float(mueth_norm(b, beta))
    at_bound = bool(b >= hi_b - 1e-6 or b <= lo_b + 1e-6)
    se = dict(a=float(se_a), b=float(se_b), beta=float(se_beta))
    vals = dict(a=a, b=b, beta=float(beta))
    ci = {k: (vals[k] - z * se[k], vals[k] + z * se[k]) for k in vals}
    return MuethFit(a=a, b=b, beta=float(beta), se=se, ci=ci, mean=float(mueth_mean(b, beta)), loglik=l_hat,
                    n=int(n), impose_mean=bool(impose_mean), at_bound=at_bound)


def _hessian(fun, x, rel=1e-4):
    """Central-difference Hessian of a scalar function."""
    x = np.asarray(x, float)
    k = x.size
    h = rel * np.maximum(np.abs(x), 1e-2)
    H = np.empty((k, k))
    f0 = fun(x)
    for p in range(k):
        for q in range(p, k):
            if p == q:
                e = np.zeros(k); e[p] = h[p]
                H[p, p] = (fun(x + e) - 2 * f0 + fun(x - e)) / h[p] ** 2
            else:
                ep = np.zeros(k); ep[p] = h[p]
                eq = np.zeros(k); eq[q] = h[q]
                H[p, q] = H[q, p] = (fun(x + ep + eq) - fun(x + ep - eq) - fun(x - ep + eq)
                                     + fun(x - ep - eq)) / (4 * h[p] * h[q])
    return H


# ----------------------------------------------------------------------------- load support
@dataclass
class LoadSupport:
    """Share of the total load Σ F carried by each class of f (Miyata Fig. 37).

    fraction[k] = Σ_{f in bin k} f / Σ f (the same as Σ F / Σ F within one snapshot; pooled
    snapshots are weighted by their contact count since each has mean f = 1); density =
    fraction / width, whose model counterpart is f P(f) / <f>.
    """

    edges: np.ndarray
    centers: np.ndarray
    fraction: np.ndarray
    density: np.ndarray
    classes: dict  # (lo, hi) -> share, for Miyata's small (< 0.5), medium (0.5-2), large (> 2)
    n: int


def load_support(f, bins="linear", classes=LOAD_CLASSES, step=None, where="all") -> LoadSupport:
    """Load-support distribution of f (Miyata Fig. 37); bins as in :func:`force_pdf`."""
    f = _as_f(f, step, where)
    edges, log = _edges(bins)
    total = f.sum()
    w, _ = np.histogram(f, edges, weights=f)
    frac = w / total if total > 0 else np.zeros(edges.size - 1)
    centers = np.sqrt(edges[:-1] * edges[1:]) if log else 0.5 * (edges[:-1] + edges[1:])
    cls = {(lo, hi): float(f[(f >= lo) & (f < hi)].sum() / total) if total > 0 else 0.0 for lo, hi in classes}
    return LoadSupport(edges=edges, centers=centers, fraction=frac, density=frac / np.diff(edges), classes=cls,
                       n=int(f.size))
