"""Fragility: the probability that a column overturns at an intensity, from a record suite.

The usual model of the field (Baker 2015, "Efficient analytical fragility function fitting using
dynamic structural analysis", Earthquake Spectra 31(1)) is a lognormal cumulative distribution,

    P(overturn | IM = x) = Φ(ln(x / θ) / β),

with median θ and dispersion β, fitted by maximum likelihood to binary outcomes. Here the outcomes
are the suite's record sweep itself (multiple stripes): every record at every scale factor s of the
sweep is one observation, at intensity x = s · IM(record) (`jaxrock.intensity`: PGA, PGV; or the
factor itself), overturned or not. This keeps what an "incremental dynamic analysis" fit of the
least overturning factors would lose: rocking overturning is not monotone in the intensity (a
record that overturns a column at s may not at 1.2 s), and a record that overturns nothing within
the sweep is an observation too, not a missing one.

The fit maximises the binomial log-likelihood Σ ln Φ(z) over overturned and Σ ln Φ(−z) over the
rest, z = (ln x − ln θ)/β, a probit regression on ln x: concave in (−ln θ/β, 1/β), solved by
Newton's method with a backtracking step (to 1e-10 in the score), vectorised over the bootstrap
samples. Outcomes that one intensity separates exactly (every overturning intensity above every
surviving one) have no finite maximum (β → 0): their fit reports β = `BETA_MIN` and θ the
geometric mean of the two intensities at the step.

The uncertainty is a bootstrap over records (the suite's independent unit; a record's stripes are
not independent of each other): `n_boot` resamplings of the records with replacement, each fitted
alike; the band of the curve and the intervals of θ and β are their percentiles.

`fit_truncated_ida` fits the same curve to a truncated incremental dynamic analysis instead (Baker
2015, eq. 7): one collapse intensity per record, or, for a record that did not collapse up to the
largest intensity it was run to, only that its capacity lies above it (a right-censored lognormal).
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr, ndtr

from .._validate import JaxrockInputError

BETA_MIN = 1e-3
N_BOOT = 500
BAND = (16.0, 84.0)  # percentiles of the bootstrap band (the field's ±1σ band); fits also report 5-95


def _loglik_terms(a, b, lnx, y):
    """Each observation's log-likelihood term, ln Φ(z) (overturned) or ln Φ(−z), z = a + b ln x."""
    z = a[..., None] + b[..., None] * lnx
    return np.where(y, log_ndtr(z), log_ndtr(-z))


def _fit_weighted(lnx: np.ndarray, y: np.ndarray, w: np.ndarray, active: np.ndarray | None = None,
                  iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Probit MLE of P = Φ(a + b ln x) for each row of weights `w` (S, n) over the observations
    (`lnx`, `y`: (n,)); returns (a, b) each (S,), with b ≤ 1/BETA_MIN. Only the rows `active` (default
    all) are iterated, each until its own score is below 1e-10 (a row without a finite maximum, left
    active, runs every iteration: the caller leaves those out)."""
    S = w.shape[0]
    # start: θ at the weighted mean log-intensity, β = 0.5 (a concave problem: any start converges)
    mean = (w * lnx).sum(1) / np.maximum(w.sum(1), 1e-300)
    a, b = -mean / 0.5, np.full(S, 2.0)
    b_max = 1.0 / BETA_MIN
    active = np.ones(S, dtype=bool) if active is None else active.copy()
    tol = 1e-10 * np.maximum(w.sum(1), 1.0)

    def ll(a, b, rows):  # an observation of weight 0 adds nothing, even where its term is −inf
        return np.where(w[rows] > 0, w[rows] * _loglik_terms(a, b, lnx, y), 0.0).sum(1)

    cur = np.full(S, np.nan)
    cur[active] = ll(a[active], b[active], active)
    for _ in range(iterations):
        z = a[:, None] + b[:, None] * lnx
        # d ln Φ(±z)/dz = ±λ; λ = φ(z)/Φ(z) (overturned) or −φ(z)/Φ(−z): computed in logs (no underflow)
        logphi = -0.5 * z * z - 0.5 * np.log(2 * np.pi)
        lam = np.where(y, np.exp(logphi - log_ndtr(z)), -np.exp(logphi - log_ndtr(-z)))
        h = lam * (lam + z)  # −d²/dz² of the log-likelihood term (> 0: concave)
        g_a, g_b = (w * lam).sum(1), (w * lam * lnx).sum(1)
        active &= ~(np.abs(g_a) + np.abs(g_b) < tol)  # converged rows stay where they are
        if not active.any():
            break
        H_aa, H_ab, H_bb = (w * h).sum(1), (w * h * lnx).sum(1), (w * h * lnx * lnx).sum(1)
        det = H_aa * H_bb - H_ab * H_ab
        det = np.where(det > 0, det, np.inf)  # a degenerate Hessian (no spread in x): no step
        da, db = (H_bb * g_a - H_ab * g_b) / det, (H_aa * g_b - H_ab * g_a) / det
        rows = np.flatnonzero(active)
        step = np.ones(rows.size)
        for _ in range(30):  # backtrack until the likelihood does not decrease
            na, nb = a[rows] + step * da[rows], np.clip(b[rows] + step * db[rows], 1e-12, b_max)
            new = ll(na, nb, rows)
            worse = new < cur[rows] - 1e-12 * np.abs(cur[rows])
            if not worse.any():
                break
            step = np.where(worse, 0.5 * step, step)
        a[rows], b[rows], cur[rows] = na, nb, new
    return a, b


def fit_lognormal(im, overturned, group=None, *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Fit a lognormal fragility curve P(overturn | IM = x) = Φ(ln(x/θ)/β) to overturning outcomes.

    Maximum likelihood on binary outcomes (Baker 2015; module docstring, `jaxrock.analyses.fragility`),
    by Newton's method on the probit regression on ln x, with a bootstrap over `group` for the
    uncertainty. An observation whose verdict is uncertain enters as the fraction q of an ensemble
    of perturbed runs that overturned, i.e. q of an overturning and 1 − q of a standing observation
    in the binomial likelihood. Outcomes that one intensity separates exactly report β = `BETA_MIN`.
    Outcomes all alike (none or every one overturned) have no fit: θ and β are NaN then, and so is a
    bootstrap sample's fit that is all alike.

    Arguments:
        im (ArrayLike): the observations' intensities x (any unit, e.g. PGA [m/s²]), each finite and > 0.
        overturned (ArrayLike): one outcome per intensity: bools, or probabilities in [0, 1].
        group (ArrayLike | None): the record of each observation, the bootstrap's unit; default None:
            each observation its own.
        n_boot: bootstrap resamplings; default `N_BOOT`.
        seed: the bootstrap's seed (the same bits every run); default 0.

    Returns:
        `median` θ and `beta` β of the fit of all observations; `median_boot`, `beta_boot`: the `n_boot`
            bootstrap fits; `median_ci`, `beta_ci`: their 5–95 % percentiles; `n`: the observations;
            `n_overturned`: those that overturned (the sum of the probabilities).

    Raises:
        JaxrockInputError: when `im` and `overturned` differ in size, an intensity is not finite and
            > 0, an outcome is neither a bool nor in [0, 1], or `group` differs in size.

    Example:
        ```python
        import numpy as np, jaxrock
        im = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
        fit = jaxrock.fit_lognormal(im, [False, False, True, False, True, True], n_boot=200)
        fit["median"], fit["beta"], fit["median_ci"]
        ```
    """
    x = np.asarray(im, dtype=float).ravel()
    q = np.asarray(overturned).ravel().astype(float)
    if x.shape != q.shape:
        raise JaxrockInputError(f"im and overturned: {x.size} and {q.size} values; give one outcome per intensity")
    if x.size == 0 or not np.all(np.isfinite(x) & (x > 0)):
        raise JaxrockInputError("im: every intensity must be a finite number > 0")
    if not np.all((q >= 0) & (q <= 1)):
        raise JaxrockInputError("overturned: every outcome must be a bool or a probability in [0, 1]")
    g = np.arange(x.size) if group is None else np.unique(np.asarray(group).ravel(), return_inverse=True)[1].ravel()
    if g.size != x.size:
        raise JaxrockInputError(f"group: {g.size} values for {x.size} observations")
    n_groups = int(g.max()) + 1
    rng = np.random.default_rng(seed)
    counts = np.vstack([np.ones(n_groups), rng.multinomial(n_groups, np.full(n_groups, 1.0 / n_groups), size=int(n_boot))])
    # each observation twice: overturned with weight q, standing with weight 1 − q (a bool: one of them 0)
    w = np.concatenate([counts[:, g] * q, counts[:, g] * (1.0 - q)], axis=1)  # times its record's multiplicity
    lnx = np.log(np.concatenate([x, x]))
    y = np.concatenate([np.ones(x.size, bool), np.zeros(x.size, bool)])
    hits = (w * y).sum(1)
    alike = (hits == 0) | (hits == w.sum(1))
    # separated outcomes (every overturning intensity above every surviving one): no finite
    # maximum (β → 0); the step of the curve lies between the two, at their geometric mean
    used = w > 0
    below = np.where(used & ~y, lnx, -np.inf).max(1)
    above = np.where(used & y, lnx, np.inf).min(1)
    separated = below < above
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the all-alike samples diverge (NaN below)
        a, b = _fit_weighted(lnx, y, w, ~(alike | separated))  # the samples without a finite maximum are not iterated
    beta, median = 1.0 / b, np.exp(-a / b)
    beta = np.where(alike, np.nan, np.where(separated, BETA_MIN, beta))
    median = np.where(alike, np.nan, np.where(separated, np.exp(0.5 * (below + above)), median))
    pct = lambda v: np.nanpercentile(v, [5.0, 95.0]) if np.isfinite(v).any() else np.array([np.nan, np.nan])
    return {"median": float(median[0]), "beta": float(beta[0]), "median_boot": median[1:], "beta_boot": beta[1:],
            "median_ci": pct(median[1:]), "beta_ci": pct(beta[1:]), "n": int(x.size), "n_overturned": float(q.sum())}


def _fit_censored(y: np.ndarray, c: np.ndarray, hit: np.ndarray, w: np.ndarray, iterations: int = 100):
    """MLE of a right-censored normal for each row of weights `w` (S, n): `y` the log capacities of
    the collapsed observations (`hit`), `c` the log truncations of the others. Newton's method in
    (γ, δ) = (1/β, ln θ/β), where the log-likelihood is concave (Olsen 1978); returns (γ, δ) each
    (S,), with γ ≤ 1/BETA_MIN."""
    S = w.shape[0]
    g_max = 1.0 / BETA_MIN
    wh, wc = np.where(hit, w, 0.0), np.where(hit, 0.0, w)  # the collapsed and the censored weights
    yh, cc = np.where(hit, y, 0.0), np.where(hit, 0.0, c)  # (inf capacities never enter an arithmetic)
    # start: the moments of the collapsed log capacities (biased low by the censoring; any start converges)
    n_h = np.maximum(wh.sum(1), 1e-300)
    mean = (wh * yh).sum(1) / n_h
    sd = np.sqrt(np.maximum((wh * (yh - mean[:, None]) ** 2).sum(1) / n_h, 0.0))
    sd = np.where(sd > 1e-3, sd, 0.5)
    gam, dlt = 1.0 / sd, mean / sd

    def ll(gam, dlt, rows):
        z = gam[:, None] * yh - dlt[:, None]
        u = dlt[:, None] - gam[:, None] * cc
        return (wh[rows] * (np.log(gam)[:, None] - 0.5 * z * z)).sum(1) + np.where(wc[rows] > 0, wc[rows] * log_ndtr(u), 0.0).sum(1)

    active = wh.sum(1) > 0  # a sample without a collapse has no fit (NaN): not iterated
    tol = 1e-10 * np.maximum(w.sum(1), 1.0)
    cur = np.full(S, np.nan)
    cur[active] = ll(gam[active], dlt[active], active)
    for _ in range(iterations):
        z = gam[:, None] * yh - dlt[:, None]
        u = dlt[:, None] - gam[:, None] * cc
        lam = np.exp(-0.5 * u * u - 0.5 * np.log(2 * np.pi) - log_ndtr(u))  # φ(u)/Φ(u), in logs
        h = lam * (lam + u)  # −d² ln Φ(u)/du² (> 0)
        g_g = (wh * (1.0 / gam[:, None] - z * yh)).sum(1) - (wc * lam * cc).sum(1)
        g_d = (wh * z).sum(1) + (wc * lam).sum(1)
        active &= ~(np.abs(g_g) + np.abs(g_d) < tol)  # converged rows stay where they are
        if not active.any():
            break
        # the negative Hessian (positive definite)
        H_gg = (wh * (1.0 / gam[:, None] ** 2 + yh * yh)).sum(1) + (wc * h * cc * cc).sum(1)
        H_gd = -(wh * yh).sum(1) - (wc * h * cc).sum(1)
        H_dd = wh.sum(1) + (wc * h).sum(1)
        det = H_gg * H_dd - H_gd * H_gd
        det = np.where(det > 0, det, np.inf)
        dg, dd = (H_dd * g_g - H_gd * g_d) / det, (H_gg * g_d - H_gd * g_g) / det
        rows = np.flatnonzero(active)
        step = np.ones(rows.size)
        for _ in range(60):  # backtrack until γ > 0 and the likelihood does not decrease
            ng, nd = np.minimum(gam[rows] + step * dg[rows], g_max), dlt[rows] + step * dd[rows]
            ok = ng > 0
            new = np.where(ok, ll(np.where(ok, ng, 1.0), nd, rows), -np.inf)
            worse = ~(new >= cur[rows] - 1e-12 * np.abs(cur[rows]))
            if not worse.any():
                break
            step = np.where(worse, 0.5 * step, step)
        keep = ~worse  # a row that found no better point stays (it has converged)
        gam[rows], dlt[rows], cur[rows] = np.where(keep, ng, gam[rows]), np.where(keep, nd, dlt[rows]), np.where(keep, new, cur[rows])
        active[rows[worse]] = False
    return gam, dlt


def fit_truncated_ida(capacity, truncation, *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Fit a lognormal fragility curve Φ(ln(x/θ)/β) to a truncated incremental dynamic analysis.

    Maximum likelihood for truncated IDA (Baker 2015, eq. 7): each record is scaled up until it
    collapses, or until the largest intensity x_max it is run to. Its collapse intensity x_i is one
    draw of a lognormal capacity; a record that did not collapse up to x_max says only that its
    capacity lies above x_max. The log-likelihood

        Σ_collapsed ln[φ((ln x_i − ln θ)/β)/β] + Σ_others ln[1 − Φ((ln x_max,i − ln θ)/β)]

    is maximised by Newton's method (in (1/β, ln θ/β), where it is concave; to 1e-10 in the score),
    vectorised over the bootstrap. When every record collapsed this is the sample mean and standard
    deviation (1/n, the maximum likelihood one; Baker's eq. 3 divides by n − 1) of ln x_i. The
    uncertainty is a bootstrap over records: `n_boot` resamplings with replacement, each fitted
    alike. No collapse (in the data or in a bootstrap sample) has no fit: NaN. Collapse intensities
    all equal and every truncation at or below them have no finite maximum: β = `BETA_MIN` then.

    Arguments:
        capacity (ArrayLike): one collapse intensity per record (any unit, e.g. PGA [m/s²]), > 0; or
            `np.inf` for a record that did not collapse up to its truncation.
        truncation (ArrayLike): the largest intensity each record was run to, finite and > 0: a
            scalar (all alike) or one per record; a finite capacity must not exceed its truncation.
        n_boot: bootstrap resamplings; default `N_BOOT`.
        seed: the bootstrap's seed (the same bits every run); default 0.

    Returns:
        `median` θ and `beta` β of the fit of all records; `median_boot`, `beta_boot`: the `n_boot`
            bootstrap fits; `median_ci`, `beta_ci`: their 5–95 % percentiles; `n`: the records;
            `n_overturned`: those that collapsed (a finite capacity).

    Raises:
        JaxrockInputError: when `capacity` is empty, not a number, or has a value that is not > 0;
            `truncation` differs in size from `capacity` (other than a scalar) or has a value that is
            not finite and > 0; or a finite capacity lies above its truncation.

    Example:
        ```python
        import numpy as np
        from jaxrock.analyses.fragility import fit_truncated_ida
        capacity = np.array([0.6, 0.8, 0.9, 1.1, 1.2, np.inf, np.inf])  # two records never collapsed
        fit = fit_truncated_ida(capacity, 1.5, n_boot=200)
        fit["median"], fit["beta"], fit["median_ci"]
        ```
    """
    x = np.asarray(capacity)
    if x.dtype.kind not in "biuf":
        raise JaxrockInputError(f"capacity = {capacity!r} is not a number; give one collapse intensity per record")
    x = x.astype(float).ravel()
    t = np.asarray(truncation)
    if t.dtype.kind not in "biuf":
        raise JaxrockInputError(f"truncation = {truncation!r} is not a number; give a finite intensity > 0")
    t = t.astype(float).ravel()
    if x.size == 0:
        raise JaxrockInputError("capacity is empty; give one collapse intensity (or inf) per record")
    if t.size == 1:
        t = np.full(x.size, t[0])
    if t.size != x.size:
        raise JaxrockInputError(f"truncation: {t.size} values for {x.size} records; give a scalar or one per record")
    if not np.all(x > 0):  # NaN fails too
        raise JaxrockInputError("capacity: every value must be > 0 (a collapse intensity) or inf (no collapse)")
    if not np.all(np.isfinite(t) & (t > 0)):
        raise JaxrockInputError("truncation: every value must be a finite intensity > 0")
    hit = np.isfinite(x)
    above = hit & (x > t)
    if above.any():
        i = int(np.flatnonzero(above)[0])
        raise JaxrockInputError(
            f"capacity: record {i} collapsed at {x[i]:g} above its truncation {t[i]:g}; a collapse intensity must be "
            "≤ the truncation (inf: no collapse)"
        )
    n = x.size
    rng = np.random.default_rng(seed)
    w = np.vstack([np.ones(n), rng.multinomial(n, np.full(n, 1.0 / n), size=int(n_boot))])
    hits = (w * hit).sum(1)
    none = hits == 0
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        y, c = np.log(np.where(hit, x, 1.0)), np.log(t)
        # a sample without a collapse has no fit: fitted on the full data's weights (harmless), then NaN
        gam, dlt = _fit_censored(y, c, hit, np.where(none[:, None], 1.0, w))
    beta = np.where(none, np.nan, 1.0 / gam)
    median = np.where(none, np.nan, np.exp(dlt / gam))
    pct = lambda v: np.nanpercentile(v, [5.0, 95.0]) if np.isfinite(v).any() else np.array([np.nan, np.nan])
    return {"median": float(median[0]), "beta": float(beta[0]), "median_boot": median[1:], "beta_boot": beta[1:],
            "median_ci": pct(median[1:]), "beta_ci": pct(beta[1:]), "n": int(n), "n_overturned": int(hit.sum())}


def probability(x, median, beta):
    """P(overturn | IM = x) of lognormal fragilities: Φ(ln(x/θ)/β), broadcast."""
    x, median, beta = np.asarray(x, dtype=float), np.asarray(median, dtype=float), np.asarray(beta, dtype=float)
    return ndtr(np.log(x / median) / beta)


def band(x, median_boot, beta_boot, percentiles=BAND) -> np.ndarray:
    """The bootstrap band of the curve at intensities `x`: (len(percentiles), len(x))."""
    p = probability(np.asarray(x)[None, :], np.asarray(median_boot)[:, None], np.asarray(beta_boot)[:, None])
    ok = np.isfinite(p).all(1)
    return np.percentile(p[ok], percentiles, axis=0) if ok.any() else np.full((len(percentiles), np.size(x)), np.nan)


__all__ = ["fit_lognormal", "fit_truncated_ida", "probability", "band", "BETA_MIN", "N_BOOT"]
