"""`jaxrock stability`: the three models' defaults on stiff and extreme scenes, as a matrix.

Each row is a scene (a `Case`) run by each model that applies to it — the rigid model (RM), the
quasi-rigid spring model (one DOF) and the flexible column (corotational beams) — with the
model's default integrator, and again by a refined reference of the same model (`REFERENCES`).
A cell records: the summary is finite or not, the status, the error of max |θ|/α′ against the
reference, the stated accuracy (`ACCURACY`), the warm run time, and the verdict (`VERDICTS`):

- `holds`: status ok and the error within the stated accuracy;
- `flagged`: a status other than ok (the run says not to trust it: honest);
- `ok but off`: status ok, the error beyond the stated accuracy (a status that lies);
- `not finite`: a non-finite summary;
- `no reference`: the reference itself did not end ok (the error is unknown).

float32 rows run the RM and the quasi-rigid SM in a child process with x64 switched off
(`jaxrock.runtime` switches it on at import; float32 is not a supported mode) against the float64
reference.

Written: `stability.md`, `stability.csv` and the heat map `stability.png` (rows × models, the
colour log10(error / accuracy), each cell's verdict written in it).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from .kept import run_parts, write_csv, write_text

G = 9.81
HOLDS, FLAGGED, OFF, NOT_FINITE, NO_REFERENCE = "holds", "flagged", "ok but off", "not finite", "no reference"
VERDICTS = (HOLDS, FLAGGED, OFF, NOT_FINITE, NO_REFERENCE)
MODELS = ("rigid", "quasi-rigid", "flexible")
#: the stated accuracy of each model's default in max |θ|/α′: the RM's and the quasi-rigid SM's
#: work–precision targets (docs/numerics.md), and the flexible default's `Checked` accuracy
ACCURACY = {"rigid": 1e-6, "quasi-rigid": 1e-6, "flexible": 1e-2}
COLUMNS = ("case", "group", "model", "finite", "status", "max_theta", "reference", "error", "accuracy", "verdict", "ms")


@dataclass(frozen=True)
class Case:
    """A scene: a block (2h, tanα), a spring (θs/α′, E of a flexible column; None: concrete),
    and a symmetric Ricker pulse a_p = accel_ratio · g tanα, ω_p = omega_ratio · p, or El Centro
    NS 1940 × `record` (40 s). `models`: those run; `precision`: "float32" runs in a child process."""

    name: str
    group: str
    height: float = 10.0
    tan_alpha: float = 0.2
    accel_ratio: float = 4.0
    omega_ratio: float = 6.0
    record: float | None = None
    smoothing: float = 1e-4
    E: float | None = None
    models: tuple[str, ...] = MODELS
    precision: str = "float64"
    quick: bool = True  # in the quick matrix

    def excitation(self):
        import jaxrock as jr

        if self.record is not None:
            return jr.el_centro().scaled(self.record)
        blk = self.block()
        return jr.RickerPulse(self.accel_ratio * G * self.tan_alpha, self.omega_ratio * float(blk.p))

    def block(self):
        import jaxrock as jr

        return jr.Block.from_slenderness(self.height, self.tan_alpha)


BASE = Case("base: 2h 10 m, tanα 0.2, a_p 4, ω_p/p 6", "base")
SPRING = ("quasi-rigid", "flexible")
CASES = (
    BASE,
    *(replace(BASE, name=f"θs = 1e-{k} α′ (stiffness × 1e{k - 1})", group="pre-yield stiffness", smoothing=10.0**-k, models=SPRING,
              quick=k in (2, 6)) for k in range(1, 7)),
    replace(BASE, name="E = 1e14 Pa (quasi-rigid beam)", group="quasi-rigid beam", E=1e14, models=("flexible",)),
    replace(BASE, name="E = 1e14 Pa, θs = 1e-6 α′", group="quasi-rigid beam", E=1e14, smoothing=1e-6, models=("flexible",), quick=False),
    replace(BASE, name="tanα 0.02", group="slenderness", tan_alpha=0.02),
    replace(BASE, name="tanα 0.5", group="slenderness", tan_alpha=0.5, quick=False),
    replace(BASE, name="2h 0.5 m", group="size", height=0.5, quick=False),
    replace(BASE, name="2h 200 m", group="size", height=200.0),
    replace(BASE, name="a_p = g tanα exactly", group="pulse amplitude", accel_ratio=1.0),
    replace(BASE, name="a_p = 50 g tanα", group="pulse amplitude", accel_ratio=50.0, omega_ratio=30.0, quick=False),
    replace(BASE, name="ω_p/p 0.5", group="pulse frequency", omega_ratio=0.5, accel_ratio=2.0, quick=False),
    replace(BASE, name="ω_p/p 30", group="pulse frequency", omega_ratio=30.0, accel_ratio=20.0),
    replace(BASE, name="near overturning (ω_p/p 6.42, a_p 7.85)", group="near overturning", omega_ratio=6.42, accel_ratio=7.85,
            quick=False),
    replace(BASE, name="chattering (a_p 1.1 g tanα, ω_p/p 1)", group="chattering", accel_ratio=1.1, omega_ratio=1.0),
    replace(BASE, name="El Centro × 2, 40 s", group="record", record=2.0, quick=False),
    replace(BASE, name="El Centro × 1, 40 s", group="record", record=1.0, models=("rigid", "quasi-rigid"), quick=False),
    replace(BASE, name="float32", group="precision", models=("rigid", "quasi-rigid"), precision="float32"),
)


def model_of(case: Case, kind: str, n_elements: int):
    import jaxrock as jr
    from jaxrock.spring import Column, SpringModel

    blk = case.block()
    if kind == "rigid":
        return jr.RigidModel(blk)
    if kind == "quasi-rigid":
        return SpringModel(blk, smoothing=case.smoothing)
    return SpringModel(blk, Column.concrete() if case.E is None else Column(case.E), n_elements=n_elements, smoothing=case.smoothing)


def reference(kind: str):
    """The refined run of each model: the RM by Dopri8 at rtol 1e-12; the quasi-rigid SM by Tsit5 at
    1e-12; the flexible column by generalized-α at 1e-8 (measured against Kvaerno5 1e-7 to 4e-7 on
    the benchmark's grid) on a ladder 20 levels deep: at 1e-8 the bilinear spring's stiff pre-yield
    band asks for steps below the default's 16 levels (tanα 0.02: a step of dt_top/2^15 after
    the kink failed its error test; 20 levels: ok, 8560 attempts)."""
    import diffrax

    import jaxrock as jr
    from jaxrock.spring import GeneralizedAlpha, SpringIntegrator

    if kind == "rigid":
        return jr.EventIntegrator(solver=diffrax.Dopri8(), rtol=1e-12, atol=1e-14, max_steps=100_000)
    if kind == "quasi-rigid":
        return SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=2_000_000)
    return GeneralizedAlpha(rtol=1e-8, atol=1e-8, max_steps=2_000_000, levels=20)


def timed(call, repeat: int):
    """(result, warm seconds, compile seconds) of `call()`: a first call, then the best of
    `repeat` more (0: untimed, +inf), compilation the first call's excess."""
    t = time.perf_counter()
    out = call()
    first = time.perf_counter() - t
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = call()
        best = min(best, time.perf_counter() - t)
    return out, best, max(first - best, 0.0)


def run_timed(model, excitation, integrator=None, repeat: int = 1):
    """(`Solution`, warm seconds, compile seconds) of one scene (`timed`)."""
    import jax

    import jaxrock as jr

    return timed(lambda: jax.block_until_ready(jr.simulate(model, excitation, integrator=integrator)), repeat)


def _run(model, excitation, integrator=None, repeat: int = 1):
    """(max θ/α′, status name, warm seconds) of one scene (`run_timed`)."""
    import jaxrock as jr

    sol, seconds, _ = run_timed(model, excitation, integrator, repeat)
    return float(sol.max_theta), str(jr.status_names(sol.status)), seconds


def verdict(finite: bool, status: str, error: float, accuracy: float, reference_ok: bool) -> str:
    if not finite:
        return NOT_FINITE
    if status != "ok":
        return FLAGGED
    if not reference_ok:
        return NO_REFERENCE
    return HOLDS if error <= accuracy else OFF


def _float32_child(case: Case) -> dict:
    """The case's RM and quasi-rigid SM default runs in a child process with x64 off."""
    code = (
        "import json, sys, jax, jaxrock as jr\n"
        "jax.config.update('jax_enable_x64', False)\n"
        "from jaxrock.numerics.stability import Case, model_of, _run\n"
        "case = Case(**json.loads(sys.argv[1]))\n"
        "out = {}\n"
        "for kind in case.models:\n"
        "    m, s, t = _run(model_of(case, kind, 4), case.excitation())\n"
        "    out[kind] = [m, s, t]\n"
        "print(json.dumps(out))\n"
    )
    done = subprocess.run([sys.executable, "-c", code, json.dumps(asdict(case))], capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        return {kind: [math.nan, "solver_failed", math.nan] for kind in case.models}
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_case(case: Case, n_elements: int) -> list[dict]:
    """The rows of one case: one per model."""
    child = _float32_child(case) if case.precision == "float32" else None
    rows = []
    for kind in case.models:
        model, ex = model_of(case, kind, n_elements), case.excitation()
        ref, ref_status, _ = _run(model, ex, reference(kind), repeat=0)
        value, status, seconds = child[kind] if child is not None else _run(model, ex)
        finite = bool(np.isfinite(value))
        error = abs(value - ref) if finite and np.isfinite(ref) else math.nan
        rows.append(dict(case=case.name, group=case.group, model=kind, finite=finite, status=status, max_theta=value, reference=ref,
                         error=error, accuracy=ACCURACY[kind], verdict=verdict(finite, status, error, ACCURACY[kind], ref_status == "ok"),
                         ms=1e3 * seconds))
    return rows


def stability(out: Path, *, quick: bool = False, progress: bool = True) -> list[dict]:
    """Run the matrix (`CASES`; quick: the cases marked quick, 4 elements against 10) into `out`:
    `stability.md`, `stability.csv`, `stability.png`. Returns the rows. Each finished case is kept
    in `out/stability_cases/` (`jaxrock.numerics.kept.run_parts`): a rerun resumes."""
    from ..cache import package_version

    out = Path(out)
    cases = [c for c in CASES if c.quick or not quick]
    n_elements = 4 if quick else 10
    key = {"quick": quick, "version": package_version()}
    rows = run_parts(cases, lambda c: run_case(c, n_elements), out / "stability_cases", key,
                     name=lambda c: f"{CASES.index(c):02d}", desc="stability", progress=progress, columns=COLUMNS)
    write(out, rows, quick=quick, n_elements=n_elements)
    return rows


def write(out: Path, rows: list[dict], *, quick: bool, n_elements: int) -> None:
    counts = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
    lines = [
        f"# Stability matrix ({'quick' if quick else 'full'}; flexible columns of {n_elements} elements)",
        "",
        "Each model's default integrator against a refined reference of the same model (RM: Dopri8 1e-12; quasi-rigid SM: Tsit5 "
        "1e-12; flexible SM: generalized-α 1e-8). Error: |Δ max θ/α′|. Verdicts: " + ", ".join(f"{v} {n}" for v, n in counts.items()) + ".",
        "",
        "| case | model | finite | status | max θ/α′ | reference | error | accuracy | verdict | ms |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['case']} | {r['model']} | {'yes' if r['finite'] else 'no'} | {r['status']} | {r['max_theta']:.6g} | "
                     f"{r['reference']:.6g} | {r['error']:.1e} | {r['accuracy']:.0e} | {r['verdict']} | {r['ms']:.1f} |")
    write_text(out / "stability.md", "\n".join(lines) + "\n")
    write_csv(out / "stability.csv", COLUMNS, rows)
    _heat_map(out / "stability.png", rows)


def _heat_map(path: Path, rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    cases = list(dict.fromkeys(r["case"] for r in rows))
    grid = np.full((len(cases), len(MODELS)), np.nan)
    text = [["" for _ in MODELS] for _ in cases]
    for r in rows:
        i, j = cases.index(r["case"]), MODELS.index(r["model"])
        e = r["error"] / r["accuracy"]
        grid[i, j] = np.log10(max(e, 1e-6)) if np.isfinite(e) else 2.0
        text[i][j] = r["verdict"] if r["verdict"] != FLAGGED else r["status"]
    fig, ax = plt.subplots(figsize=(8.5, 0.38 * len(cases) + 1.6))
    im = ax.imshow(grid, cmap="RdYlGn_r", vmin=-6, vmax=2, aspect="auto")
    for i in range(len(cases)):
        for j in range(len(MODELS)):
            ax.text(j, i, text[i][j] or "—", ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(MODELS)), MODELS)
    ax.set_yticks(range(len(cases)), cases, fontsize=7)
    fig.colorbar(im, ax=ax, label="log10(error / stated accuracy)")
    ax.set_title("Defaults on stiff and extreme scenes")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
