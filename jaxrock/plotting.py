"""Figures in the style of the paper: overturning spectra (figures 6, 9, 11, 15), their uplift and
overturning boundary lines (figures 12, 16), time histories (figures 5, 8, 13), record spectra
(figure 10), and the damper calibration (figure 7 and the calibrated c̄).

Every function returns the matplotlib `Figure` and, with `path=...`, also writes it as a PNG.
The data each plot draws is kept on the figure as `fig.jaxrock_data` (a dict of numpy arrays), so
tests and scripts can check what was drawn without reading pixels.

matplotlib's non-interactive Agg backend is selected on import when no display is available
(no `DISPLAY`/`WAYLAND_DISPLAY` on Linux), so the functions work on headless machines.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import matplotlib

if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from .geometry import G  # noqa: E402

CMAP = "viridis"  # perceptually uniform
OVERTURN_COLOR = "0.55"  # grey fill (with hatching) for overturned cells
UNCERTAIN_COLOR = "m"  # ring around a cell whose verdict is uncertain (jaxrock.sensitivity)
LEVELS = np.linspace(0.0, 1.0, 11)

X_LABEL = r"$\omega_p/p$"
Y_LABEL = r"$a_p/(g\,\tan\alpha)$"
CBAR_LABEL = r"$\theta_{\max}/\alpha$"


_CREATOR = {"png": "Software", "pdf": "Creator", "svg": "Creator", "ps": "Creator", "eps": "Creator"}  # metadata key per format


def save_figure(fig, path, dpi: int = 150) -> Path:
    """`fig` written to `path`, its format from the suffix, never over a file jaxrock did not write
    (`jaxrock.io.files.refuse_foreign`); the formats that carry metadata name jaxrock in it."""
    from .io.files import refuse_foreign

    path = Path(path)
    refuse_foreign(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    key = _CREATOR.get(path.suffix[1:].lower())
    meta = {key: f"jaxrock, with Matplotlib {matplotlib.__version__}"} if key else None
    fig.savefig(path, dpi=dpi, bbox_inches="tight", metadata=meta)
    return path


def _finish(fig, path, data):
    fig.jaxrock_data = data
    if path is not None:
        save_figure(fig, path)
    return fig


def _title_of(spectrum) -> str:
    a = spectrum.attrs
    parts = [str(a.get("model", ""))]
    if "tan_alpha" in a:
        parts.append(f"tanα = {float(a['tan_alpha']):.3g}")
    if "height" in a:
        parts.append(f"2h = {float(a['height']):.3g} m")
    if "pulse" in a:
        parts.append(str(a["pulse"]))
    return ", ".join(p for p in parts if p)


def boundary_lines(spectrum) -> dict:
    """The bold lines of a spectrum plot: x = ω_p/p, the least uplifting and overturning a_p/(g tanα)."""
    return {
        "omega_ratio": np.asarray(spectrum.omega_ratio, dtype=float),
        "uplift": np.asarray(spectrum.uplift_boundary, dtype=float),
        "overturn": np.asarray(spectrum.overturn_boundary, dtype=float),
    }


def _cell_edges(v: np.ndarray) -> np.ndarray:
    """Edges of the cells centred on the grid values `v` (a lone value gets a ±5 % cell)."""
    if v.size == 1:
        half = 0.05 * abs(float(v[0])) or 0.05
        return np.array([v[0] - half, v[0] + half])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def _draw_spectrum(ax, spectrum, title, *, colorbar=True):
    x = np.asarray(spectrum.omega_ratio, dtype=float)
    y = np.asarray(spectrum.accel_ratio, dtype=float)
    z = np.clip(np.asarray(spectrum.max_theta, dtype=float), 0.0, 1.0)
    over = np.asarray(spectrum.overturned, dtype=bool)
    bad = np.asarray(spectrum.status) != 0
    # Overturned cells (θ_max/α = 1) are covered by their own grey, hatched region on top.
    if x.size >= 2 and y.size >= 2:
        cs = ax.contourf(x, y, z, levels=LEVELS, cmap=CMAP, extend="neither")
        if over.any():
            ax.contourf(
                x, y, over.astype(float), levels=[0.5, 1.5], colors=[OVERTURN_COLOR], hatches=["//"], alpha=1.0
            )
    else:  # a single row or column: contours need a 2-D grid, fall back to cells
        xe, ye = _cell_edges(x), _cell_edges(y)
        cs = ax.pcolormesh(xe, ye, z, cmap=CMAP, norm=BoundaryNorm(LEVELS, 256), shading="flat")
        if over.any():
            ax.pcolormesh(xe, ye, np.where(over, 1.0, np.nan), cmap=ListedColormap([OVERTURN_COLOR]), shading="flat")
        if x.size * y.size == 1:  # one cell: its value, written on it
            ax.text(x[0], y[0], f"θ_max/α = {float(spectrum.max_theta[0, 0]):.4g}" + ("\noverturned" if over[0, 0] else ""),
                    ha="center", va="center", fontsize=10, color="k", bbox=dict(facecolor="w", alpha=0.8, lw=0))
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
    lines = boundary_lines(spectrum)
    ax.plot(lines["omega_ratio"], lines["uplift"], color="k", lw=2.5, label="uplift")
    # dashed black on a white line: visible on the colours and on the grey overturned region
    ax.plot(lines["omega_ratio"], lines["overturn"], color="w", lw=3.5)
    ax.plot(lines["omega_ratio"], lines["overturn"], color="k", lw=2.5, ls="--", label="overturn")
    if bad.any():
        yy, xx = np.nonzero(bad)
        ax.plot(x[xx], y[yy], "rx", ms=4, label="solver status ≠ ok")
    doubt = np.asarray(getattr(spectrum, "uncertain", np.zeros_like(over)), dtype=bool)
    if doubt.any():  # verdicts rounding could flip (jaxrock.sensitivity): ringed, over the colours and the grey
        yy, xx = np.nonzero(doubt)
        ax.plot(x[xx], y[yy], "o", mfc="none", mec=UNCERTAIN_COLOR, mew=1.2, ms=5, label="verdict uncertain")
    ax.set_xlabel(X_LABEL)
    ax.set_ylabel(Y_LABEL)
    if x.size > 1 and y.size > 1:
        ax.set_xlim(x.min(), x.max())
        ax.set_ylim(y.min(), y.max())
    ax.set_title(title if title is not None else _title_of(spectrum), fontsize=10)
    cb = None
    if colorbar:
        cb = ax.figure.colorbar(cs, ax=ax, ticks=LEVELS[::2])
        cb.set_label(CBAR_LABEL)
    return cs, cb


def _legend_handles(*spectra):
    """The legend's entries; "verdict uncertain" where one of `spectra` has such a cell."""
    from matplotlib.lines import Line2D

    doubt = any(np.any(np.asarray(getattr(s, "uncertain", False))) for s in spectra)
    return [
        Line2D([], [], color="k", lw=2.5, label="least uplift"),
        Line2D([], [], color="k", lw=2.5, ls="--", label="least overturning"),
        Patch(facecolor=OVERTURN_COLOR, hatch="//", label="overturned"),
        *([Line2D([], [], ls="none", marker="o", mfc="none", mec=UNCERTAIN_COLOR, mew=1.2, label="verdict uncertain")] if doubt else []),
    ]


def plot_spectrum(spectrum, ax=None, title=None, *, path=None, legend=True):
    """Filled contours of θ_max/α over (ω_p/p, a_p/(g tanα)) (paper figures 6, 9, 11, 15).

    Overturned cells are grey and hatched; the least uplifting acceleration (solid) and the least
    overturning one (dashed) are drawn bold; cells whose run did not end with `Status.ok` are
    marked with red crosses, cells whose verdict is uncertain (`jaxrock.sensitivity`) ringed. Returns the figure (`fig.jaxrock_data` holds the boundary lines).
    """
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 4.6))
    else:
        fig = ax.figure
    _draw_spectrum(ax, spectrum, title)
    if legend:
        ax.legend(handles=_legend_handles(spectrum), loc="upper left", fontsize=7, framealpha=0.8)
    data = boundary_lines(spectrum)
    data["max_theta"] = np.asarray(spectrum.max_theta)
    data["uncertain"] = int(np.sum(np.asarray(spectrum.uncertain))) if hasattr(spectrum, "uncertain") else 0
    return _finish(fig, path, data)


def plot_spectra_grid(spectra, titles=None, *, ncols=None, path=None, suptitle=None):
    """Several spectra side by side with a shared colourbar (e.g. RM | SM | SM + masses)."""
    spectra = list(spectra)
    n = len(spectra)
    if n == 0:
        raise ValueError("plot_spectra_grid needs at least one spectrum")
    titles = [None] * n if titles is None else list(titles)
    ncols = n if ncols is None else int(ncols)
    nrows = -(-n // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.2 * ncols, 3.6 * nrows), squeeze=False, constrained_layout=True)
    cs = None
    for k, (s, t) in enumerate(zip(spectra, titles)):
        cs, _ = _draw_spectrum(axes.flat[k], s, t, colorbar=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    cb = fig.colorbar(cs, ax=axes, ticks=LEVELS[::2], shrink=0.9)
    cb.set_label(CBAR_LABEL)
    axes.flat[0].legend(handles=_legend_handles(*spectra), loc="upper left", fontsize=7, framealpha=0.8)
    if suptitle:
        fig.suptitle(suptitle)
    data = {"boundaries": [boundary_lines(s) for s in spectra]}
    return _finish(fig, path, data)


def plot_boundaries(spectra, labels=None, ax=None, *, path=None, title=None):
    """Uplift (solid) and overturning (dashed) boundary lines of several spectra on one axes
    (paper figures 12 and 16); one colour per spectrum."""
    spectra = list(spectra)
    labels = [_title_of(s) for s in spectra] if labels is None else list(labels)
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 4.6))
    else:
        fig = ax.figure
    data = []
    for k, (s, lab) in enumerate(zip(spectra, labels)):
        b = boundary_lines(s)
        c = f"C{k % 10}"
        ax.plot(b["omega_ratio"], b["uplift"], "-", color=c, lw=2, label=f"{lab}: uplift")
        ax.plot(b["omega_ratio"], b["overturn"], "--", color=c, lw=2, label=f"{lab}: overturn")
        data.append(b)
    ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel(X_LABEL)
    ax.set_ylabel(Y_LABEL)
    if title:
        ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7)
    return _finish(fig, path, {"boundaries": data, "labels": labels})


def plot_history(solutions, excitation, fields=("theta",), *, model=None, alpha=None, path=None, title=None):
    """θ/α over time with the ground acceleration üg/g below (paper figures 5, 8, 13, 17).

    `solutions`: one `Solution` with a history (`simulate(..., save=Save(ts, fields))`), or a dict
    {label: Solution} to compare models on the same axes (e.g. RM, SM, flexible SM). θ is
    normalised by `alpha`, by default the rocking slenderness α′ of `model`'s block; with neither,
    the raw θ [rad] is drawn. Further saved fields (e.g. "w_top", "base_moment" of the spring
    model) get their own panels. Overturning times are marked by vertical lines.
    """
    sols = dict(solutions) if isinstance(solutions, dict) else {"": solutions}
    if alpha is None and model is not None:
        alpha = float(model.block.alpha_r)
    fields = tuple(fields)
    for label, sol in sols.items():
        if sol.ts is None or sol.history is None:
            raise ValueError(f"plot_history needs Solutions with a time history ({label!r} has none): simulate(..., save=Save(ts, fields))")
        missing = [f for f in fields if f not in sol.history]
        if missing:
            raise ValueError(f"fields {missing} were not saved for {label!r}; saved: {sorted(sol.history)}")
    n = len(fields) + 1
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.9 * n + 0.8), sharex=True, squeeze=False, constrained_layout=True)
    axes = axes[:, 0]
    data = {}
    colors, dashes = ["k", "C3", "C0", "C2"], ["-", "--", "-.", ":"]
    for k, (label, sol) in enumerate(sols.items()):
        ts = np.asarray(sol.ts, dtype=float)
        t_over = float(np.asarray(sol.t_overturn))
        entry = {"t": ts, "t_overturn": t_over}
        for ax, f in zip(axes, fields):
            y = np.asarray(sol.history[f], dtype=float)
            if f == "theta" and alpha is not None:
                y = y / float(alpha)
            ax.plot(ts, y, color=colors[k % 4], ls=dashes[k % 4], lw=1.2, label=label or None)
            entry[f] = y
        if np.isfinite(t_over):
            for ax in axes:
                ax.axvline(t_over, color=colors[k % 4], lw=0.8, ls="--")
            axes[0].annotate(f"{label + ' ' if label else ''}overturns at t = {t_over:.3g} s", (t_over, 0.95 - 0.1 * k),
                             xycoords=("data", "axes fraction"), fontsize=8, ha="right", va="top")
        data[label] = entry
    for ax, f in zip(axes, fields):
        if f == "theta" and alpha is not None:
            ax.set_ylabel(r"$\theta/\alpha$")
            ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
            ax.axhline(-1.0, color="0.6", lw=0.8, ls=":")
        else:
            ax.set_ylabel(f)
        ax.axhline(0.0, color="0.8", lw=0.6)
    ts = np.asarray(next(iter(sols.values())).ts, dtype=float)
    ug = np.asarray(_eval_many(excitation, ts), dtype=float)
    axes[-1].plot(ts, ug / G, color="C0", lw=1.0)
    axes[-1].set_ylabel(r"$\ddot u_g/g$")
    axes[-1].set_xlabel("t [s]")
    if len(sols) > 1:
        axes[0].legend(fontsize=8, loc="lower left")
    if len(sols) == 1:  # a single solution: the flat layout the tests and callers read
        data = {**next(iter(data.values())), "ug_over_g": ug / G}
    else:
        data["ug_over_g"] = ug / G
    if title:
        axes[0].set_title(title, fontsize=10)
    return _finish(fig, path, data)


def _eval_many(excitation, ts):
    import jax

    return jax.jit(jax.vmap(excitation))(ts)


def plot_record_spectrum(record_spectra, labels=None, *, x="height", ax=None, path=None, title=None):
    """Least overturning scale factor of a record against 2h (`x="height"`) or p (`x="p"`)
    (paper figure 10); one line per `RecordSpectrum`. Heights where no factor of the sweep
    overturned the body (scale = inf) are left out of the line and marked with a triangle at the
    top of the axes."""
    record_spectra = list(record_spectra)
    labels = [str(r.attrs.get("model", "")) for r in record_spectra] if labels is None else list(labels)
    if x not in ("height", "p"):
        raise ValueError(f"x = {x!r}; valid: 'height', 'p'")
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 4.2))
    else:
        fig = ax.figure
    data = []
    for k, (rs, lab) in enumerate(zip(record_spectra, labels)):
        h = np.asarray(rs.height, dtype=float)
        s = np.asarray(rs.scale, dtype=float)
        if x == "p":
            tan_a = float(rs.attrs.get("tan_alpha_base", rs.attrs.get("tan_alpha")))
            R = 0.5 * h * np.sqrt(1 + tan_a**2)
            xv = np.sqrt(3 * G / (4 * R))
        else:
            xv = h
        fin = np.isfinite(s)
        ax.plot(xv[fin], s[fin], "o-", color=f"C{k % 10}", label=lab, ms=4)
        if (~fin).any():
            ax.plot(xv[~fin], np.ones((~fin).sum()), "^", color=f"C{k % 10}", transform=ax.get_xaxis_transform(),
                    clip_on=False, ms=6)
        data.append({"x": xv, "scale": s})
    ax.set_xlabel("2h [m]" if x == "height" else "p [rad/s]")
    ax.set_ylabel("least overturning scale factor")
    ax.set_ylim(bottom=0)
    if title:
        ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    return _finish(fig, path, {"lines": data, "labels": labels})


__all__ = [
    "plot_spectrum",
    "plot_spectra_grid",
    "plot_boundaries",
    "plot_history",
    "plot_record_spectrum",
    "boundary_lines",
]


def plot_energy_ratio(tan_alphas, cbars, xs, r2, targets, *, path=None):
    """Figure 7: the SM's free-rocking energy ratio per cycle r_eq² against θ₀/α, one line per
    (c̄, tanα) (`r2[i, j]` over `xs` for tan_alphas[i], cbars[j]), the RM's η⁴ as levels."""
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["-", "--", ":"]
    for j, c in enumerate(cbars):
        for i, t in enumerate(tan_alphas):
            ax.plot(xs, r2[i, j], styles[i % 3], color=colors[j % len(colors)], lw=1.5, label=f"c̄ = {c:g}, tanα = {t:g}")
    for i, t in enumerate(tan_alphas):
        ax.axhline(targets[i], color="k", ls=styles[i % 3], lw=0.8, alpha=0.7)
        ax.text(0.01, targets[i], f" RM r² = η⁴, tanα = {t:g}", va="bottom", fontsize=7, transform=ax.get_yaxis_transform())
    ax.axvspan(0.5, 0.95, color="0.9", zorder=0, label="calibration angles")
    ax.set_xlabel("θ₀/α")
    ax.set_ylabel("r_eq² = E(θ₁)/E(θ₀)")
    ax.set_xlim(0, 1)
    ax.set_ylim(0.4, 1.0)
    ax.set_title("Figure 7: SM (added masses) free-rocking energy ratio per cycle")
    ax.legend(fontsize=7, ncol=3, loc="lower left")
    fig.tight_layout()
    return _finish(fig, path, {"theta0_over_alpha": np.asarray(xs), "r2": np.asarray(r2), "targets": np.asarray(targets)})


def plot_calibration(res, fit, *, path=None):
    """The calibrated damper c̄ against α (`CalibrationResult`), eq. 17 and the power-law fit
    (`PowerLawFit`), and the ratio to eq. 17."""
    from .spring import cbar_eq17

    a = np.asarray(res.alpha)
    c = np.asarray(res.cbar)
    aa = np.linspace(a.min(), a.max(), 200)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10.0, 4.2))
    ax.plot(a, c, "o", label="calibrated (optax Adam through the SM)")
    ax.plot(aa, np.asarray(cbar_eq17(aa)), "k--", label="eq. 17: 0.02 (α/0.1)²")
    ax.plot(aa, fit(aa), "-", color="C1", label=f"fit: {fit.k:.4f} (α/0.1)^{fit.n:.2f}")
    ax.set_xlabel("α [rad]")
    ax.set_ylabel("c̄ = c/(m g^0.5 R^1.5)")
    ax.legend(fontsize=8)
    ax.set_title("Damper calibration: SM r_eq² = RM η⁴")
    ax2.plot(a, c / np.asarray(res.cbar_eq17), "o-")
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.set_xlabel("α [rad]")
    ax2.set_ylabel("c̄ calibrated / c̄ eq. 17")
    ax2.set_title("gap to eq. 17")
    fig.tight_layout()
    return _finish(fig, path, {"alpha": a, "cbar": c, "cbar_eq17": np.asarray(res.cbar_eq17)})


def _suite_panels(ds, var):
    """The panels of a suite figure: one column per model, one row per value of the axes other than
    record, height and model (e.g. tanα); each (title, selection)."""
    other = [d for d in ds[var].dims if d not in ("model", "record", "height", "bootstrap", "bound")]
    import itertools

    combos = list(itertools.product(*(range(ds.sizes[d]) for d in other))) or [()]
    models = list(ds.model.values) if "model" in ds.dims else [None]
    panels = []
    for c in combos:
        row = []
        for m in models:
            sel = {d: i for d, i in zip(other, c)}
            label = ", ".join(f"{d} = {float(ds[d][i]):g}" for d, i in sel.items())
            sub = ds.isel(sel)
            if m is not None:
                sub = sub.sel(model=m)
            row.append((", ".join(x for x in (str(m) if m is not None else "", label) if x), sub))
        panels.append(row)
    return panels


def _suite_figure(ds, var, draw, path, title):
    """A suite figure: `draw(ax, sub, first_column)` (returning the panel's data) in each panel of
    `_suite_panels(ds, var)`, titled by its model and values."""
    panels = _suite_panels(ds, var)
    nr, nc = len(panels), len(panels[0])
    fig, axes = plt.subplots(nr, nc, figsize=(4.2 * nc, 3.4 * nr), squeeze=False, sharey=True)
    data = []
    for r, row in enumerate(panels):
        for c, (label, sub) in enumerate(row):
            axes[r, c].set_title(label, fontsize=9, pad=14)
            data.append({"label": label, **draw(axes[r, c], sub, c == 0)})
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _finish(fig, path, data)


def plot_suite_scales(ds, *, path=None, title=None):
    """The least overturning scale factor of a suite against 2h (paper figure 10 for a suite): one
    thin line per record, the median over the records and the 16–84 % band (order statistics: a
    record that no factor of the sweep overturns counts as the largest; where a statistic is such a
    record the line stops and a triangle marks the top). `ds`: `jaxrock.analyses.suite.run_suite`."""

    def draw(ax, sub, first):
        h = np.atleast_1d(sub.height.values)
        s = np.asarray(sub.least_scale.transpose("record", ...).values, dtype=float).reshape(sub.sizes["record"], h.size)
        for line in s:
            fin = np.isfinite(line)
            ax.plot(h[fin], line[fin], "-", color="0.6", lw=0.8)
        lo, med, hi = np.percentile(s, [16.0, 50.0, 84.0], axis=0, method="inverted_cdf")
        ceiling = 1.1 * np.max(s[np.isfinite(s)], initial=1.0)  # a band up to "never overturned" reaches the top
        ax.fill_between(h, np.minimum(lo, ceiling), np.minimum(hi, ceiling), color="C0", alpha=0.25, label="16–84 %")
        fin = np.isfinite(med)
        ax.plot(h[fin], med[fin], "o-", color="C0", lw=2, ms=4, label="median")
        if (~fin).any():
            ax.plot(h[~fin], np.ones((~fin).sum()), "^", color="C0", transform=ax.get_xaxis_transform(), clip_on=False)
        never = (~np.isfinite(s)).sum(0)
        for hv, k in zip(h, never):  # records that no factor of the sweep overturns, above each size
            if k:
                ax.text(hv, 1.02, f"{k}/{s.shape[0]}", transform=ax.get_xaxis_transform(), ha="center", fontsize=7, color="0.4")
        ax.set_xlabel("2h [m]  (k/n above: records no factor overturns)")
        if first:
            ax.set_ylabel("least overturning scale factor")
            ax.legend(fontsize=8)
        ax.set_ylim(bottom=0)
        return {"height": h, "scale": s, "median": med, "p16": lo, "p84": hi}

    return _suite_figure(ds, "least_scale", draw, path, title)


def plot_fragility(ds, *, path=None, title=None):
    """Fragility curves of a suite: P(overturn) against the intensity measure, one colour per 2h, the
    lognormal fit with its bootstrap 16–84 % band, and a dot at the median. `ds`:
    `jaxrock.analyses.suite.run_suite`."""
    from .analyses.fragility import band, probability

    im, units = ds.attrs.get("im", "im"), ds["fragility_median"].attrs.get("units", "")
    med_all = np.asarray(ds.fragility_median.values, dtype=float)
    top = 2.0 * np.nanmax(med_all) if np.isfinite(med_all).any() else 1.0
    x = np.linspace(top / 400, top, 400)

    def draw(ax, sub, first):
        curves = []
        for k, h in enumerate(np.atleast_1d(sub.height.values)):
            one = sub.isel(height=k) if "height" in sub.dims else sub
            m, b = float(one.fragility_median), float(one.fragility_beta)
            if not np.isfinite(m):
                continue
            p = probability(x, m, b)
            lo, hi = band(x, one.fragility_median_boot.values, one.fragility_beta_boot.values)
            ax.fill_between(x, lo, hi, color=f"C{k % 10}", alpha=0.2)
            ax.plot(x, p, color=f"C{k % 10}", lw=1.8, label=f"2h = {h:g} m: θ = {m:.3g}, β = {b:.2f}")
            ax.plot([m], [0.5], "o", color=f"C{k % 10}", ms=4)
            curves.append({"height": float(h), "median": m, "beta": b, "x": x, "p": p, "p16": lo, "p84": hi})
        ax.set_xlabel(f"{im} [{units}]")
        if first:
            ax.set_ylabel("P(overturn)")
        ax.set_ylim(0, 1)
        ax.legend(fontsize=7)
        return {"curves": curves}

    return _suite_figure(ds, "fragility_median", draw, path, title)


__all__ += ["plot_suite_scales", "plot_fragility"]


def plot_curves(panels, *, ncols=None, path=None, title=None):
    """Line panels side by side (paper figures 3 and 4): `panels` is a list of dicts with `title`,
    `xlabel`, `ylabel` and `lines`, {label: (x, y)}; a label starting with "paper" is drawn dashed
    (a closed form of the paper), the others solid (jaxrock's models); `ncols` panels a row."""
    ncols = len(panels) if ncols is None else ncols
    nrows = -(-len(panels) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.6 * ncols, 3.6 * nrows), squeeze=False, constrained_layout=True)
    data = {}
    for k, (ax, panel) in enumerate(zip(axes.ravel(), panels)):
        for j, (label, (x, y)) in enumerate(panel["lines"].items()):
            closed_form = label.startswith("paper")
            ax.plot(x, y, "--" if closed_form else "-", lw=2.4 if not closed_form else 1.2, color=f"C{j}", label=label,
                    zorder=2 if closed_form else 1)
            data[f"{k}:{label}"] = np.stack([np.asarray(x), np.asarray(y)])
        ax.set_title(panel["title"], fontsize=9)
        ax.set_xlabel(panel["xlabel"])
        ax.set_ylabel(panel["ylabel"])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return _finish(fig, path, data)


def _risk_figure(risk, draw, path, title, sharey=True):
    """A figure of a suite's risk analysis: one row per model, one panel per column (cell); `draw(ax,
    one, first)` draws the panel of `one` (the dataset at a model and a cell) and returns its data."""
    import itertools

    cells = [d for d in risk.ds_median.dims if d not in ("model", "damage_state", "im")]
    combos = list(itertools.product(*(range(risk.sizes[d]) for d in cells))) or [()]
    nr, nc = risk.sizes["model"], len(combos)
    fig, axes = plt.subplots(nr, nc, figsize=(3.6 * nc, 3.1 * nr), squeeze=False, sharey=sharey)
    data = []
    for r in range(nr):
        for c, idx in enumerate(combos):
            sel = dict(zip(cells, idx))
            one = risk.isel(model=r, **sel)
            label = ", ".join([str(risk.model.values[r]), *(f"{d} = {float(risk[d][i]):g}" for d, i in sel.items())])
            axes[r, c].set_title(label, fontsize=8)
            data.append({"label": label, **draw(axes[r, c], one, c == 0)})
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _finish(fig, path, data)


def plot_damage_states(risk, *, path=None, title=None, im: int = 0):
    """The fragility family of a suite's damage states against its `im`-th measure: one curve per
    state (max θ/α ≥ d; 1: overturning) with its bootstrap 16–84 % band. `risk`:
    `jaxrock.analyses.risk.risk_analysis`."""
    from .analyses.fragility import band, probability

    spec, units = str(risk.im.values[im]), risk.attrs["im_units"][im]
    xs = risk.ida_im.isel(im=im).values
    x = np.exp(np.linspace(np.log(np.nanmin(xs)), np.log(np.nanmax(xs)), 300))

    def draw(ax, one, first):
        curves = []
        for s, d in enumerate(risk.damage_state.values):
            f = one.isel(im=im, damage_state=s)
            m, b = float(f.ds_median), float(f.ds_beta)
            if not np.isfinite(m):
                continue
            colour = plt.get_cmap("viridis")(s / max(risk.sizes["damage_state"] - 1, 1))
            lo, hi = band(x, f.ds_median_boot.values, f.ds_beta_boot.values)
            ax.fill_between(x, lo, hi, color=colour, alpha=0.2)
            ax.plot(x, probability(x, m, b), color=colour, lw=1.6,
                    label=("overturning" if d >= 1 else f"θ/α ≥ {d:g}") + f": θ = {m:.3g}, β = {b:.2f}")
            curves.append({"damage_state": float(d), "median": m, "beta": b})
        ax.set_xscale("log")
        ax.set_xlabel(f"{spec} [{units}]")
        if first:
            ax.set_ylabel("P(damage state reached)")
        ax.set_ylim(0, 1)
        ax.legend(fontsize=6)
        return {"curves": curves}

    return _risk_figure(risk, draw, path, title)


def plot_ida(risk, *, path=None, title=None, im: int = 0):
    """IDA curves of a suite: each record's max θ/α against its intensity (the `im`-th measure) over
    the factors, flat at 1 from overturning on; a record that stands again at a larger factor (a
    resurrection) drawn dashed; the median and 16/84 % curves over the records."""
    from .analyses.risk import ida_curves

    spec, units = str(risk.im.values[im]), risk.attrs["im_units"][im]

    def draw(ax, one, first):
        x = one.ida_im.isel(im=im).transpose("record", "scale").values
        edp = one.ida_edp.transpose("record", "scale").values
        for r in range(x.shape[0]):
            ax.plot(edp[r], x[r], "--" if int(one.windows[r]) else "-", color="0.6", lw=0.8)
        grid, (p16, p50, p84) = ida_curves(edp, x)
        ax.plot(p50, grid, "k-", lw=1.8, label="median")
        ax.plot(p16, grid, "k:", lw=1.2, label="16 / 84 %")
        ax.plot(p84, grid, "k:", lw=1.2)
        ax.set_yscale("log")
        ax.set_xlim(0, 1.05)
        ax.set_xlabel("max θ/α (1: overturned)")
        if first:
            ax.set_ylabel(f"{spec} [{units}]")
            ax.legend(fontsize=7)
        return {"im": grid, "p16": p16, "p50": p50, "p84": p84}

    return _risk_figure(risk, draw, path, title, sharey=False)


def plot_deaggregation(risk, *, path=None, title=None):
    """The deaggregation of each damage state's mean annual frequency over the hazard's measure: the
    share of λ_DS per unit ln x, P(DS|x) |dλ/dx| x / λ_DS, one curve per state."""
    x = risk.hazard_im.values
    units = risk.attrs["im_units"][0]

    def draw(ax, one, first):
        out = []
        for s, d in enumerate(risk.damage_state.values):
            colour = plt.get_cmap("viridis")(s / max(risk.sizes["damage_state"] - 1, 1))
            y = one.deaggregation.isel(damage_state=s).values
            ax.plot(x, y, color=colour, lw=1.6, label=("overturning" if d >= 1 else f"θ/α ≥ {d:g}") + f": λ = {float(one.maf[s]):.2g}/yr")
            out.append({"damage_state": float(d), "density": y})
        ax.set_xscale("log")
        ax.set_xlabel(f"{risk.im.values[0]} [{units}]")
        if first:
            ax.set_ylabel("share of λ per unit ln x")
        ax.legend(fontsize=6)
        return {"x": x, "states": out}

    return _risk_figure(risk, draw, path, title)


__all__ += ["plot_damage_states", "plot_ida", "plot_deaggregation"]


def plot_identification(result, path=None, *, title=None):
    """An identification (`jaxrock.identify`): the measured θ/α′ as dots and the fitted model's as
    lines, one per segment (each starts at a measured peak, marked), the residuals θ_model − θ_measured
    below with ± the estimated noise; where the top displacement was measured, the column's deflection
    u_top − 2h sinθ (θ the fitted one, for the measured and the fitted u_top: the bending that shows ζ
    and E); and, where there are bootstrap estimates, one histogram per parameter with its estimate and
    95 % interval."""
    seg = result.segments
    alpha = float(result.model.block.alpha_r)
    mask = np.asarray(seg.mask, dtype=bool)
    real = mask.any(axis=1)
    boot = np.asarray(result.bootstrap, dtype=float)
    P = len(result.free)
    has_boot = boot.ndim == 2 and boot.shape[0] > 0
    has_top = result.fitted_top is not None
    rows = [3.0, 1.4] + ([1.8] if has_top else []) + ([1.6] if has_boot else [])
    fig = plt.figure(figsize=(7.5, 1.3 * sum(rows) + 0.6), constrained_layout=True)
    grid = fig.add_gridspec(len(rows), max(P, 1), height_ratios=rows)
    ax = fig.add_subplot(grid[0, :])
    axr = fig.add_subplot(grid[1, :], sharex=ax)
    axw = fig.add_subplot(grid[2, :], sharex=ax) if has_top else None
    two_h = 2.0 * float(result.model.block.h)
    t_all, meas, fit, res, bend = [], [], [], [], []
    for k in np.flatnonzero(real):
        m = mask[k]
        t = np.asarray(seg.ts[k], dtype=float)[m]
        y = np.asarray(seg.theta[k], dtype=float)[m]
        f = np.asarray(result.fitted[k], dtype=float)[m]
        ax.plot(t, y / alpha, ".", color="0.45", ms=2.5, label="measured" if not t_all else None)
        ax.plot(t, f / alpha, "-", color="C3", lw=1.3, label="fitted model" if not t_all else None)
        axr.plot(t, f - y, ".", color="C0", ms=2.0)
        t_all.append(t), meas.append(y), fit.append(f), res.append(f - y)
        if has_top:
            rigid = two_h * np.sin(f)
            mt = np.asarray(seg.top_mask[k], dtype=bool)[m]
            w_meas = np.where(mt, np.asarray(seg.top[k], dtype=float)[m] - rigid, np.nan)
            w_fit = np.asarray(result.fitted_top[k], dtype=float)[m] - rigid
            axw.plot(t, 1e3 * w_meas, ".", color="0.45", ms=2.0)
            axw.plot(t, 1e3 * w_fit, "-", color="C3", lw=1.0)
            bend.append(np.stack([w_meas, w_fit]))
    cat = (lambda xs: np.concatenate(xs) if xs else np.zeros(0))
    pk_t, pk_th = np.asarray(seg.peaks_t, dtype=float), np.asarray(seg.peaks_theta, dtype=float)
    ax.plot(pk_t, pk_th / alpha, "v", mfc="none", color="k", ms=6, label="measured peaks (segment starts)")
    ax.axhline(0.0, color="0.8", lw=0.6)
    ax.set_ylabel(r"$\theta/\alpha'$")
    ax.legend(fontsize=8, loc="upper right")
    ax.tick_params(labelbottom=False)
    noise = float(result.noise)
    for s in (-noise, noise):
        axr.axhline(s, color="0.6", lw=0.8, ls=":")
    axr.axhline(0.0, color="0.8", lw=0.6)
    axr.set_ylabel("residual [rad]")
    axr.set_xlabel("t [s]")
    axr.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    if has_top:
        axr.tick_params(labelbottom=False)
        axr.set_xlabel("")
        axw.axhline(0.0, color="0.8", lw=0.6)
        axw.set_ylabel("u_top − 2h sinθ [mm]", fontsize=8)
        axw.set_xlabel("t [s]")
    est = np.asarray(result.estimate, dtype=float)
    interval = np.asarray(result.interval, dtype=float)
    if has_boot:
        for i, name in enumerate(result.free):
            axh = fig.add_subplot(grid[len(rows) - 1, i])
            axh.hist(boot[:, i], bins=min(30, max(5, boot.shape[0] // 4)), color="C0", alpha=0.6)
            axh.axvline(est[i], color="k", lw=1.5)
            for b in interval[i]:
                axh.axvline(b, color="k", lw=0.9, ls="--")
            axh.set_xlabel(name + ("" if result.identifiable[i] else " (not identifiable)"), fontsize=9)
            axh.tick_params(labelsize=7)
            axh.ticklabel_format(axis="x", useOffset=False)
            if i == 0:
                axh.set_ylabel("bootstrap", fontsize=8)
    ax.set_title(title if title else "identification: " + ", ".join(f"{n} = {v:.4g}" for n, v in zip(result.free, est)), fontsize=9)
    return _finish(fig, path, {"t": cat(t_all), "theta_measured": cat(meas), "theta_fitted": cat(fit), "residual": cat(res),
                               "alpha": alpha, "peaks_t": pk_t, "peaks_theta": pk_th, "estimate": est, "interval": interval,
                               "bootstrap": boot, "deflection": np.concatenate(bend, axis=1) if bend else None})


__all__ += ["plot_identification"]
