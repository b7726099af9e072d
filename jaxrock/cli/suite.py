"""`jaxrock suite`: a record suite's least overturning factors and fragility, for each model."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from .guards import (report, say, EXIT_INTERRUPTED, _estimate, _exit_if_untrusted, _guarded, _history, _hold, _resume_command,
                     _status_counts, record_run_seconds, SENSITIVITY_COST)
from ..scene import BUILTIN_SUITE, MAX_ENSEMBLE, RECORD_ALIASES, builtin_record_names
from .options import model_option, _check_count, _check_refine, parse_values, SENSITIVITY_HELP, LIST_HELP as _LIST, uncertain_line
from .grammar import flag_of
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION


@app.command()
@_guarded
def suite(
    records: Optional[list[str]] = typer.Argument(None, help="record files, folders of records (.AT2, .txt, .dat, .csv), list files (.list: one per line) and "
                                                  f"packaged records ({builtin_record_names()}) or '{BUILTIN_SUITE}' (all five), as --record does; default: '{RECORD_ALIASES[0]}'"),
    record: Optional[str] = typer.Option(None, help="the records, as the arguments take them, separated by commas (the grammar of "
                                         "sweep --record)"),
    model: list = model_option("rigid,spring,spring-flexible", many=True),
    height: str = typer.Option("1,2,4,8", help=f"full height 2h [m]: {_LIST}"),
    tan_alpha: str = typer.Option("0.2", help=f"slenderness tanα: {_LIST}"),
    scale: str = typer.Option("0.25:4:16", help="record factors of the sweep ('1,2,5' or 'a:b:n'): the fragility's observations, "
                              "and the brackets the least overturning factor is bisected in"),
    refine: int = typer.Option(5, help="bisections of each least overturning factor (resolution: the sweep's step / 2^refine)"),
    im: str = typer.Option("pga", help="intensity measures, comma-separated; the first is the fragility's and the hazard's: pga [m/s2], "
                           "pgv [m/s], pgd [m], arias [m/s], cav [m/s], sa:T (Sa [m/s2] at T seconds, 5 % damping), sa:T1 (at the "
                           "column's first period, eq. 21), pga_ratio (PGA/(g tanα)), pgv_ratio (PGV p/(g tanα)), or scale (the factor)"),
    damage_states: str = typer.Option("1", help="damage states: increasing thresholds of max θ/α in (0, 1], 1 = overturning "
                                      "(e.g. 0.1,0.5,1): a fragility per state and measure, the IDA curves and the measures' efficiency"),
    hazard: Optional[str] = typer.Option(None, help="hazard curve of the first --im: a CSV of its value [SI units, or g with '[g]' in "
                                         "the header] and annual rate of exceedance, or 'power:k0,k' (rate = k0 x^-k): each damage "
                                         "state's mean annual frequency and probability in --years"),
    years: float = typer.Option(50.0, help="exposure time of the damage states' probabilities [years], > 0"),
    boot: int = typer.Option(500, help="bootstrap resamplings of the records (the fragility's band)"),
    units: Optional[str] = typer.Option(None, help="acceleration units of two-column record files (default g)"),
    out: Path = typer.Option(Path("out/suite"), help="output folder: suite.zarr, least_scale.csv/.png, fragility.csv/.md/.png, "
                             "and each model's sweep store <model>.zarr (a rerun resumes it)"),
    sensitivity: bool = typer.Option(True, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    ensemble: int = typer.Option(0, help=f"replace each uncertain verdict by the fraction of this many runs at its factor x (1 ± 1e-7) "
                                 f"that overturn, and fit the fragility on those fractions (0 to {MAX_ENSEMBLE}; 0: the verdicts)"),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a suite estimated beyond 1 h"),
):
    """A record suite: each record's intensity measures, its least overturning scale factor for each
    column (figure 10 for a suite: median and 16-84 % band) and the fragility of each column
    (lognormal by maximum likelihood, bootstrap band), for each model."""
    from .._validate import JaxrockInputError, check_grid, check_writable
    from ..analyses.suite import _check_im, check_motion

    kinds = [k.value for k in model]
    _check_refine(refine)
    _check_count("--boot", boot)
    from ..analyses.risk import check_damage_states
    from ..intensity import parse_ims

    ims = parse_ims(im, allow_scale=True)
    _check_im(ims[0])
    states = check_damage_states(parse_values("--damage-states", damage_states))
    if not (np.isfinite(years) and years > 0):
        raise JaxrockInputError(f"--years = {years:g}; valid: a number > 0 (the exposure time)")
    if hazard is not None and ims[0] == "scale":
        raise JaxrockInputError("--hazard: the first --im is 'scale', which no hazard curve is given in; put a measure first")
    from ..analyses.hazard import HazardCurve

    curve = None if hazard is None else HazardCurve.parse(hazard)
    if not 0 <= ensemble <= MAX_ENSEMBLE:
        raise JaxrockInputError(f"--ensemble = {ensemble}; valid: an integer in [0, {MAX_ENSEMBLE}] (0: the verdicts as they are)")
    if ensemble and not sensitivity:
        raise JaxrockInputError("--ensemble replaces the uncertain verdicts, which only --sensitivity finds: drop --no-sensitivity")
    given = {}
    for name, text in (("height", height), ("tan_alpha", tan_alpha)):
        v = parse_values(flag_of(name), text)
        given[name] = float(v[0]) if v.size == 1 else v
    sc = parse_values("--scale", scale)
    if sc.size < 2:
        raise JaxrockInputError(f"--scale {scale!r}: one factor; give at least 2 (the sweep whose outcomes are fitted)")
    check_grid("--scale", sc)  # the least overturning factor is the first of them that overturns
    check_writable("--out", out / "fragility.csv")
    _hold(out, "--out")
    from ..io.records import read_records
    from ..analyses.sweep import Sweep

    records = [*(records or ()), *(r.strip() for r in (record or "").split(",") if r.strip())]
    for src in records:
        if Path(src).is_dir() and os.path.realpath(src) == os.path.realpath(out):
            raise JaxrockInputError(f"--out {out}: is the records folder {src}; the suite's CSV outputs would be read as records "
                                    "on a rerun: choose another --out")
    recs = read_records(records or [RECORD_ALIASES[0]], units=units)
    check_motion(recs)
    seconds = max(float(r.t_end - r.t_start) for r in recs)
    runs = cost = 0.0
    for k in kinds:
        sw = Sweep.make(k, records=recs, scale=sc, **given)  # every value checked before anything runs
        n = sw.size + refine * sw.size // sc.size
        runs, cost = runs + n, cost + n * record_run_seconds(k, seconds) * (SENSITIVITY_COST if sensitivity else 1.0)
    _estimate(int(runs), kinds[0], yes, what=f"record runs ({', '.join(kinds)})", per_cell=cost / runs)
    from ..analyses.suite import run_suite
    from ..interrupt import Interrupted
    from ..io import store as zstore
    from ..reports import fragility_rows, suite_files

    t0 = time.perf_counter()
    try:
        ds = run_suite(kinds, recs, scale=sc, refine=refine, im=ims[0], n_boot=boot, store_dir=out, progress=not quiet,
                       history=_history(), sensitivity=sensitivity, ensemble=ensemble, **given)
    except Interrupted:
        kept = ", ".join(f"{out / f'{k}.zarr'} ({zstore.kept_scenes(out / f'{k}.zarr'):,} runs)" for k in kinds if (out / f"{k}.zarr").is_dir())
        typer.echo(f"interrupted: the sweeps kept in {kept or 'no store yet'}; resume with: {_resume_command()}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    from ..analyses.risk import risk_analysis
    from ..reports import risk_files

    risk = risk_analysis(ds, recs, damage_states=states, ims=[i for i in ims if i != "scale"] or ["pga"], hazard=curve, years=years,
                         n_boot=boot)
    if hazard is not None:
        risk.attrs["hazard"] = hazard  # as the user gave it: the file, or power:k0,k
    secs = time.perf_counter() - t0
    files = suite_files(ds, out, f"{len(recs)} records")
    files.update(risk_files(risk, out, f"{len(recs)} records"))
    say(f"suite: {len(recs)} records × {len(kinds)} model(s) × {ds.sizes['scale']} factors"
               + "".join(f" × {len(v)} {k}" for k, v in given.items() if np.ndim(v)) + f" in {secs:.1f} s")
    say(f"{'record':<24}{'PGA [m/s2]':>11}{'PGV [m/s]':>11}{'D5-95 [s]':>11}")
    for r in range(ds.sizes["record"]):
        one = ds.isel(record=r)
        say(f"{str(one.record.values)[:23]:<24}{float(one.pga):11.3f}{float(one.pgv):11.3f}{float(one.d5_95):11.2f}")
    say(Path(files["table"]).read_text(encoding="utf-8").split("\n\n")[1])
    say(Path(files["efficiency"]).read_text(encoding="utf-8").split("\n\n")[1])
    if curve is not None:
        say(Path(files["risk"]).read_text(encoding="utf-8").split("\n\n")[1])
    say(uncertain_line(ds.least_scale_uncertain.values if sensitivity else None, ds.uncertain.values, "least factor(s)",
                              ds.least_scale.size))
    say("wrote " + ", ".join(str(p) for p in files.values()))
    report("suite", {"models": kinds, "records": [{"record": str(ds.record.values[r]), "pga": float(ds.pga[r]), "pgv": float(ds.pgv[r]),
                                                    "d5_95": float(ds.d5_95[r])} for r in range(ds.sizes["record"])],
                     "fragility": fragility_rows(ds), "damage_states": _table_rows(files["damage_states"]),
                     "efficiency": _table_rows(files["efficiency_csv"]),
                     **({"risk": _table_rows(files["risk_csv"])} if "risk_csv" in files else {}),
                     "status": _status_counts(ds.worst_status.values), "seconds": secs, "files": list(files.values())},
           {"pga": "m/s2", "pgv": "m/s", "d5_95": "s", "seconds": "s"})
    _exit_if_untrusted(_status_counts(ds.worst_status.values), "column(s) × record(s)")


def _table_rows(path) -> list[dict]:
    """The rows of a table this command wrote (numbers as numbers), for --json."""
    import csv

    def value(v):
        try:
            return float(v)
        except ValueError:
            return v

    with open(path, encoding="utf-8") as fh:
        return [{k: value(v) for k, v in row.items()} for row in csv.DictReader(line for line in fh if not line.startswith("#"))]
