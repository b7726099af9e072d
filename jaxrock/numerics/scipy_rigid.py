"""An independent SciPy reference for the rigid rocking model (RM), written from SPEC.

Nothing here comes from `jaxrock.rigid`: only the geometry numbers of a `jaxrock.Block`
(α′, p′, η′ of section 5; α, p, η for a plain block) are read, and those can also be given as
plain floats. The ground motions are re-written from SPEC's formulas as NumPy functions.

Model (SPEC "Rigid rocking model", eqs. 2 and 22):

- rest: θ ≡ 0 while |üg| ≤ g tanα′; uplift at the first time |üg| exceeds g tanα′, on the side
  s = −sign(üg) (üg > 0 → θ < 0). The first exceedance is found by a dense scan of |üg| on a
  grid (with each local maximum of |üg| on the grid refined by a bounded scalar maximisation, so
  that a peak hardly above the level between two grid points is not missed) and a bisection that
  returns a time at which |üg| ≥ level, so the block starts moving the right way.
- rocking: θ̈ = −p′² [sin(sα′ − θ) + (üg/g) cos(sα′ − θ)], integrated by `scipy.integrate.solve_ivp`
  with three events:
    impact   sθ ↓ 0  (terminal): θ ← 0 exactly, θ̇ ← η θ̇, s ← −s;
    apex     sθ̇ ↓ 0 (not terminal): a peak |θ| (the maximum is only reached at an apex);
    overturn sθ ↑ threshold·α′ (terminal).
- Zeno: with η < 1 the impacts accumulate. After an impact whose new velocity is below
  `zeno_v · p′α′` the block is taken to be at rest when |üg| ≤ g tanα′ (a flight at that speed
  peaks below ½ zeno_v² α′ and lasts ~2 zeno_v/(p′ tanα′)), or to uplift afresh on side
  −sign(üg) otherwise.
- after the excitation window (t > t_end) the motion is free: energy can only decrease, so the
  integration stops at the first apex after t_end (its peak is the last one that matters), at
  rest, or at overturning. With `t_final` (history runs) it integrates to t_final instead.

Records are piecewise linear: pass their sample times as `tstops` so that no step straddles a kink.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

G = 9.81  # m/s², SPEC
# β of eq. 29 (1.3801 in the paper, rounded) normalises the pulse's peak to a_p: found here by a
# bounded scalar search, independently of jaxrock's closed form
BETA = -minimize_scalar(
    lambda x: -abs((x**2 / 3 - 3) * (x / math.sqrt(3)) * math.exp(-(x**2) / 6)), bounds=(0.5, 2.5), method="bounded", options={"xatol": 1e-12}
).fun


# --- excitations (SPEC "Excitations"), NumPy ----------------------------------------------------


def ricker(a_p, omega_p):
    """Symmetric Ricker pulse üg(t) = a_p (1 − ω_p²t²/2) exp(−ω_p²t²/4); window ±12/ω_p."""
    a_p, omega_p = float(a_p), float(omega_p)

    def f(t):
        x = omega_p * np.asarray(t, dtype=float)
        return a_p * (1 - x**2 / 2) * np.exp(-(x**2) / 4)

    return f, -12.0 / omega_p, 12.0 / omega_p


def antisymmetric_ricker(a_p, omega_p):
    """Antisymmetric Ricker pulse, eq. 29, β = max of the unscaled shape (≈ 1.38011905); window ±15/ω_p."""
    a_p, omega_p = float(a_p), float(omega_p)

    def f(t):
        x = omega_p * np.asarray(t, dtype=float)
        return a_p / BETA * (x**2 / 3 - 3) * (x / math.sqrt(3)) * np.exp(-(x**2) / 6)

    return f, -15.0 / omega_p, 15.0 / omega_p


def record(acc, dt, scale=1.0):
    """A record sampled every dt from t = 0, linear between samples, zero outside (m/s²)."""
    acc = np.asarray(acc, dtype=float) * float(scale)
    ts = float(dt) * np.arange(acc.size)

    def f(t):
        return np.interp(np.asarray(t, dtype=float), ts, acc, left=0.0, right=0.0)

    return f, 0.0, float(ts[-1]), ts


# --- result --------------------------------------------------------------------------------------


@dataclasses.dataclass
class Result:
    max_theta: float  # max |θ| / α′ (= threshold when overturned)
    overturned: bool
    t_overturn: float  # inf if not overturned
    n_impacts: int
    t_uplift: float  # first uplift, inf if none
    uplift_side: float  # side of the first uplift (±1), 0 if none
    apexes: list  # (t, θ) of every apex
    impacts: list  # (t, θ̇ before, θ̇ after) of every impact
    segments: list  # (t0, t1, dense solution or None for rest)
    n_steps: int  # right-hand-side evaluations of all solve_ivp calls
    n_rest: int  # how many times the block came to rest (Zeno closures included)

    def history(self, ts):
        """θ(ts), θ̇(ts) (0 while at rest or before the start; held after overturning)."""
        ts = np.asarray(ts, dtype=float)
        th = np.zeros_like(ts)
        om = np.zeros_like(ts)
        for t0, t1, dense in self.segments:
            if dense is None:
                continue
            m = (ts >= t0) & (ts <= t1)
            if m.any():
                y = dense(ts[m])
                th[m], om[m] = y[0], y[1]
        if self.overturned and self.segments:
            t0, t1, dense = self.segments[-1]
            m = ts > t1
            if m.any() and dense is not None:
                y = dense(t1)
                th[m], om[m] = y[0], y[1]
        return th, om


# --- solver --------------------------------------------------------------------------------------


def _geometry(block):
    """(α′, p′, η′) from a jaxrock Block or a tuple of floats."""
    if isinstance(block, tuple):
        return tuple(float(v) for v in block)
    return float(block.alpha_r), float(block.p_r), float(block.eta_r)


def _bisect_up(g, a, b, tol):
    """g(a) ≤ 0 < g(b): shrink to [a, b] with b − a ≤ tol; return b (where g > 0)."""
    for _ in range(200):
        if b - a <= tol:
            break
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        if g(m) > 0:
            b = m
        else:
            a = m
    return b


def _excess(ug, level, uv=None):
    """F(t) = |üg(t)| − level (1 + üv(t)/g), vectorised: a body at rest uplifts where F > 0."""
    if uv is None:
        return lambda s: np.abs(np.asarray(ug(s), dtype=float)) - level
    return lambda s: np.abs(np.asarray(ug(s), dtype=float)) - level * (1 + np.asarray(uv(s), dtype=float) / G)


def next_exceedance(ug, t, t_stop, level, scan_dt, uv=None):
    """First time τ ∈ [t, t_stop] with |ug(τ)| > level (1 + uv(τ)/g) (a time where it does
    exceed), or None; `uv` (vertical acceleration) None: 0."""
    F = _excess(ug, level, uv)
    g = lambda s: float(F(s))
    if g(t) > 0:
        return t
    n = max(int(math.ceil((t_stop - t) / scan_dt)), 1)
    grid = np.linspace(t, t_stop, n + 1)
    vals = F(grid)
    tol = 1e-15 * max(1.0, abs(t), abs(t_stop))
    pos = np.flatnonzero(vals > 0)
    first = pos[0] if pos.size else vals.size
    # local maxima of |üg| on the grid before the first positive sample: refine each
    for i in range(1, min(first, vals.size - 1)):
        if vals[i] >= vals[i - 1] and vals[i] >= vals[i + 1] and vals[i] > -0.05 * level:
            r = minimize_scalar(lambda s: -g(s), bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                                options={"xatol": 1e-14 * max(1.0, abs(grid[i]))})
            if -r.fun > 0:
                return _bisect_up(g, grid[i - 1], r.x, tol)
    if pos.size == 0:
        return None
    return _bisect_up(g, grid[first - 1], grid[first], tol)


def solve(
    block,
    excitation_fn,
    t_start,
    t_end,
    eta=None,
    threshold=1.0,
    rtol=1e-12,
    atol=1e-14,
    method="DOP853",
    *,
    t_final=None,
    tstops=None,
    scan_dt=None,
    zeno_v=1e-7,
    dense=None,
    max_step=np.inf,
    max_events=200_000,
    vertical_fn=None,
) -> Result:
    """Integrate the rigid rocking block from rest at `t_start` (see module docstring).

    - `block`: a jaxrock `Block` (its α′, p′, η′ are used) or a tuple (α′, p′, η′).
    - `excitation_fn(t)`: üg [m/s²], vectorised over NumPy arrays; window [t_start, t_end].
    - `eta`: impact velocity ratio (None → the block's η′); `threshold`: overturn at |θ| ≥ thr·α′.
    - `rtol`, `atol`, `method`: passed to `solve_ivp`.
    - `t_final`: integrate to this time (history runs) instead of stopping when the answer is fixed.
    - `tstops`: times the integration must step on (record samples); `scan_dt`: grid of the
      uplift scan (default: `tstops` spacing, else (t_end − t_start)/4000).
    - `vertical_fn(t)`: üv [m/s², upwards], vectorised, or None (none): it scales gravity,
      θ̈ = −p′²[(1 + üv/g) sin(sα′ − θ) + (üg/g) cos(sα′ − θ)], uplift at |üg| > (g + üv) tanα′.
    """
    alpha, p, eta_block = _geometry(block)
    eta = eta_block if eta is None else float(eta)
    thr = float(threshold)
    level = G * math.tan(alpha)
    ug = excitation_fn
    t_start, t_end = float(t_start), float(t_end)
    history_run = t_final is not None
    t_stop = float(t_final) if history_run else t_end
    if dense is None:
        dense = history_run
    if tstops is not None:
        tstops = np.asarray(tstops, dtype=float)
        if scan_dt is None and tstops.size > 1:
            scan_dt = float(np.min(np.diff(tstops)))
    if scan_dt is None:
        scan_dt = (t_end - t_start) / 4000
    p2 = p * p
    uv = vertical_fn
    gv = (lambda t: 1.0) if uv is None else (lambda t: 1.0 + float(uv(t)) / G)
    lifts = lambda t: float(_excess(ug, level, uv)(t)) > 0
    v_zeno = zeno_v * p * alpha

    def rhs(t, y, s):
        phi = s * alpha - y[0]
        return [y[1], -p2 * (gv(t) * math.sin(phi) + float(ug(t)) / G * math.cos(phi))]

    def ev_impact(t, y, s):
        return s * y[0]

    ev_impact.terminal, ev_impact.direction = True, -1

    def ev_apex(t, y, s):
        return s * y[1]

    ev_apex.terminal, ev_apex.direction = False, -1

    def ev_over(t, y, s):
        return s * y[0] - thr * alpha

    ev_over.terminal, ev_over.direction = True, 1

    t, theta, omega, side = t_start, 0.0, 0.0, 1.0
    resting = True
    peak = 0.0
    overturned, t_over = False, math.inf
    t_up0, side_up0 = math.inf, 0.0
    apexes, impacts, segments = [], [], []
    nfev = n_rest = 0
    free_after_end = False  # stop at the first apex after t_end (summary runs)

    for _ in range(max_events):
        if resting:
            t_up = next_exceedance(ug, t, t_stop, level, scan_dt, uv) if t < t_stop else None
            if t_up is None:
                segments.append((t, t_stop, None))
                break
            segments.append((t, t_up, None))
            t, theta, omega = t_up, 0.0, 0.0
            side = -math.copysign(1.0, float(ug(t)))
            resting = False
            if not math.isfinite(t_up0):
                t_up0, side_up0 = t, side
            continue

        # one rocking piece: to the next impact/overturn, or to the next tstop / end
        if history_run:
            t_seg = t_stop
        elif t < t_end:
            t_seg = t_end
        else:
            free_after_end = True
            t_seg = t + 1e4 / p
        if tstops is not None:
            nxt = tstops[tstops > t * (1 + 1e-15) + 1e-300]
            if nxt.size and nxt[0] < t_seg:
                t_seg = float(nxt[0])
        if t_seg <= t:
            break
        events = [ev_impact, ev_apex, ev_over]
        sol = solve_ivp(rhs, (t, t_seg), [theta, omega], method=method, rtol=rtol, atol=atol,
                        events=events, args=(side,), dense_output=dense, max_step=max_step)
        nfev += sol.nfev
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
        t_imp, t_apx, t_ovr = (np.asarray(e) for e in sol.t_events)
        y_apx = np.asarray(sol.y_events[1])
        stop_apex = None
        for k in range(t_apx.size):
            if t_apx[k] <= t:  # an apex exactly at the start (uplift from rest): not a peak
                continue
            apexes.append((float(t_apx[k]), float(y_apx[k][0])))
            peak = max(peak, abs(float(y_apx[k][0])) / alpha)
            if free_after_end and stop_apex is None:
                stop_apex = float(t_apx[k])
        tf = float(sol.t[-1])
        segments.append((t, tf, sol.sol))
        thf, omf = float(sol.y[0, -1]), float(sol.y[1, -1])
        if t_ovr.size:
            overturned, t_over, peak = True, float(t_ovr[0]), thr
            break
        if stop_apex is not None:
            break
        if t_imp.size:
            if float(t_imp[0]) <= t:
                # the block cannot leave θ = 0 on this side: decide as from rest
                if lifts(t):
                    side, omega, theta = -math.copysign(1.0, float(ug(t))), 0.0, 0.0
                else:
                    resting, theta, omega = True, 0.0, 0.0
                    n_rest += 1
                continue
            t = float(t_imp[0])
            post = eta * omf
            impacts.append((t, omf, post))
            theta, side = 0.0, -side
            if abs(post) < v_zeno:
                omega = 0.0
                if lifts(t):
                    side = -math.copysign(1.0, float(ug(t)))
                else:
                    resting = True
                    n_rest += 1
            else:
                omega = post
            continue
        # no event: reached t_seg
        t, theta, omega = tf, thf, omf
        if history_run and t >= t_stop:
            peak = max(peak, abs(theta) / alpha)
            break
        if free_after_end and t_seg >= t + 1e4 / p * 0.999:
            break
    else:
        raise RuntimeError("scipy_rigid.solve: too many events")

    return Result(
        max_theta=peak,
        overturned=overturned,
        t_overturn=t_over,
        n_impacts=len(impacts),
        t_uplift=t_up0,
        uplift_side=side_up0,
        apexes=apexes,
        impacts=impacts,
        segments=segments,
        n_steps=nfev,
        n_rest=n_rest,
    )


def solve_pulse(block, a_p, omega_p, *, antisymmetric=False, **kw) -> Result:
    """`solve` for a (symmetric or antisymmetric) Ricker pulse."""
    f, t0, t1 = (antisymmetric_ricker if antisymmetric else ricker)(a_p, omega_p)
    return solve(block, f, t0, t1, **kw)


def solve_record(block, acc, dt, scale=1.0, **kw) -> Result:
    """`solve` for a sampled record (acc in m/s²), stepping on every sample."""
    f, t0, t1, ts = record(acc, dt, scale)
    return solve(block, f, t0, t1, tstops=ts, **kw)
