"""What `jaxrock stability` and `jaxrock work-precision` share: the rows of each finished part
(a case, a panel) kept on disk so that an interrupted run resumes, and their files written whole."""

from __future__ import annotations

import json
from pathlib import Path


def write_text(path: Path, text: str) -> None:
    """`text` into `path`, whole or not at all (`jaxrock.io.files.write_atomically`)."""
    from ..io.files import write_atomically

    write_atomically(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


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


def run_parts(parts, run, folder: Path, key: dict, *, name, desc: str, progress: bool) -> list[dict]:
    """The rows of `run(part)` for every part, each part's kept in `folder/<name(part)>.json` with
    `key` (mode and version): a part kept under the same key is read back, not run; a signal stops
    the run after the part in progress (`jaxrock.interrupt.stop_point`), with it kept."""
    from tqdm.auto import tqdm

    from ..interrupt import stop_point

    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for part in tqdm(parts, desc=desc, unit="part", disable=not progress):
        path = folder / f"{name(part)}.json"
        stored = json.loads(path.read_text()) if path.exists() else None
        if stored is not None and stored["key"] == key:
            rows.extend(stored["rows"])
            continue
        new = run(part)
        write_text(path, json.dumps({"key": key, "rows": new}))
        rows.extend(new)
        stop_point()
    return rows
