"""Tables as CSV files: one row per dict, numbers written exactly (`repr`: a float read back is the
float written; `inf` for infinities), an optional `# ` footer line; written atomically."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from .files import write_atomically


def cell(x) -> str:
    """A CSV cell: floats exactly (`repr`), infinities as `inf`/`-inf`, anything else as `str`."""
    if isinstance(x, float):
        return ("inf" if x > 0 else "-inf") if math.isinf(x) else repr(x)
    return str(x)


def write_table(path, rows: list[dict], *, footer: str | None = None) -> Path:
    """Write `rows` (dicts with the same keys, in order) to the CSV file `path`, atomically."""

    def write(tmp):
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]), lineterminator="\n")
            w.writeheader()
            w.writerows({k: cell(v) for k, v in r.items()} for r in rows)
            if footer is not None:
                fh.write(f"# {footer}\n")

    return write_atomically(Path(path), write)
