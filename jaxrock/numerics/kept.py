"""What `jaxrock stability` and `jaxrock work-precision` share: the rows of each finished part
(a case, a panel) kept on disk so that an interrupted run resumes, and their files written whole."""

from __future__ import annotations

import json
from pathlib import Path


def write_text(path: Path, text: str) -> None:
    """`text` into `path`, whole or not at all, never over a file jaxrock did not write
    (`jaxrock.io.files.write_output`)."""
    from ..io.files import text_head, write_output

    write_output(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"), text_head(text))


def write_csv(path: Path, columns: tuple[str, ...], rows: list[dict]) -> None:
    """`rows` as CSV: floats exactly (repr), flags 0/1, text quoted where it holds a comma."""

    def cell(x) -> str:
        if isinstance(x, bool):
            return str(int(x))
        if isinstance(x, float):
            return repr(x)
        s = str(x)
        return f'"{s}"' if "," in s else s

    write_text(path, "\n".join([",".join(columns)] + [",".join(cell(r[c]) for c in columns) for r in rows]) + "\n")


def read_kept(path: Path, check) -> object | None:
    """`check(data)` of the JSON object kept in `path`; None where the file is missing, truncated,
    not an object, or `check` finds a key missing or of another type (the part is then run
    again, never taken as done)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return check(data) if isinstance(data, dict) else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def _rows(stored: dict, key: dict, columns: tuple[str, ...]) -> list[dict] | None:
    rows = stored["rows"]
    if stored["key"] != key or not isinstance(rows, list) or not all(isinstance(r, dict) and set(columns) <= set(r) for r in rows):
        return None
    return rows


def run_parts(parts, run, folder: Path, key: dict, *, name, desc: str, progress: bool, columns: tuple[str, ...]) -> list[dict]:
    """The rows of `run(part)` (each with every one of `columns`) for every part, each part's kept
    in `folder/<name(part)>.json` with `key` (mode and version): a part kept under the same key is
    read back, not run (a damaged file is run again: `read_kept`); a signal stops the run after the
    part in progress (`jaxrock.interrupt.stop_point`), with it kept."""
    import jax
    from tqdm.auto import tqdm

    from ..interrupt import stop_point
    from ..io.files import write_atomically  # a part's rows: kept in the run's own folder, read back only by it

    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for part in tqdm(parts, desc=desc, unit="part", disable=not progress):
        path = folder / f"{name(part)}.json"
        kept = read_kept(path, lambda stored: _rows(stored, key, columns))
        if kept is not None:
            rows.extend(kept)
            continue
        new = run(part)
        # free the part's compiled programs: kept in one process, every one adds memory maps, and
        # the full `jaxrock work-precision` ended its sixth panel in 'LLVM compilation error: Cannot
        # allocate memory' (vm.max_map_count 65530), as `jaxrock reproduce` had (`jaxrock.paper.reproduce`)
        jax.clear_caches()
        write_atomically(path, lambda tmp: Path(tmp).write_text(json.dumps({"key": key, "rows": new}), encoding="utf-8"))
        rows.extend(new)
        stop_point()
    return rows
