"""Tables as CSV files: one row per dict, numbers written exactly (`repr`: a float read back is the
float written; `inf` for infinities), an optional `# ` footer line; written atomically. Read back as
checked UTF-8 text (`csv_text`)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from .._validate import JaxrockInputError
from .files import text_head, write_output


def cell(x) -> str:
    """A CSV cell: floats exactly (`repr`), infinities as `inf`/`-inf`, anything else as `str`."""
    if isinstance(x, float):
        return ("inf" if x > 0 else "-inf") if math.isinf(x) else repr(x)
    return str(x)


def write_table(path, rows: list[dict], *, footer: str | None = None, columns: list[str] | None = None) -> Path:
    """Write `rows` (dicts with the same keys, in order) to the CSV file `path`, atomically; `columns`
    names them where there may be no row (default: the first row's keys)."""

    fields = list(rows[0]) if columns is None else list(columns)
    header = ",".join(fields)

    def write(tmp):
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=fields, lineterminator="\n")
            w.writeheader()
            w.writerows({k: cell(v) for k, v in r.items()} for r in rows)
            if footer is not None:
                fh.write(f"# {footer}\n")

    return write_output(Path(path), write, text_head(header))


def csv_text(path: Path, what: str) -> io.StringIO:
    """A CSV file's text, for `csv` (newline=""): a file that is not UTF-8 text is refused in one line."""
    try:
        text = Path(path).read_bytes().decode("utf-8-sig")  # a spreadsheet's byte-order mark is not part of the header
    except UnicodeDecodeError as e:
        raise JaxrockInputError(f"{path}: the {what} file is not UTF-8 text (byte {e.start}: {e.reason}); expected a CSV") from None
    if "\x00" in text:
        raise JaxrockInputError(f"{path}: the {what} file is binary (NUL bytes); expected a CSV")
    return io.StringIO(text, newline="")
