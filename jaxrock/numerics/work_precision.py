"""`jaxrock work-precision`: error against run time, per scene and per vmapped grid, for the RM and
the SM, with the peers on the same axes and the defaults marked.

Panels (`PANELS`), each a log–log diagram of the error of max |θ|/α′ (against a converged
reference of the same model, `Panel.reference`) over the warm run time per scene:

- RM, one scene and a grid: diffrax Tsit5, Dopri5 and Dopri8 over rtol (atol = rtol/100); Tsit5 in
  float32 (one scene, a child process with x64 off); the SciPy event loop
  (`jaxrock.numerics.scipy_rigid`, DOP853 and RK45, on the grid a subsample of its cells);
- quasi-rigid SM, one scene and a grid: Tsit5 (the default at 1e-10, after the exact pre-yield phase) and generalized-α over the
  tolerance, and OpenSeesPy (`jaxrock.numerics.opensees_sm`, Newmark at dt = T/n) when the
  `opensees` extra is installed;
- flexible SM (50 m concrete column), one scene and a grid: generalized-α over the tolerance,
  `Checked` generalized-α (the default) and OpenSeesPy;
- the spring: tanh and bilinear backbones over the smoothing θs/α′ (the quasi-rigid default: the
  bilinear at 1e-5), errors against the sharp limit (bilinear at θs = 1e-7 α′, Tsit5 1e-12): the
  regularisation's error and cost;
- the mesh: the flexible column over its number of elements, against 20 elements.

Times: jaxrock's best of `repeat` warm calls (compilation apart, in its own column: first call −
warm call); a grid's per scene is the whole vmapped `overturning_spectrum` over its cells. SciPy's
and OpenSees' per run (OpenSees' includes building its model, as its users run it).

Written: `work_precision.csv` (every point), `work_precision.md` (a table per panel and the
defaults' table docs/numerics.md quotes) and `work_precision.png`.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .kept import run_parts, write_csv, write_text
from .stability import reference, run_timed, timed

G = 9.81
COLUMNS = ("panel", "series", "setting", "error", "ms", "compile_s", "failed", "cells", "default", "peer")


@dataclass(frozen=True)
class Panel:
    name: str
    title: str
    model: str  # rigid, quasi-rigid, flexible
    grid: bool = False
    smoothing: float = 1e-4


PANELS = (
    Panel("rm-scene", "RM, one scene", "rigid"),
    Panel("rm-grid", "RM, vmapped grid", "rigid", grid=True),
    Panel("sm-scene", "quasi-rigid SM, one scene", "quasi-rigid"),
    Panel("sm-grid", "quasi-rigid SM, vmapped grid", "quasi-rigid", grid=True),
    Panel("flex-scene", "flexible SM (50 m concrete), one scene", "flexible"),
    Panel("flex-grid", "flexible SM (50 m concrete), vmapped grid", "flexible", grid=True),
    Panel("spring", "SM spring smoothing, against the sharp limit", "quasi-rigid"),
    Panel("mesh", "flexible SM, elements, against 20", "flexible"),
)


@dataclass
class Settings:
    quick: bool
    rtols: tuple = (1e-6, 1e-8, 1e-10, 1e-11)  # the references run at 1e-12
    ga_tols: tuple = (1e-4, 1e-5, 1e-6, 1e-7)
    scipy_rtols: tuple = (1e-4, 1e-6, 1e-8, 1e-10)
    opensees_steps: tuple = (100, 200, 400, 800)
    smoothings: tuple = (1e-2, 1e-3, 1e-4, 1e-5)
    elements: tuple = (2, 4, 10)
    n_elements: int = 10
    grid: int = 32
    flex_grid: int = 8
    subsample: int = 16
    repeat: int = 3
    opensees: bool = field(default_factory=lambda: _has_opensees())

    @classmethod
    def make(cls, quick: bool) -> "Settings":
        if not quick:
            return cls(quick=False)
        return cls(quick=True, rtols=(1e-6, 1e-8, 1e-10), ga_tols=(1e-4, 1e-5, 1e-6), scipy_rtols=(1e-4, 1e-6, 1e-8),
                   opensees_steps=(100, 400), smoothings=(1e-2, 1e-3, 1e-4, 1e-5), elements=(2, 4, 10), n_elements=4, grid=6, flex_grid=3,
                   subsample=4, repeat=2)


def _has_opensees() -> bool:
    """Whether OpenSeesPy loads: not installed, or installed but unable to load (its compiled
    library missing a BLAS or Python of its build: "Failed to import openseespy on Linux"), the
    OpenSees panels are left out, the latter said in one line."""
    import importlib.util

    if importlib.util.find_spec("openseespy") is None:
        return False
    try:
        import openseespy.opensees  # noqa: F401
    except Exception as e:  # openseespy raises RuntimeError, ImportError or OSError as its loader fails
        why = " ".join(str(e).split())[:200]
        print(f"work-precision: the OpenSees panels are left out: openseespy is installed but cannot load "
              f"({type(e).__name__}: {why})", file=sys.stderr)
        return False
    return True


# -- scenes ------------------------------------------------------------------------------------
def rigid_block():
    import jaxrock as jr

    return jr.Block.from_slenderness(10.0, 0.2)


def flexible_block():
    import jaxrock as jr

    return jr.Block.from_slenderness(50.0, 0.1)


def scene_pulse(block):
    """The one scene: a symmetric Ricker pulse a_p = 4 g tanα, ω_p = 6 p (uplift, impacts, no
    overturning)."""
    import jaxrock as jr

    return jr.RickerPulse(4.0 * G * float(block.tan_alpha), 6.0 * float(block.p))


def grid_axes(n: int):
    return np.linspace(1.0, 15.0, n), np.linspace(0.5, 10.0, n)


def model_of(kind: str, *, smoothing=None, backbone=None, n_elements=10):
    """The panels' model of `kind` (None: the model's default backbone and smoothing)."""
    import jaxrock as jr
    from jaxrock.spring import Column, SpringModel

    if kind == "rigid":
        return jr.RigidModel(rigid_block())
    if kind == "quasi-rigid":
        return SpringModel(rigid_block(), smoothing=smoothing, backbone=backbone)
    return SpringModel(flexible_block(), Column.concrete(), n_elements=n_elements, smoothing=smoothing, backbone=backbone)


def _scene_values(model, integrator, repeat):
    import jaxrock as jr

    sol, best, comp = run_timed(model, scene_pulse(model.block), integrator, repeat)
    return np.atleast_1d(float(sol.max_theta)), np.atleast_1d(str(jr.status_names(sol.status)) != "ok"), best, comp


def _grid_values(model, integrator, n, repeat):
    import jaxrock as jr

    wr, ar = grid_axes(n)
    spec, best, comp = timed(lambda: jr.overturning_spectrum(model, wr, ar, integrator=integrator, progress=False), repeat)
    return np.asarray(spec.max_theta).ravel(), (np.asarray(spec.status) != 0).ravel(), best / (n * n), comp


def _point(panel, series, setting, values, failed, ref, seconds, compile_s, *, default=False, peer=False):
    err = np.abs(values - ref)
    error = float(np.max(err)) if np.all(np.isfinite(err)) else math.nan
    return dict(panel=panel.name, series=series, setting=setting, error=error, ms=1e3 * seconds, compile_s=compile_s,
                failed=int(np.sum(failed)), cells=int(values.size), default=default, peer=peer)


def _subsample(n, k, seed=0):
    rng = np.random.default_rng(seed)
    return np.sort(rng.choice(n * n, size=min(k, n * n), replace=False))


# -- the panels --------------------------------------------------------------------------------
def _jax_series(panel, s: Settings, model, ref, series):
    """`series`: (label, [(setting, integrator, default)])."""
    rows = []
    for label, points in series:
        for setting, integ, default in points:
            if panel.grid:
                vals, failed, sec, comp = _grid_values(model, integ, s.flex_grid if panel.model == "flexible" else s.grid, s.repeat)
            else:
                vals, failed, sec, comp = _scene_values(model, integ, s.repeat)
            rows.append(_point(panel, label, setting, vals, failed, ref, sec, comp, default=default))
    return rows


def _reference(panel, s: Settings, model):
    integ = reference(panel.model)
    if panel.grid:
        vals, failed, _, _ = _grid_values(model, integ, s.flex_grid if panel.model == "flexible" else s.grid, 0)
    else:
        vals, failed, _, _ = _scene_values(model, integ, 0)
    if failed.any():
        raise RuntimeError(f"{panel.name}: the reference failed on {int(failed.sum())} cells")
    return vals


def rigid_panel(panel, s: Settings):
    import diffrax

    import jaxrock as jr
    from jaxrock.rigid.event_integrator import PULSE_TOLERANCES

    model = model_of("rigid")
    ref = _reference(panel, s, model)
    default = jr.EventIntegrator()
    series = []
    solvers = (("Tsit5", diffrax.Tsit5()), ("Dopri5", diffrax.Dopri5()), ("Dopri8", diffrax.Dopri8()))
    for name, solver in (solvers[::2] if s.quick else solvers):  # quick: Tsit5 and Dopri8
        at_default = lambda r: name == "Tsit5" and r == PULSE_TOLERANCES[0]  # the default on pulses: Tsit5 at rtol 1e-8, atol rtol/100
        pts = [(f"rtol {r:g}" + (" (default)" if at_default(r) else ""),
                default if at_default(r) else jr.EventIntegrator(solver=solver, rtol=r, atol=r * 1e-2), at_default(r)) for r in s.rtols]
        series.append((f"jaxrock {name}", pts))
    rows = _jax_series(panel, s, model, ref, series)
    if not panel.grid:
        rows += _float32_rows(panel, s, ref)
    rows += _scipy_rows(panel, s, ref)
    return rows


def _peer_cells(panel, s: Settings, block, ref):
    """The cells a peer runs, as (a_p, ω_p) pairs, and the reference there: the one scene, or a
    random subsample of the grid (`Settings.subsample`; half as many for the flexible column)."""
    if not panel.grid:
        ex = scene_pulse(block)
        return [(float(ex.a_p), float(ex.omega_p))], ref
    n = s.flex_grid if panel.model == "flexible" else s.grid
    wr, ar = grid_axes(n)
    W, A = np.meshgrid(wr, ar)  # the spectrum's cell order: a_p rows, ω_p columns
    idx = _subsample(n, s.subsample // 2 if panel.model == "flexible" else s.subsample)
    return [(float(A.ravel()[i] * G * float(block.tan_alpha)), float(W.ravel()[i] * float(block.p))) for i in idx], ref[idx]


def _peer_point(panel, series, setting, run, cells, ref_cells):
    """A peer's point: `run(a_p, ω_p)` → (max θ/α′, failed, seconds) on each cell; its max error
    and its mean time per run."""
    vals, failed, secs = zip(*(run(a, w) for a, w in cells))
    return _point(panel, series, setting, np.asarray(vals, float), np.asarray(failed, bool), ref_cells, float(np.mean(secs)), 0.0,
                  peer=True)


def _scipy_rows(panel, s: Settings, ref):
    from . import scipy_rigid as sr

    blk = rigid_block()
    cells, ref_cells = _peer_cells(panel, s, blk, ref)

    def run(method, r):
        def one(a, w):
            t = time.perf_counter()
            res = sr.solve_pulse(blk, a, w, rtol=r, atol=r * 1e-2, method=method)
            return res.max_theta, False, time.perf_counter() - t

        return one

    return [_peer_point(panel, f"SciPy {method}", f"rtol {r:g}", run(method, r), cells, ref_cells)
            for method in ("DOP853", "RK45") for r in s.scipy_rtols]


def _float32_rows(panel, s: Settings, ref):
    """Tsit5 over rtol in float32: a child process with x64 switched off after import."""
    code = (
        "import json, sys, jax\n"
        "import jaxrock as jr\n"
        "jax.config.update('jax_enable_x64', False)\n"
        "from jaxrock.numerics.stability import run_timed\n"
        "from jaxrock.numerics.work_precision import model_of, scene_pulse\n"
        "m = model_of('rigid'); ex = scene_pulse(m.block); out = []\n"
        "for r in json.loads(sys.argv[1]):\n"
        "    integ = jr.EventIntegrator(rtol=r, atol=r * 1e-2, root_tol=1e-6)\n"
        "    sol, best, comp = run_timed(m, ex, integ, int(sys.argv[2]))\n"
        "    out.append([r, float(sol.max_theta), str(jr.status_names(sol.status)), best, comp])\n"
        "print(json.dumps(out))\n"
    )
    rtols = [r for r in (1e-3, 1e-4, 1e-5, 1e-6) if not s.quick or r in (1e-4, 1e-6)]
    done = subprocess.run([sys.executable, "-c", code, json.dumps(rtols), str(s.repeat)], capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        return []
    return [_point(panel, "jaxrock Tsit5 float32", f"rtol {r:g}", np.atleast_1d(v), np.atleast_1d(st != "ok"), ref, sec, comp)
            for r, v, st, sec, comp in json.loads(done.stdout.strip().splitlines()[-1])]


def spring_panel(panel, s: Settings):
    from jaxrock.spring import Checked, GeneralizedAlpha, SpringIntegrator

    flexible = panel.model == "flexible"
    model = model_of(panel.model, n_elements=s.n_elements)
    ref = _reference(panel, s, model)
    ga = [(f"tol {t:g}", GeneralizedAlpha(rtol=t, atol=t), False) for t in s.ga_tols]
    if flexible:
        series = [("jaxrock generalized-α", ga),
                  ("jaxrock Checked generalized-α", [(f"tol {t:g}" + (" (default)" if t == 1e-5 else ""),
                                                      Checked(GeneralizedAlpha(rtol=t, atol=t)), t == 1e-5) for t in s.ga_tols[1:]])]
    else:
        default = model.default_integrator()  # Tsit5 at 1e-10 after the exact pre-yield phase
        tsit = [(f"tol {r:g}" + (" (default)" if r == default.rtol else ""),
                 default if r == default.rtol else SpringIntegrator(rtol=r, atol=r, solver="tsit5", max_steps=200_000),
                 r == default.rtol) for r in s.rtols]
        series = [("jaxrock Tsit5", tsit), ("jaxrock generalized-α", ga)]
    rows = _jax_series(panel, s, model, ref, series)
    if s.opensees:
        rows += _opensees_rows(panel, s, ref)
    return rows


def _opensees_rows(panel, s: Settings, ref):
    """OpenSeesPy's SM (Newmark trapezoidal at dt = min(T_p, 2π/p)/n, its model built per run as
    its users run it) on the panel's cells; its messages go to the null device."""
    import os

    import openseespy.opensees as ops

    from . import opensees_sm as osm

    flexible = panel.model == "flexible"
    blk = flexible_block() if flexible else rigid_block()
    sc = osm.Scene(2 * float(blk.h), 2 * float(blk.b), E=30e9 if flexible else None, n_elements=s.n_elements if flexible else 1)
    cells, ref_cells = _peer_cells(panel, s, blk, ref)
    ops.logFile(os.devnull, "-noEcho")

    def run(n):
        def one(a, w):
            r = osm.run_pulse(sc, a, w, steps_per_period=n)
            return r["max_theta"], r["failed"], r["time"]

        return one

    return [_peer_point(panel, "OpenSeesPy Newmark", f"dt = T/{n}", run(n), cells, ref_cells) for n in s.opensees_steps]


def smoothing_panel(panel, s: Settings):
    """tanh and bilinear backbones over θs/α′ at the default integrator (quasi-rigid, one scene),
    against the sharp limit: bilinear at θs = 1e-7 α′ by Tsit5 1e-12."""
    from jaxrock.spring import SpringIntegrator

    sharp = model_of("quasi-rigid", smoothing=1e-7, backbone="bilinear")
    ref, failed, _, _ = _scene_values(sharp, SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=4_000_000), 0)
    if failed.any():
        raise RuntimeError("the sharp-limit reference failed")
    from jaxrock.scene import default_spring

    rows = []
    default = default_spring(flexible=False)
    for backbone in ("tanh", "bilinear"):
        for th in s.smoothings:
            model = model_of("quasi-rigid", smoothing=th, backbone=backbone)
            vals, failed, sec, comp = _scene_values(model, None, s.repeat)
            is_default = (backbone, th) == default
            rows.append(_point(panel, f"{backbone} backbone", f"θs {th:g} α′" + (" (default)" if is_default else ""),
                               vals, failed, ref, sec, comp, default=is_default))
    return rows


def mesh_panel(panel, s: Settings):
    """The flexible column over its number of elements at the default integrator, against 20
    elements by generalized-α 1e-8 (one scene)."""
    ref, failed, _, _ = _scene_values(model_of("flexible", n_elements=20), reference("flexible"), 0)
    if failed.any():
        raise RuntimeError("the 20-element reference failed")
    rows = []
    for n in s.elements:
        vals, failed, sec, comp = _scene_values(model_of("flexible", n_elements=n), None, s.repeat)
        rows.append(_point(panel, "elements, default integrator", f"{n} elements" + (" (default)" if n == 10 else ""), vals, failed, ref,
                           sec, comp, default=n == 10))
    return rows


def run_panel(panel: Panel, s: Settings) -> list[dict]:
    if panel.name == "spring":
        return smoothing_panel(panel, s)
    if panel.name == "mesh":
        return mesh_panel(panel, s)
    return rigid_panel(panel, s) if panel.model == "rigid" else spring_panel(panel, s)


def work_precision(out: Path, *, quick: bool = False, progress: bool = True) -> list[dict]:
    """Every panel into `out` (`work_precision.csv`, `.md`, `.png`). Each finished panel is kept
    in `out/work_precision_panels/` (`jaxrock.numerics.kept.run_parts`): a rerun resumes."""
    from ..cache import package_version

    out = Path(out)
    s = Settings.make(quick)
    key = {"quick": quick, "version": package_version(), "opensees": s.opensees}
    rows = run_parts(PANELS, lambda p: run_panel(p, s), out / "work_precision_panels", key, name=lambda p: p.name,
                     desc="work-precision", progress=progress, columns=COLUMNS)
    write(out, rows, s)
    return rows


# -- writing -----------------------------------------------------------------------------------
def defaults_table(rows: list[dict]) -> list[str]:
    """The defaults against the peers, one line per panel with a default: the default's time and
    error, and the fastest peer point at an error no larger (else the peer's most accurate), with
    the time ratio."""
    lines = ["| scenes | default | ms/scene | max error | peer: the fastest at ≤ that error, else its most accurate | peer ms | "
             "peer / jaxrock |", "|---|---|---|---|---|---|---|"]
    for panel in PANELS:
        pts = [r for r in rows if r["panel"] == panel.name]
        d = next((r for r in pts if r["default"]), None)
        if d is None:
            continue
        peers = [r for r in pts if r["peer"] and np.isfinite(r["error"])]
        good = [r for r in peers if r["error"] <= max(d["error"], 1e-15)]
        peer = min(good, key=lambda r: r["ms"]) if good else (min(peers, key=lambda r: r["error"]) if peers else None)
        p_cells = (f"{peer['series']} {peer['setting']} ({peer['error']:.1e}) | {peer['ms']:.3g} | {peer['ms'] / d['ms']:.0f}×" if peer
                   else "— | — | —")
        lines.append(f"| {panel.title} | {d['series']} {d['setting']} | {d['ms']:.3g} | {d['error']:.1e} | {p_cells} |")
    return lines


def write(out: Path, rows: list[dict], s: Settings) -> None:
    lines = [f"# Work–precision ({'quick' if s.quick else 'full'})", "",
             "Error: max |Δ max θ/α′| against each panel's converged reference (over a grid's cells, or a peer's subsample); "
             "ms: warm run time per scene (a grid: the vmapped spectrum over its cells); compile apart. "
             f"OpenSeesPy {'included' if s.opensees else 'not installed (the `opensees` extra)'}.", "",
             "## Defaults against the peers", "", *defaults_table(rows), ""]
    for panel in PANELS:
        pts = [r for r in rows if r["panel"] == panel.name]
        lines += [f"## {panel.title}", "", "| series | setting | max error | ms/scene | compile s | failed | cells |", "|---|---|---|---|---|---|---|"]
        lines += [f"| {r['series']} | {r['setting']} | {r['error']:.2e} | {r['ms']:.3g} | {r['compile_s']:.1f} | {r['failed']} | {r['cells']} |"
                  for r in pts]
        lines.append("")
    write_text(out / "work_precision.md", "\n".join(lines))
    write_csv(out / "work_precision.csv", COLUMNS, rows)
    _figure(out / "work_precision.png", rows)


def _figure(path: Path, rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    panels = [p for p in PANELS if any(r["panel"] == p.name for r in rows)]
    ncols = 2
    nrows = math.ceil(len(panels) / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(11, 3.6 * nrows), squeeze=False)
    for ax, panel in zip(axes.ravel(), panels):
        pts = [r for r in rows if r["panel"] == panel.name]
        floor = 1e-16
        for series in dict.fromkeys(r["series"] for r in pts):
            ss = [r for r in pts if r["series"] == series and np.isfinite(r["error"])]  # in the order measured: the setting's
            ax.loglog([r["ms"] for r in ss], [max(r["error"], floor) for r in ss], "s--" if ss and ss[0]["peer"] else "o-",
                      label=series, ms=4)
        for r in pts:
            if r["default"] and np.isfinite(r["error"]):
                ax.loglog(r["ms"], max(r["error"], floor), "*", color="k", ms=14, mfc="gold", zorder=5)
        ax.set_title(panel.title, fontsize=9)
        ax.set_xlabel("ms per scene (warm)")
        ax.set_ylabel("max error in max θ/α′")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    fig.suptitle("Work–precision (★ the default)")
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
