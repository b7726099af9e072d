"""The results file of a batch run (format: `jaxrock.io.scenes_file`): each finished row (its row
number, the scene's input cells as given, then the result columns), appended and flushed per chunk,
read back and checked for a resumed run, and rewritten in row order at the end."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from .._validate import JaxrockInputError
from ..results import OUTPUTS, RESULT_COLUMNS, STATUS_NAMES, status_codes
from .files import output_stem, write_atomically
from .scenes_file import Scenes
from .tables import cell, csv_text


def result_rows(sol, k: int) -> list[dict]:
    """The result cells (`RESULT_COLUMNS`) of the first `k` lanes of a batch's `Solution`."""
    col = {name: np.asarray(getattr(sol, name))[:k] for name in OUTPUTS}
    status = np.asarray(status_codes(sol.status))[:k]
    return [
        {**{name: cell(o.csv_value(col[name][i])) for name, o in OUTPUTS.items()}, "status": STATUS_NAMES[int(status[i])]}
        for i in range(k)
    ]


def read_done(results: Path, header: list[str], scenes: Scenes) -> dict[int, dict]:
    """Finished rows of an earlier run (row number → result row), checked against the scenes."""
    done: dict[int, dict] = {}
    if not results.exists():
        return done
    with csv_text(results, "results") as fh:
        reader = csv.DictReader(fh)
        expected = ["row", *header, *RESULT_COLUMNS]
        if reader.fieldnames is None:
            return done
        if list(reader.fieldnames) != expected:
            raise JaxrockInputError(
                f"{results}: its columns {reader.fieldnames} do not match this scenes file "
                f"(expected {expected}); use another results file or run without --resume"
            )
        by_row = {int(r): v for r, v in zip(scenes.rows, scenes.values)}
        for rec in reader:
            try:
                r = int(rec["row"])
            except (TypeError, ValueError):
                continue  # a partly written last line of an interrupted run
            if r not in by_row or any(rec.get(c) in (None, "") for c in ("status", "max_theta")):
                continue
            if any(rec[h] != by_row[r][h] for h in header):
                raise JaxrockInputError(
                    f"{results}: row {r} was computed for other inputs than row {r} of the scenes file; "
                    f"use another results file or run without --resume"
                )
            done[r] = rec
    return done


def count_results(results) -> int:
    """Finished rows in a results file (0 when it is missing or unreadable)."""
    try:
        with csv_text(Path(results), "results") as fh:
            return sum(1 for rec in csv.DictReader(fh) if rec.get("status") in STATUS_NAMES)
    except (OSError, JaxrockInputError):
        return 0


def results_path_for(scenes_path, results_path) -> Path:
    """The results file: `results_path`, or inside it when it is a folder (or ends with a
    separator) as `<scenes stem>_results.csv`."""
    return output_stem(results_path, f"{Path(scenes_path).stem}_results.csv")


def start_results(results: Path, fields: list[str]) -> None:
    """A fresh results file: its header line."""
    results.parent.mkdir(parents=True, exist_ok=True)
    with open(results, "w", newline="", encoding="utf-8") as fh:
        csv.DictWriter(fh, fieldnames=fields).writeheader()


def append_results(results: Path, fields: list[str], records: list[dict]) -> None:
    """Append finished rows, flushed to disk (an interrupted run keeps them)."""
    with open(results, "a", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writerows(records)
        fh.flush()
        os.fsync(fh.fileno())


def rewrite_results(results: Path, fields: list[str], rows: dict[int, dict]) -> None:
    """The finished file: every row in row order, written atomically."""

    def write(tmp):
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=fields)
            w.writeheader()
            for r in sorted(rows):
                w.writerow({k: rows[r][k] for k in fields})

    write_atomically(results, write)


__all__ = ["result_rows", "read_done", "count_results", "results_path_for", "start_results", "append_results", "rewrite_results"]
