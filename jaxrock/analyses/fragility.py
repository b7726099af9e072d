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


def _fit_weighted(lnx: np.ndarray, y: np.ndarray, w: np.ndarray, iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Probit MLE of P = Φ(a + b ln x) for each row of weights `w` (S, n) over the observations
    (`lnx`, `y`: (n,)); returns (a, b) each (S,), with b ≤ 1/BETA_MIN."""
    S = w.shape[0]
    # start: θ at the weighted mean log-intensity, β = 0.5 (a concave problem: any start converges)
    mean = (w * lnx).sum(1) / np.maximum(w.sum(1), 1e-300)
    a, b = -mean / 0.5, np.full(S, 2.0)
    b_max = 1.0 / BETA_MIN

    def ll(a, b):  # an observation of weight 0 adds nothing, even where its term is −inf
        return np.where(w > 0, w * _loglik_terms(a, b, lnx, y), 0.0).sum(1)

    cur = ll(a, b)
    for _ in range(iterations):
        z = a[:, None] + b[:, None] * lnx
        # d ln Φ(±z)/dz = ±λ; λ = φ(z)/Φ(z) (overturned) or −φ(z)/Φ(−z): computed in logs (no underflow)
        logphi = -0.5 * z * z - 0.5 * np.log(2 * np.pi)
        lam = np.where(y, np.exp(logphi - log_ndtr(z)), -np.exp(logphi - log_ndtr(-z)))
        h = lam * (lam + z)  # −d²/dz² of the log-likelihood term (> 0: concave)
        g_a, g_b = (w * lam).sum(1), (w * lam * lnx).sum(1)
        H_aa, H_ab, H_bb = (w * h).sum(1), (w * h * lnx).sum(1), (w * h * lnx * lnx).sum(1)
        det = H_aa * H_bb - H_ab * H_ab
        det = np.where(det > 0, det, np.inf)  # a degenerate Hessian (no spread in x): no step
        da, db = (H_bb * g_a - H_ab * g_b) / det, (H_aa * g_b - H_ab * g_a) / det
        step = np.ones(S)
        for _ in range(30):  # backtrack until the likelihood does not decrease
            na, nb = a + step * da, np.clip(b + step * db, 1e-12, b_max)
            new = ll(na, nb)
            worse = new < cur - 1e-12 * np.abs(cur)
            if not worse.any():
                break
            step = np.where(worse, 0.5 * step, step)
        a, b, cur = na, nb, new
        if np.all(np.abs(g_a) + np.abs(g_b) < 1e-10 * np.maximum(w.sum(1), 1.0)):
            break
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
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the all-alike samples diverge (NaN below)
        a, b = _fit_weighted(lnx, y, w)
    hits = (w * y).sum(1)
    alike = (hits == 0) | (hits == w.sum(1))
    beta, median = 1.0 / b, np.exp(-a / b)
    # separated outcomes (every overturning intensity above every surviving one): no finite
    # maximum (β → 0); the step of the curve lies between the two, at their geometric mean
    used = w > 0
    below = np.where(used & ~y, lnx, -np.inf).max(1)
    above = np.where(used & y, lnx, np.inf).min(1)
    separated = below < above
    beta = np.where(alike, np.nan, np.where(separated, BETA_MIN, beta))
    median = np.where(alike, np.nan, np.where(separated, np.exp(0.5 * (below + above)), median))
    pct = lambda v: np.nanpercentile(v, [5.0, 95.0]) if np.isfinite(v).any() else np.array([np.nan, np.nan])
    return {"median": float(median[0]), "beta": float(beta[0]), "median_boot": median[1:], "beta_boot": beta[1:],
            "median_ci": pct(median[1:]), "beta_ci": pct(beta[1:]), "n": int(x.size), "n_overturned": float(q.sum())}


def probability(x, median, beta):
    """P(overturn | IM = x) of lognormal fragilities: Φ(ln(x/θ)/β), broadcast."""
    x, median, beta = np.asarray(x, dtype=float), np.asarray(median, dtype=float), np.asarray(beta, dtype=float)
    return ndtr(np.log(x / median) / beta)


def band(x, median_boot, beta_boot, percentiles=BAND) -> np.ndarray:
    """The bootstrap band of the curve at intensities `x`: (len(percentiles), len(x))."""
    p = probability(np.asarray(x)[None, :], np.asarray(median_boot)[:, None], np.asarray(beta_boot)[:, None])
    ok = np.isfinite(p).all(1)
    return np.percentile(p[ok], percentiles, axis=0) if ok.any() else np.full((len(percentiles), np.size(x)), np.nan)


__all__ = ["fit_lognormal", "probability", "band", "BETA_MIN", "N_BOOT"]
