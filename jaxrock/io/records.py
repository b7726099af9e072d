"""Reading ground-motion records from files into `Record` excitations (accelerations in m/s²).

Two formats are read:

* PEER NGA `.AT2`: header lines (in the classic layout four: the second names the event, the
  third states the units, the fourth gives `NPTS=` and `DT=` [s]; the rotated components of the
  NGA data carry six or more, with "7997 0.0050 NPTS, DT" last), then the accelerations in rows of
  any length.
* Two-column text: `time [s]  acceleration` per line, separated by whitespace or a comma, `#`
  starting a comment; accelerations in g unless `units` says otherwise.

Malformed files raise `JaxrockInputError` naming the file, the line and what is valid.
"""

from __future__ import annotations

import os
import re
from importlib import resources
from pathlib import Path

import numpy as np

from .._validate import JaxrockInputError, is_number
from ..excitation import Record
from ..geometry import G
from ..scene import builtin_record_names

_UNITS = {"g": G, "m/s2": 1.0, "cm/s2": 0.01, "mm/s2": 1e-3, "in/s2": 0.0254, "ft/s2": 0.3048}  # factor to m/s²
_UNITS_VALID = "g, m/s2, cm/s2 (gal), mm/s2, in/s2, ft/s2 (also written m/s/s, m/sec^2, m/s²)"
# a header's statement of units: 'IN UNITS OF G.', 'UNITS OF CM/S/S', 'The units are (g)'
_HEADER_UNITS = re.compile(r"\bUNITS\b\s*(?:OF|ARE|:|=)?\s*\(?\s*([A-Za-z][A-Za-z/0-9*^²]*)", re.IGNORECASE)
# 'Acceleration in g', 'ACCELERATION IN CM/S/S' (the NGA rotated components' header)
_HEADER_IN = re.compile(r"\bACCELERATION\b.*?\bIN\s+\(?\s*([A-Za-z][A-Za-z/0-9*^²]*)", re.IGNORECASE)
_HEADER_LINES = 4  # the classic layout: NPTS and DT on the fourth line
_MAX_HEADER_LINES = 12  # NPTS and DT are looked for on the lines up to this one
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?"
_NPTS = re.compile(r"\bNPTS\s*=\s*([-+]?\d+)\b", re.IGNORECASE)
_DT = re.compile(rf"\bDT\s*=\s*({_NUMBER})", re.IGNORECASE)
# values first, then their labels in either order: '7997 0.0050 NPTS, DT', '0.005 7997 DT, NPTS'
_LABELLED_AFTER = re.compile(rf"^\s*({_NUMBER})[\s,]+({_NUMBER})[\s,]+(NPTS|DT)\s*[,;]?\s*(NPTS|DT)\b", re.IGNORECASE)
_UNIFORM_RTOL = 1e-6


def _unit_key(units: str) -> str | None:
    """The canonical name of an acceleration unit as written ('CM/SEC/SEC' → 'cm/s2'), or None."""
    u = units.strip().lower().replace(" ", "").replace("²", "2").replace("**2", "2").replace("^2", "2")
    u = u.replace("sec", "s").replace("/s/s", "/s2")
    u = {"gal": "cm/s2", "gals": "cm/s2"}.get(u, u)
    return u if u in _UNITS else None


def unit_factor(units: str, source="units") -> float:
    """Factor from `units` (see `_UNITS_VALID`) to m/s²; a unit it cannot interpret is refused."""
    key = _unit_key(units)
    if key is None:
        raise JaxrockInputError(f"units = {units!r} (for {source}); valid units are {_UNITS_VALID}")
    return _UNITS[key]


def _split_lines(text: str) -> list[str]:
    """Lines split on newlines only (so '\\r\\r\\n' endings count as one line), right-stripped."""
    return [line.rstrip() for line in text.split("\n")]


def _read_lines(path: Path) -> list[str]:
    path = Path(path)
    if path.is_dir():
        raise JaxrockInputError(f"{path}: is a folder; read_record reads one record file (read_records reads a folder's records)")
    if not path.exists():
        raise JaxrockInputError(f"{path}: no such file")
    if not path.is_file():
        raise JaxrockInputError(f"{path}: is not a regular file (a FIFO, a device or a socket); expected a record file")
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise JaxrockInputError(f"{path}: cannot be read ({e.strerror or e})") from None
    if raw[:2] == b"\x1f\x8b":
        raise JaxrockInputError(f"{path}: the file is gzip-compressed; decompress it first (gunzip) to a text record")
    if b"\x00" in raw[:65536]:
        raise JaxrockInputError(f"{path}: the file is binary (NUL bytes); expected a text record (.AT2 or two-column)")
    # a spreadsheet's byte-order mark is not data; other undecodable bytes are shown as U+FFFD
    lines = _split_lines(raw.decode("utf-8-sig", errors="replace"))
    if not any(lines):
        raise JaxrockInputError(f"{path}: the file is empty; expected a ground-motion record (.AT2 or two-column text)")
    return lines


def _parse_row(line: str, lineno: int, source) -> np.ndarray:
    """The numbers on one line (separated by whitespace or commas), all finite."""
    tokens = line.replace(",", " ").split()
    try:
        row = np.array(tokens, dtype=float)
    except ValueError:
        bad = next(t for t in tokens if not is_number(t))
        raise JaxrockInputError(
            f"{source}: line {lineno}: non-numeric token {bad!r}; expected numbers such as -0.0064 or -.6403182E-02"
        ) from None
    if not np.all(np.isfinite(row)):
        bad = tokens[int(np.flatnonzero(~np.isfinite(row))[0])]
        raise JaxrockInputError(
            f"{source}: line {lineno}: non-finite value {bad!r}; every value must be a finite number"
        )
    return row


def _numeric_rows(lines: list[str], first_lineno: int, source, comment: str | None = None):
    """(line numbers, values per line, all values in order) of the non-blank lines; text after
    `comment` is ignored. Parsed in one vectorised pass (10⁶ lines in about a second); a line with
    a bad token is then found and named by `_parse_row`."""
    if comment is not None:
        lines = [line.split(comment, 1)[0] for line in lines]
    kept = [(lineno, line) for lineno, line in enumerate(lines, start=first_lineno) if line.strip()]
    tokens = [line.replace(",", " ").split() for _, line in kept]
    counts = np.fromiter(map(len, tokens), dtype=int, count=len(tokens))
    try:
        values = np.array([t for row in tokens for t in row], dtype=float)
        if np.all(np.isfinite(values)):
            return [lineno for lineno, _ in kept], counts, values
    except ValueError:
        pass
    for lineno, line in kept:  # name the first bad line
        _parse_row(line, lineno, source)
    raise AssertionError("unreachable: a bad token was not found line by line")  # pragma: no cover


def _at2_npts_dt(line: str, lineno: int, source) -> tuple[int, float] | None:
    """NPTS and DT [s] from one header line, or None where the line gives no NPTS. Spellings:
    `NPTS=  4000, DT= .01000 SEC`, `NPTS= 4000 DT= 0.01`, `DT= 0.01 NPTS= 4000` (any case), and the
    values before their labels, `7997 0.0050 NPTS, DT` (either order). A line with NPTS but no
    DT, or two different NPTS, is refused."""
    after = _LABELLED_AFTER.match(line)
    if after is not None and {after.group(3).upper(), after.group(4).upper()} == {"NPTS", "DT"}:
        first, second = after.group(1), after.group(2)
        npts_text, dt_text = (first, second) if after.group(3).upper() == "NPTS" else (second, first)
    else:
        found = {m.group(1) for m in _NPTS.finditer(line)}
        if not found:
            return None
        dts = {m.group(1) for m in _DT.finditer(line)}
        if len(found) > 1 or len(dts) != 1:
            what = f"NPTS = {' and '.join(sorted(found))}" if len(found) > 1 else ("no numeric DT=" if not dts else "two DT=")
            raise JaxrockInputError(f"{source}: line {lineno}: {what} in {line.strip()[:60]!r}; "
                                    f"expected one of each, e.g. 'NPTS=  4000, DT= .01000 SEC' or '4000 0.0100 NPTS, DT'")
        npts_text, dt_text = found.pop(), dts.pop()
    try:
        npts = int(npts_text)
    except ValueError:
        raise JaxrockInputError(f"{source}: line {lineno}: NPTS = {npts_text}; the number of samples must be an integer") from None
    dt = float(dt_text)
    if npts < 2:
        raise JaxrockInputError(f"{source}: line {lineno}: NPTS = {npts}; a record needs NPTS >= 2 samples")
    if dt <= 0:
        raise JaxrockInputError(f"{source}: line {lineno}: DT = {dt:g} s; the time step must be > 0")
    return npts, dt


def _at2_header(lines: list[str], source) -> tuple[int, int, float]:
    """(header lines, NPTS, DT): the first line giving NPTS and DT ends the header."""
    for k, line in enumerate(lines[:_MAX_HEADER_LINES]):
        got = _at2_npts_dt(line, k + 1, source)
        if got is not None:
            return k + 1, *got
    raise JaxrockInputError(
        f"{source}: no NPTS and DT in the first {min(len(lines), _MAX_HEADER_LINES)} line(s); an .AT2 file's header ends with "
        f"a line giving both, e.g. 'NPTS=  4000, DT= .01000 SEC' or '4000 0.0100 NPTS, DT', followed by the values"
    )


def _at2_units(header: list[str], units: str | None, source) -> float:
    """Factor to m/s² of an .AT2 file: the units its header lines (before NPTS) state ('IN UNITS
    OF G', 'UNITS OF CM/S/S', 'The units are (g)', 'Acceleration in g'), else `units`, else g (the
    PEER convention). A stated unit it cannot interpret, or one that contradicts `units`, is refused."""
    for lineno, line in enumerate(header, start=1):
        match = _HEADER_UNITS.search(line)
        if match is None:
            match = _HEADER_IN.search(line)
            if match is None or _unit_key(match.group(1)) is None:  # 'in' before a word that is no unit says nothing
                continue
        stated = match.group(1)
        key = _unit_key(stated)
        if key is None:
            raise JaxrockInputError(
                f"{source}: line {lineno}: the header states units {stated!r}, which jaxrock cannot interpret; "
                f"valid units are {_UNITS_VALID}"
            )
        if units is not None and _unit_key(units) != key:
            raise JaxrockInputError(f"{source}: line {lineno}: the header states units {stated!r}, but units = {units!r} was given")
        return _UNITS[key]
    return G if units is None else unit_factor(units, source)


def read_at2(path: str | os.PathLike, *, units: str | None = None, name: str | None = None) -> Record:
    """Read a PEER NGA `.AT2` acceleration file into a `Record` in m/s².

    The header ends with the line that gives the number of samples and the time step [s] — the
    fourth in the classic layout (the second names the event; the third states the units, as in
    `ACCELERATION TIME HISTORY IN UNITS OF G` or `UNITS OF CM/S/S`), the seventh in the rotated
    components of the NGA data ("Orig PEER filename = …", rotation lines, "Acceleration in g") —
    found on any of the first 12 lines, spelt `NPTS=  4000, DT= .01000 SEC`, `NPTS= 4000 DT= 0.01`,
    `DT= 0.01, NPTS= 4000` or `7997 0.0050 NPTS, DT`. Then exactly NPTS accelerations, any number
    per row, in free or Fortran format (`.6403182E-02`, `0.00630`). Units are read from the header;
    `units` is used where the header states none and must agree where it does.

    Arguments:
        path: the `.AT2` file.
        units: the acceleration unit where the header states none (g, m/s2, cm/s2 (gal), mm/s2,
            in/s2, ft/s2, also written m/s/s, m/sec^2, m/s²); default None: g there, the header's elsewhere.
        name: the record's name; default None: the event line of the classic layout, else the file's stem.

    Returns:
        The record (`Record`), accelerations in m/s².

    Raises:
        JaxrockInputError: when the file is missing, unreadable, binary or empty, its header gives no
            valid NPTS (≥ 2) and DT (> 0), it holds other than NPTS values, a value is not a finite
            number, or `units` is unknown or disagrees with the header.

    Example:
        ```python
        import jaxrock
        record = jaxrock.read_at2("RSN6_IMPVALL.I_I-ELC180.AT2")
        record.dt  # the file's DT [s]
        ```
    """
    source = Path(path)
    lines = _read_lines(source)
    n_header, npts, dt = _at2_header(lines, source)
    _, _, values = _numeric_rows(lines[n_header:], n_header + 1, source)
    if values.size != npts:
        fewer_more = "fewer" if values.size < npts else "more"
        raise JaxrockInputError(
            f"{source}: {values.size} values after the header, {fewer_more} than NPTS = {npts} "
            f"(line {n_header}); the file must hold exactly NPTS values"
        )
    factor = _at2_units(lines[: n_header - 1], units, source)
    event = lines[1].strip() if n_header == _HEADER_LINES else ""  # the classic layout's event line
    return Record(values * factor, dt, name=name or event or source.stem)


def _uniform_step(times: np.ndarray, linenos: list[int], source) -> float:
    """The mean time step [s] of a strictly increasing time column whose steps all lie within 1e-6
    (relative) of their median."""
    steps = np.diff(times)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise JaxrockInputError(
            f"{source}: line {linenos[k + 1]}: time {times[k + 1]:g} s does not exceed the previous "
            f"{times[k]:g} s; time must be strictly increasing"
        )
    typical = np.median(steps)
    off = np.abs(steps - typical) > _UNIFORM_RTOL * typical
    if np.any(off):
        k = int(np.flatnonzero(off)[0])
        raise JaxrockInputError(
            f"{source}: line {linenos[k + 1]}: time step {steps[k]:g} s differs from the median step "
            f"{typical:g} s; time must be uniform (relative tolerance {_UNIFORM_RTOL:g})"
        )
    return float((times[-1] - times[0]) / (times.size - 1))


def _parse_two_column(lines: list[str], source, units: str, name: str) -> Record:
    factor = unit_factor(units, source)
    linenos, counts, values = _numeric_rows(lines, 1, source, comment="#")
    if np.any(counts != 2):
        k = int(np.flatnonzero(counts != 2)[0])
        raise JaxrockInputError(
            f"{source}: line {linenos[k]}: {counts[k]} value(s); expected two columns, time [s] and acceleration"
        )
    if len(linenos) < 2:
        raise JaxrockInputError(
            f"{source}: {len(linenos)} data line(s); a record needs at least 2 'time acceleration' lines"
        )
    data = values.reshape(-1, 2)
    dt = _uniform_step(data[:, 0], linenos, source)
    return Record(data[:, 1] * factor, dt, name=name)


def read_two_column(path: str | os.PathLike, *, units: str = "g", name: str | None = None) -> Record:
    """Read a two-column text record, `time [s]  acceleration` per line, into a `Record` in m/s².

    Columns are separated by whitespace or a comma; `#` starts a comment (whole line or trailing);
    blank lines are skipped. `units` is the acceleration unit (default g; also m/s2, cm/s2, mm/s2,
    in/s2, ft/s2): the file cannot say it, so give it when it is not g. Time must be
    strictly increasing and uniform (every step within 1e-6 relative of the median step; the
    record's `dt` is the mean step). Time may start anywhere: the record is shifted so that its first sample
    is at t = 0.

    Arguments:
        path: the text file.
        units: the acceleration unit: g, m/s2, cm/s2 (gal), mm/s2, in/s2 or ft/s2 (also written m/s/s,
            m/sec^2, m/s²); default "g".
        name: the record's name; default None: the file's stem.

    Returns:
        The record (`Record`), accelerations in m/s², first sample at t = 0.

    Raises:
        JaxrockInputError: when the file is missing, unreadable, binary or empty, a line does not hold
            two finite numbers, time is not strictly increasing and uniform, or `units` is unknown.

    Example:
        ```python
        import jaxrock
        record = jaxrock.read_two_column("station.txt", units="cm/s2", name="station")
        ```
    """
    source = Path(path)
    return _parse_two_column(_read_lines(source), source, units, name or source.stem)


def read_record(path: str | os.PathLike, **kw) -> Record:
    """Read a record file: `.AT2` (any case) with `read_at2`, anything else with `read_two_column`.

    Arguments:
        path: the record file.
        **kw (str): keyword arguments of the chosen reader: `name`; `units` (for two-column files the unit,
            default g; for .AT2 files the unit where the header states none, checked where it does).

    Returns:
        The record (`Record`), accelerations in m/s².

    Raises:
        JaxrockInputError: as the chosen reader raises it (a missing or malformed file, an unknown unit).

    Example:
        ```python
        import jaxrock
        record = jaxrock.read_record("IELC180.AT2")
        ```
    """
    reader = read_at2 if Path(path).suffix.lower() == ".at2" else read_two_column
    return reader(path, **kw)


def read_record_pair(horizontal: str | os.PathLike, vertical: str | os.PathLike, *, units=None, name: str | None = None) -> Record:
    """Read a horizontal/vertical pair of one event from two files into one `Record` (its `vertical`).

    Each file is read by `read_record` with its own units; the shorter component is padded with
    zeros to the longer's length (the pair ends with the longer one).

    Arguments:
        horizontal: the horizontal component's file.
        vertical: the vertical component's file (upwards positive).
        units (str | tuple[str, str] | None): the unit of both files, or (horizontal's, vertical's),
            as `read_record` takes it; default None: each reader's default.
        name: the pair's name; default None: the horizontal file's stem.

    Returns:
        The pair (`Record` with `vertical`), accelerations in m/s².

    Raises:
        JaxrockInputError: as `read_record` raises it, when the two sample steps differ (relative
            1e-6), or the vertical peak is not below g.

    Example:
        ```python
        import jaxrock
        pair = jaxrock.read_record_pair("RSN1063_NS.AT2", "RSN1063_UP.AT2")
        ```
    """
    hu, vu = units if isinstance(units, (tuple, list)) else (units, units)
    h = read_record(horizontal, **({} if hu is None else {"units": hu}))
    v = read_record(vertical, **({} if vu is None else {"units": vu}))
    if not np.isclose(float(h.dt), float(v.dt), rtol=_UNIFORM_RTOL, atol=0.0):
        raise JaxrockInputError(f"record pair {horizontal} + {vertical}: horizontal dt = {float(h.dt):g} s, vertical dt = "
                                f"{float(v.dt):g} s; valid: one sample step (resample one of them)")
    n = max(h.n, v.n)
    pad = lambda r: np.pad(np.asarray(r.acc), (0, n - r.n))
    return Record(pad(h), h.dt, name=name or Path(horizontal).stem, vertical=pad(v))


RECORD_SUFFIXES = (".at2", ".txt", ".dat", ".csv")  # the files of a record folder (`read_records`)
LIST_SUFFIX = ".list"  # a suite's list file (`read_records`)


def _builtin(entry: str, base: Path) -> bool:
    """Whether a suite's source names packaged records (one of them, or `BUILTIN_SUITE`): a file or
    folder of that name, relative to `base`, is read instead."""
    from ..scene import BUILTIN_SUITE, is_builtin_record

    return (is_builtin_record(entry) or entry.strip().lower() == BUILTIN_SUITE) and not (base / entry).exists()


def _list_entries(path: Path) -> list[str | tuple[str, str]]:
    """The sources a list file names: one per line (a record file, a folder or a packaged record's
    name; relative paths from the list file's folder), blank lines and `#` comments skipped. A line
    of two record files separated by ` + ` is a horizontal/vertical pair (`read_record_pair`)."""
    entries = []
    for lineno, line in enumerate(_read_lines(path), start=1):
        entry = line.split("#", 1)[0].strip()
        if not entry:
            continue
        if " + " in entry and not (path.parent / entry).exists():
            pair = tuple(part.strip() for part in entry.split(" + "))
            missing = [part for part in pair if not (path.parent / part).is_file()]
            if len(pair) != 2 or missing:
                raise JaxrockInputError(f"{path}: line {lineno}: {entry}: a pair is two record files, 'HORIZONTAL + VERTICAL' "
                                        f"(relative to {path.parent}){f'; no such file: {missing[0]}' if missing else ''}")
            entries.append(tuple(str(path.parent / part) for part in pair))
            continue
        builtin = _builtin(entry, path.parent)
        if not builtin and not (path.parent / entry).exists():
            raise JaxrockInputError(f"{path}: line {lineno}: {entry}: no such file or folder (relative to {path.parent}) "
                                    "nor a packaged record")
        entries.append(entry if builtin else str(path.parent / entry))
    if not entries:
        raise JaxrockInputError(f"{path}: the list names no record; expected one record file, folder or packaged record per line")
    return entries


def read_records(sources, *, units: str | None = None, _lists: tuple[str, ...] = ()) -> list[Record]:
    """The records of a suite, read from files, folders, list files or packaged records.

    Each source is a record file, a folder (its files ending in one of `RECORD_SUFFIXES`, .at2,
    .txt, .dat, .csv, any case, sorted by name), a list file (`*.list`: one such source per line,
    relative to the list's folder, `#` comments; a line `H.AT2 + V.AT2` is a horizontal/vertical pair,
    `read_record_pair`), a packaged record's name (`builtin_record`) or
    `builtin`, all five packaged records (El Centro first); a file or folder of such a name in the
    working directory is read instead. Files are read by `read_record` and named by their file stem
    (unique within a folder).

    Arguments:
        sources (str | os.PathLike | Sequence[str | os.PathLike]): one source or a sequence of them.
        units: the acceleration unit, as `read_record` takes it; default None: each reader's default.

    Returns:
        The records (`Record`), in the order of the sources.

    Raises:
        JaxrockInputError: when a folder holds no record file, a source is neither a file, a folder
            nor a packaged record, two records share a name, a list names itself (directly or through
            other lists) or names nothing, or a file is malformed.

    Example:
        ```python
        import jaxrock
        suite = jaxrock.read_records(["builtin", "my_records/"], units="g")
        ```
    """
    from ..scene import BUILTIN_SUITE, PACKAGED_RECORDS, RECORD_ALIASES

    out: list[Record] = []
    for src in [sources] if isinstance(sources, (str, os.PathLike)) else list(sources):
        if isinstance(src, tuple):  # a pair from a list file
            out.append(read_record_pair(*src, units=units))
            continue
        if _builtin(str(src), Path(".")):
            suite = str(src).strip().lower() == BUILTIN_SUITE
            out += [builtin_record(n) for n in (RECORD_ALIASES[0], *PACKAGED_RECORDS)] if suite else [builtin_record(str(src))]
            continue
        path = Path(src)
        if path.is_file() and path.suffix.lower() == LIST_SUFFIX:
            here = os.path.realpath(path)
            if here in _lists:
                chain = " → ".join(map(str, (*_lists[_lists.index(here):], here)))
                raise JaxrockInputError(f"records: the list {path} names itself ({chain}); a list may name only records, folders and other lists")
            out += read_records(_list_entries(path), units=units, _lists=(*_lists, here))
            continue
        if path.is_dir():
            files = sorted(f for f in path.iterdir() if f.is_file() and f.suffix.lower() in RECORD_SUFFIXES)
            if not files:
                raise JaxrockInputError(f"records: {path} holds no record file (names ending in {', '.join(RECORD_SUFFIXES)})")
        elif path.is_file():
            files = [path]
        else:
            raise JaxrockInputError(f"records: {path}: no such file or folder, nor a packaged record ({BUILTIN_SUITE} or one of "
                                    f"{builtin_record_names()})")
        out += [read_record(f, name=f.stem, **({} if units is None else {"units": units})) for f in files]
    names = [r.name for r in out]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise JaxrockInputError(f"records: two records named {twice[0]!r}; rename one file")
    return out


def builtin_record(name: str, *, label: str | None = None) -> Record:
    """A packaged record by name, any case.

    The packaged records (`jaxrock/data/README.md`: sources and attribution): `elcentro`
    (El Centro 1940 NS, `el_centro`), `elcentro_peknold`, `arl360`, `b-elc000`, `a-tin000`.

    Arguments:
        name: the packaged record's name, any case.
        label: the record's name; default None: its file stem.

    Returns:
        The record (`Record`), accelerations in m/s².

    Raises:
        JaxrockInputError: when `name` is not a packaged record.

    Example:
        ```python
        import jaxrock
        record = jaxrock.builtin_record("arl360")
        ```
    """
    from ..scene import PACKAGED_RECORDS, RECORD_ALIASES

    key = name.strip().lower()
    if key in RECORD_ALIASES:
        return el_centro()
    if key not in PACKAGED_RECORDS:
        raise JaxrockInputError(f"record {name!r} is not a packaged record; valid: {builtin_record_names()}")
    file = PACKAGED_RECORDS[key]
    with resources.as_file(resources.files("jaxrock") / "data" / "records" / file) as path:
        return read_at2(path, name=label or Path(file).stem)


def el_centro() -> Record:
    """El Centro 1940 NS ground acceleration (4000 samples at 0.01 s, PGA 0.3129 g), in m/s².

    Imperial Valley earthquake of 19 May 1940, El Centro Array #9 (USGS station 117), component
    180, as shipped in `jaxrock/data/elcentro_ns_1940.txt` (the same values as
    `jaxrock/data/IELC180.AT2`). Source: the OpenSees repository (github.com/OpenSees/OpenSees),
    file `Workshops/OpenSeesDays/IELC180.AT2`, a PEER Strong Motion Database record (processing
    by Pacific Engineering, band-pass HP = 0.2 Hz, LP = 15 Hz). The record itself is public data
    of the US Geological Survey's strong-motion program, as processed for the PEER database.

    Returns:
        The record (`Record`), named "El Centro 1940 NS".

    Example:
        ```python
        import jaxrock
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        sol = jaxrock.simulate(jaxrock.RigidModel(block), jaxrock.el_centro())
        ```
    """
    resource = resources.files("jaxrock") / "data" / "elcentro_ns_1940.txt"
    lines = _split_lines(resource.read_text(encoding="utf-8"))
    return _parse_two_column(lines, "jaxrock/data/elcentro_ns_1940.txt", "g", "El Centro 1940 NS")
