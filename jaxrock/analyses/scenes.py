"""Running a scenes file (`jaxrock batch scenes.csv --out results.csv`, `run_scenes`): the checked rows
(`jaxrock.io.scenes_file`, which documents both files) grouped by structure, each group stacked and
run by the batch engine (`jaxrock.analyses.engine`) in chunks of `chunk_size` rows padded to a power
of two ≥ 8 (few compiled shapes), the results appended per chunk (an interrupted run keeps its
finished rows; `resume=True` skips them) and rewritten in row order at the end.

A group's rows are chunked in order of their intensity (`Scenes.intensity`: peak |üg| over
g tanα′), not of the file: a vmapped chunk runs as long as its slowest scene, so scenes that stay at
rest, chatter near the uplift level or overturn at once are best run with their like
(benchmarks/bench_rigid.py: the same grid's cells cost 1.7× as much shuffled as in order of a_p)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from .. import interrupt
from .._validate import JaxrockInputError
from ..io import provenance
from ..io.files import exclusive, same_file
from ..io.results_file import append_results, read_done, result_rows, results_path_for, rewrite_results, start_results
from ..io.scenes_file import Scenes, read_scenes
from ..results import OUTPUTS, RESULT_COLUMNS, STATUS_NAMES
from ..outputs import computed
from .engine import run_batch


@dataclass
class BatchReport:
    """What `run_scenes` did."""

    n_rows: int
    n_run: int
    n_skipped: int
    n_groups: int
    seconds: float
    status_counts: dict = field(default_factory=dict)
    flag_counts: dict = field(default_factory=dict)  # each flag of the summary (overturned, uplifted, ...): rows where it is set
    path: Path | None = None


def _chunks(idx: list[int], size: int):
    for lo in range(0, len(idx), size):
        yield idx[lo : lo + size]


_MIN_PAD = 8


def _pad_size(k: int, chunk: int) -> int:
    """Batch shapes: powers of two from 8 up to the chunk size (few compilations)."""
    return min(chunk, max(_MIN_PAD, 1 << max(0, (k - 1).bit_length())))


def _description(scenes: Scenes) -> dict[str, str]:
    """What determines a batch's numbers beyond each row's own inputs (which the results file
    holds): the package version, the integrators (each model's default) and every record's content."""
    d = {"jaxrock": provenance.package_version(), "integrator": "each model's default"}
    for values, rec in zip(scenes.values, scenes.records):
        if rec is not None:
            name = f"record {values.get('pulse', '')}"
            if name not in d:
                d[name] = provenance.value_text(np.concatenate([np.ravel(rec.acc), np.ravel(rec.dt)]))
    return d


def run_scenes(scenes_path, results_path, *, resume: bool = False, chunk_size: int = 256, progress: bool = True,
               force: bool = False, sensitivity: bool = False) -> BatchReport:
    """Run every scene of a scenes file and write the results file.

    All rows are checked first (`read_scenes`). Rows of the same structure are stacked and run by
    the batch engine in chunks of `chunk_size` rows padded to a power of two ≥ 8, in order of their
    intensity (module docstring, `jaxrock.analyses.scenes`). Results are appended per chunk (an
    interrupted run keeps its finished rows) and rewritten in row order at the end. With `resume`,
    rows already in the results file are skipped, once `<results>.made_by.json` shows they were made
    by this package version from the same record contents. An existing file without that
    description beside it is not a results file of a batch run: it is overwritten only with `force`.

    Arguments:
        scenes_path (str | os.PathLike): the scenes CSV file (`read_scenes`).
        results_path (str | os.PathLike): the results CSV file, or a folder (or a path ending with a
            separator) to hold `<scenes stem>_results.csv`.
        resume: skip the rows already in the results file; default False.
        chunk_size: rows per vmapped chunk, an integer ≥ 1; default 256.
        progress: show a progress bar; default True.
        force: overwrite an existing file that is not a batch run's results file; default False.
        sensitivity: every run reports its sensitivity and whether its verdict is uncertain
            (`jaxrock.sensitivity`; else those columns read NaN and 0); default False.

    Returns:
        What was done (`BatchReport`): rows, rows run and skipped, groups, seconds, counts of each
            status and flag, and the results path.

    Raises:
        JaxrockInputError: at a bad row (naming it and its column); when `chunk_size` < 1, the results
            file is the scenes file, a scenes column is named like a result column, an existing file
            is not a batch run's results (without `force`), or on `resume` the results were made
            otherwise (naming the difference).

    Example:
        ```python
        import jaxrock
        report = jaxrock.run_scenes("scenes.csv", "results.csv", resume=True)
        report.status_counts  # e.g. {"ok": 120}
        ```
    """
    if int(chunk_size) < 1:
        raise JaxrockInputError(f"chunk_size = {chunk_size}; valid: an integer >= 1")
    chunk_size = int(chunk_size)
    t0 = time.perf_counter()
    results = results_path_for(scenes_path, results_path)
    if same_file(results, scenes_path):
        raise JaxrockInputError(f"{results}: the results file is the scenes file (the same file by another name); name another")
    scenes = read_scenes(scenes_path)
    header = scenes.header
    clash = [h for h in header if h.lower() in ("row", *RESULT_COLUMNS)]
    if clash:
        raise JaxrockInputError(f"{scenes_path}: line 1: column(s) {clash} are names of result columns; rename them")
    if results.exists() and not force and not results.with_name(results.name + ".made_by.json").is_file():
        raise JaxrockInputError(f"results file {results} exists and is not the results of a batch run (no {results.name}.made_by.json "
                                f"beside it); pass --force to overwrite it, or name another path")
    with exclusive(results, "results file"):
        return _run(scenes, header, results, resume, chunk_size, progress, t0, bool(sensitivity))


def _run(scenes, header, results: Path, resume, chunk_size, progress, t0, sensitivity: bool) -> BatchReport:
    """`run_scenes` on checked scenes, the results file held."""
    made_by = {**_description(scenes), "sensitivity": str(sensitivity)}
    sidecar = results.with_name(results.name + ".made_by.json")
    done = read_done(results, header, scenes) if resume else {}
    if done:
        fresh = "run without --resume to start afresh, or write another results file"
        provenance.check_description(sidecar, made_by, f"{results}", fresh)
    fields = ["row", *header, *RESULT_COLUMNS]

    todo = {key: idx[~np.isin(scenes.rows[idx], list(done))] for key, idx in scenes.groups.items()}
    # a chunk runs as long as its slowest scene: chunks of like intensity (module docstring)
    todo = {key: idx[np.argsort(scenes.intensity(idx), kind="stable")] for key, idx in todo.items() if idx.size}
    n_todo = sum(idx.size for idx in todo.values())

    if not (resume and results.exists() and done):
        start_results(results, fields)
        provenance.write_description(sidecar, made_by)
    bar = tqdm(total=len(scenes), initial=len(scenes) - n_todo, unit="scene", desc="batch", disable=not progress)
    new: dict[int, dict] = {}
    for (kind, exc), idx in todo.items():
        for part in _chunks(list(idx), chunk_size):
            interrupt.stop_point()
            index = np.asarray(part + [part[0]] * (_pad_size(len(part), chunk_size) - len(part)))
            sol = run_batch(scenes.model(kind, index), scenes.excitation(exc, index), model_batched=True, sensitivity=sensitivity)
            records = [{"row": str(int(scenes.rows[i])), **scenes.values[i], **res} for i, res in zip(part, result_rows(sol, len(part)))]
            append_results(results, fields, records)
            new.update({int(rec["row"]): rec for rec in records})
            bar.update(len(part))
    bar.close()

    # all done: rewrite in row order (atomically)
    allrows = {**done, **new}
    rewrite_results(results, fields, allrows)

    statuses = [allrows[r]["status"] for r in allrows]
    counts = {name: statuses.count(name) for name in STATUS_NAMES if statuses.count(name)}
    return BatchReport(
        n_rows=len(scenes),
        n_run=n_todo,
        n_skipped=len(scenes) - n_todo,
        n_groups=len(todo),
        seconds=time.perf_counter() - t0,
        status_counts=counts,
        flag_counts={name: sum(int(allrows[r][name]) for r in allrows) for name, o in OUTPUTS.items()
                     if o.kind == "bool" and computed(o, {o.needs: [float(allrows[r][o.needs]) for r in allrows]} if o.needs else {})},
        path=results,
    )


__all__ = ["run_scenes", "BatchReport"]
