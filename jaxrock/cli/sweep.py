"""`jaxrock sweep`: every scene of a product of axes into a chunked Zarr store, on local devices or a Dask cluster."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from . import guards
from .guards import (report, say, EXIT_INTERRUPTED, _estimate, _exit_if_untrusted, _guarded, _history, _resume_command,
                     _status_counts, record_run_seconds, SENSITIVITY_COST, cell_seconds)
from ..scene import (BUILTIN_SUITE, DEFAULT_MODEL, DEFAULT_PULSE, builtin_record_names, model_params, pulse_params)
from .options import (model_option, BackboneKind, ModelKind, PulseKind, _check_count, _integrator, parse_values, SENSITIVITY_HELP, LIST_HELP as
                      _LIST, check_pulse_params, uncertain_line, with_params)
from .grammar import flag_of
from .app import QUIET_OPTION, TOL_HELP, app, BACKBONE_DEFAULTS, JSON_OPTION


@app.command()
@_guarded
@with_params(lists=True)
def sweep(
    model: ModelKind = model_option(DEFAULT_MODEL),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles (pulse sweeps)"),
    accel_ratio: Optional[str] = typer.Option(None, help=f"a_p/(g tanα′): {_LIST} (pulse sweeps; default 0.5:10:48)"),
    omega_ratio: Optional[str] = typer.Option(None, help=f"ω_p/p′: {_LIST} (pulse sweeps; default 1:15:48)"),
    record: Optional[str] = typer.Option(None, help="a record sweep instead of pulses: record files, folders of records (.AT2, "
                                          f".txt, .dat, .csv), packaged records ({builtin_record_names()}) or '{BUILTIN_SUITE}' (all of them), separated by commas"),
    units: Optional[str] = typer.Option(None, help="acceleration units of two-column record files (default g)"),
    scale: Optional[str] = typer.Option(None, help=f"record factor: {_LIST} (record sweeps; default 1)"),
    height: str = typer.Option("10", help=f"full height 2h [m]: {_LIST}"),
    tan_alpha: str = typer.Option("0.2", help=f"slenderness tanα: {_LIST}"),
    tan_alpha_base: Optional[str] = typer.Option(None, help=f"extended base tanα′ ≥ tanα: {_LIST}"),
    smoothing: Optional[str] = typer.Option(None, help=f"spring: pre-yield rotation θs/α′ in (0, 1): {_LIST}"),
    backbone: Optional[BackboneKind] = typer.Option(None, help=f"spring: base-spring backbone (default {BACKBONE_DEFAULTS})"),
    tol: Optional[float] = typer.Option(None, help=TOL_HELP),
    out: Path = typer.Option(Path("out/sweep.zarr"), help="the Zarr store (xarray.open_zarr reads it); a rerun of the same "
                               "command resumes it, one with other parameters is refused"),
    chunk_size: int = typer.Option(1024, help="most scenes per chunk: one vmapped batch, one Zarr chunk, one Dask task (1024: the fastest of 256, 1024, 4096 on the rigid model, benchmarks/bench_sweep.py)"),
    devices: Optional[int] = typer.Option(None, help="run chunks on this many local devices, one chunk per device at a time "
                                          "(default: all; on a CPU, one device per core)"),
    scheduler: Optional[str] = typer.Option(None, help="address of a running Dask scheduler (tcp://host:8786): each chunk is a "
                                            "task of its workers, which write into --out (a folder they all see); needs "
                                            "jaxrock[distributed]"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a sweep estimated beyond 1 h or 2 GB"),
    **params: Optional[str],
):
    """Every scene of a product of axes (pulses or records × sizes × slendernesses × model
    parameters) into a chunked Zarr store: resumable, a chunk per local device at a time, or spread
    over a Dask cluster."""
    from .._validate import JaxrockInputError, check_writable
    from ..scene import sweep_quantities, takes

    _check_count("--chunk-size", chunk_size)
    if devices is not None:
        _check_count("--devices", devices)
    lists = {"height": height, "tan_alpha": tan_alpha, "tan_alpha_base": tan_alpha_base, **params, "smoothing": smoothing,
             "accel_ratio": accel_ratio, "omega_ratio": omega_ratio, "scale": scale}
    given = {}
    for name, text in lists.items():
        if text is None:
            continue
        flag = flag_of(name)
        if (name in model_params() or name == "smoothing") and model.value not in takes(name):
            raise JaxrockInputError(f"{flag} applies to --model {' / '.join(takes(name))} only, not {model.value}")
        if name in pulse_params():
            check_pulse_params(pulse.value, {name: text}, record is not None)
        v = parse_values(flag, text)
        given[name] = float(v[0]) if v.size == 1 else v
    if record is None:
        if scale is not None:
            raise JaxrockInputError("--scale applies to record sweeps (--record), not to pulses")
        given.setdefault("accel_ratio", np.linspace(0.5, 10.0, 48))
        given.setdefault("omega_ratio", np.linspace(1.0, 15.0, 48))
        recs = None
    else:
        for name in ("accel_ratio", "omega_ratio"):
            if name in given:
                raise JaxrockInputError(f"{flag_of(name)} applies to pulse sweeps, not to --record")
        from ..io.records import read_records

        recs = read_records([r for r in record.split(",") if r.strip()], units=units)
    if scheduler is not None and devices is not None:
        raise JaxrockInputError("--devices applies to this process; with --scheduler each worker uses its own devices")
    devs = None if scheduler is not None else _local_devices(devices)
    if out.name in ("", ".", ".."):
        raise JaxrockInputError(f"--out {str(out)!r}: names the current or a parent folder, not a store; "
                                "give a folder of its own, e.g. --out out/sweep.zarr")
    if out.exists() and not out.is_dir():
        raise JaxrockInputError(f"--out {out}: is a file; expected a Zarr store folder (new or made by this sweep)")
    check_writable("--out", out.with_name(out.name + ".lock"))
    from ..analyses.sweep import Sweep

    sw = Sweep.make(model.value, pulse=None if recs else pulse.value, records=recs, integrator=_integrator(model, tol),
                    backbone=None if backbone is None else backbone.value, chunk_size=chunk_size, sensitivity=sensitivity, **given)
    dearer = SENSITIVITY_COST if sensitivity else 1.0
    if recs:
        seconds = max(float(r.t_end - r.t_start) for r in recs)
        per_run = record_run_seconds(model.value, seconds) * dearer
        _estimate(sw.size, model.value, yes, what="record runs", per_cell=per_run)
    else:
        kind = "spring-ga" if (model == ModelKind.spring and tol is not None) else model.value
        _estimate(sw.size, kind, yes, what="scenes", per_cell=cell_seconds(kind) * dearer)
    client = None
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:
            raise JaxrockInputError("--scheduler needs Dask's distributed: pip install 'jaxrock[distributed]'") from None
        _probe_scheduler(scheduler)
        try:
            client = guards._held.enter_context(Client(scheduler, timeout="10s", set_as_default=False))  # dask.compute elsewhere stays local
        except Exception as e:  # refused, timed out, or not an address: one answer
            raise JaxrockInputError(f"--scheduler {scheduler}: no Dask scheduler answers there within 10 s "
                                    f"({type(e).__name__}: {e}); expected a running scheduler's address, tcp://HOST:PORT") from None
    from ..analyses.sweep import run_sweep
    from ..interrupt import Interrupted
    from ..io import store as zstore

    ran = 0

    def count(k):  # the scenes this run ran (a resumed store's damaged chunks included)
        nonlocal ran
        ran += sw.chunk_scenes(k)

    t0 = time.perf_counter()
    try:
        ds = run_sweep(sw, out, client=client, devices=devs, progress=not quiet,
                       history=_history(), on_chunk=count)
    except Interrupted:
        kept = len(zstore.flagged(out, sw)) if out.exists() else 0
        typer.echo(f"interrupted: {kept} of {sw.n_chunks} chunks kept in {out}; resume with: {_resume_command()}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    seconds = time.perf_counter() - t0
    dims = " × ".join(f"{len(v)} {k}" for k, v in sw.axes.items())
    where = f"Dask cluster {scheduler}" if scheduler else f"{len(devs)} device(s)"
    before = sw.size - ran
    resumed = f" ({before:,} were in the store already)" if before else ""
    say(f"sweep: {sw.model} model, {dims} = {sw.size:,} scenes in {sw.n_chunks} chunk(s) of ≤ {math.prod(sw.chunk_shape):,}; "
               f"{ran:,} run in {seconds:.1f} s ({ran / seconds:,.0f} scenes/s with compilation) on {where}{resumed}")
    say(f"overturned: {int(ds.overturned.sum()):,} scenes ({100 * float(ds.overturned.mean()):.1f} %); uplifted: "
               f"{int(ds.uplifted.sum()):,}")
    say(uncertain_line(ds.uncertain.values if sensitivity else None, what="scenes"))
    say(f"wrote {out}")
    report("sweep", {"model": sw.model, "axes": {k: np.asarray(v) if k != "record" else list(v) for k, v in sw.axes.items()},
                     "scenes": sw.size, "chunks": sw.n_chunks, "run": ran, "overturned": int(ds.overturned.sum()),
                     "uplifted": int(ds.uplifted.sum()), "uncertain": int(ds.uncertain.sum()) if sensitivity else None,
                     "status": _status_counts(ds.status.values), "seconds": seconds, "files": [out]},
           {"seconds": "s", **{k: u for k, (_, u, _) in sweep_quantities(sw.model if isinstance(sw.model, str) else None).items()
                               if k in sw.axes and u}})
    _exit_if_untrusted(_status_counts(ds.status.values), "scene(s)")


_SCHEDULER = re.compile(r"^(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.-]+):(\d{1,5})$")


def _probe_scheduler(address: str) -> None:
    """`--scheduler`: an address (PROTOCOL://HOST:PORT or HOST:PORT) where something accepts a
    TCP connection within 10 s, checked before a Dask client is made (a client that cannot connect
    hangs in its own cleanup and prints tracebacks after the answer)."""
    import socket

    from .._validate import JaxrockInputError

    m = _SCHEDULER.match(address.strip())
    if m is None or not 0 < int(m.group(3)) < 65536:
        raise JaxrockInputError(f"--scheduler {address!r}: not a scheduler address; expected tcp://HOST:PORT (or HOST:PORT; "
                                "tls://, ws://, ucx:// also), as `dask scheduler` prints it")
    host, port = m.group(2).strip("[]"), int(m.group(3))
    try:
        socket.create_connection((host, port), timeout=10).close()
    except OSError as e:
        raise JaxrockInputError(f"--scheduler {address}: no Dask scheduler answers there within 10 s ({e.strerror or e}); "
                                "expected a running scheduler's address, tcp://HOST:PORT") from None


def _local_devices(n: Optional[int]):
    import jax

    devs = jax.local_devices()
    if n is not None and n > len(devs):
        from .._validate import JaxrockInputError

        raise JaxrockInputError(f"--devices = {n}; valid: 1 to {len(devs)} (this host's devices)")
    return devs if n is None else devs[:n]
