"""Record readers (PEER .AT2, two-column text, packaged El Centro) and the sampled `Record`."""

import os
from pathlib import Path

import jax
import numpy as np
import pytest

from helpers import invoke

from jaxrock import G, JaxrockInputError
from jaxrock.io.records import builtin_record, el_centro, read_at2, read_record, read_records, read_two_column

PACKAGE_DATA = Path(__file__).resolve().parents[1] / "jaxrock" / "data"

# packaged file -> (NPTS, DT [s], PGA [g] from jaxrock/data/README.md or None where it gives none)
PACKAGED_FILES = {
    "IELC180.AT2": (4000, 0.01, 0.3129),
    "elcentro_ns_1940.txt": (4000, 0.01, 0.3129),
    "records/elCentro_peknold.AT2": (1559, 0.02, 0.3188),
    "records/ARL360.at2": (2000, 0.02, None),
    "records/B-ELC000.AT2": (8000, 0.005, None),
    "records/A-TIN000.AT2": (7996, 0.005, None),
}


def _raw_lines(path: Path) -> list[str]:
    """Lines split on '\\n' only (ARL360.at2 ends its lines with '\\r\\r\\n')."""
    return path.read_bytes().decode().split("\n")


def _naive_at2_values(path: Path) -> np.ndarray:
    """Independent oracle: every whitespace token after the 4 header lines, in g."""
    return np.array(" ".join(_raw_lines(path)[4:]).split(), dtype=float)


# --- real files ---------------------------------------------------------------------------------


@pytest.mark.parametrize("rel", sorted(PACKAGED_FILES))
def test_packaged_files_parse(rel):
    npts, dt, pga = PACKAGED_FILES[rel]
    path = PACKAGE_DATA / rel
    rec = read_record(path)
    assert rec.n == npts
    assert float(rec.dt) == pytest.approx(dt, rel=1e-12)
    acc_g = np.asarray(rec.acc) / G
    assert 0.01 < np.max(np.abs(acc_g)) < 3.0  # a unit read wrongly is off by 9.81 or 100
    if pga is not None:
        assert np.max(np.abs(acc_g)) == pytest.approx(pga, abs=5e-5)
    if path.suffix.lower() == ".at2":
        np.testing.assert_array_equal(acc_g * G, _naive_at2_values(path) * G)
        assert rec.name == _raw_lines(path)[1].strip()


def test_every_packaged_record_is_checked_and_named():
    """Every packaged record file (the real header variants) is in PACKAGED_FILES, is reachable by
    its name (`builtin_record`, the same values as reading its file) and is in the `builtin` suite."""
    from jaxrock.scene import PACKAGED_RECORDS

    present = {f"records/{p.name}" for p in (PACKAGE_DATA / "records").iterdir() if p.is_file()}
    assert present == {f"records/{f}" for f in PACKAGED_RECORDS.values()} and present <= set(PACKAGED_FILES)
    suite = read_records(["builtin"])
    assert [r.name for r in suite] == ["El Centro 1940 NS", *(Path(f).stem for f in PACKAGED_RECORDS.values())]
    for name, file in PACKAGED_RECORDS.items():
        by_name = builtin_record(name.upper())
        np.testing.assert_array_equal(by_name.acc, read_record(PACKAGE_DATA / "records" / file).acc)
        assert by_name.name == Path(file).stem and float(by_name.dt) == float(read_record(PACKAGE_DATA / "records" / file).dt)
    np.testing.assert_array_equal(builtin_record("El-Centro").acc, el_centro().acc)
    with pytest.raises(JaxrockInputError, match="not a packaged record; valid: elcentro"):
        builtin_record("ARL361")


def test_packaged_el_centro():
    rec = el_centro()
    at2 = read_at2(PACKAGE_DATA / "IELC180.AT2")
    txt = read_two_column(PACKAGE_DATA / "elcentro_ns_1940.txt")
    np.testing.assert_array_equal(rec.acc, at2.acc)
    np.testing.assert_array_equal(rec.acc, txt.acc)
    assert rec.n == 4000 and float(rec.dt) == pytest.approx(0.01, rel=1e-12)
    assert float(at2.dt) == 0.01
    k = int(np.argmax(np.abs(np.asarray(rec.acc))))
    assert float(rec.acc[k]) / G == pytest.approx(-0.3129, abs=5e-5)
    assert k * 0.01 == pytest.approx(2.15)
    assert at2.name.startswith("IMPERIAL VALLEY 5/19/40")


# --- Record behaviour on a real record ----------------------------------------------------------


def _records():
    return read_records(["builtin"])


def test_record_interpolates_exactly_at_samples():
    for rec in _records():
        acc = np.asarray(rec.acc)
        vals = np.asarray(jax.vmap(rec)(rec.times))
        # exact up to the rounding of t/dt (|Δ| ≲ n ε max|a|)
        np.testing.assert_allclose(vals, acc, rtol=1e-12, atol=1e-12 * np.max(np.abs(acc)), err_msg=rec.name)
        assert float(rec(rec.t_end)) == pytest.approx(acc[-1], rel=1e-12, abs=1e-18), rec.name
        assert float(rec(-1e-9)) == 0.0 and float(rec(rec.t_end + 1e-9)) == 0.0


# --- well-formed variants -----------------------------------------------------------------------

AT2_HEAD = "PEER STRONG MOTION DATABASE RECORD.\nTEST EVENT 1/1/00, STATION, 000\nACCELERATION IN UNITS OF G\n"


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, newline="")
    return path


def test_at2_header_variants(tmp_path):
    body = "  .1E-01 -.2E-01  0.03\r\n-0.04\r\n   0.05   0.06\r\n"
    for line4 in ("NPTS=  6, DT= .01000 SEC", "NPTS= 6 DT= 0.01", "npts=6,dt=1.0E-02"):
        path = _write(tmp_path, "v.at2", AT2_HEAD + line4 + "\r\n" + body)
        rec = read_record(path)
        np.testing.assert_allclose(rec.acc, G * np.array([0.01, -0.02, 0.03, -0.04, 0.05, 0.06]), rtol=1e-15)
        assert float(rec.dt) == 0.01 and rec.name == "TEST EVENT 1/1/00, STATION, 000"
    assert read_at2(path, name="mine").name == "mine"


NGA_ROTATED = ("Orig PEER filename = RSN1063_NORTHR_RRS228.AT2, Scale factor = 1.000\n"
               "Northridge-01, 1/17/1994, Rinaldi Receiving Sta, 228\n"
               "Rotated to FN azimuth = 32.0\n"
               "Rotated to FP azimuth = 122.0\n"
               "Fault-normal component\n"
               "Acceleration in {units}\n"
               "{line}\n")


@pytest.mark.parametrize("line", ["6 0.0050 NPTS, DT", "0.0050 6 DT, NPTS", "NPTS= 6, DT= .0050 SEC", "DT= 0.005, NPTS= 6",
                                  "NPTS=  6, dt=  0.005"])
def test_at2_npts_dt_on_any_header_line_in_any_spelling(tmp_path, line):
    """Issue 52: the rotated fault-normal/fault-parallel components of PEER's NGA data have a
    6-line header and "7997 0.0050 NPTS, DT" on line 7: they were refused ("line 4: no numeric
    NPTS="). NPTS and DT are now read from the first header line that gives them, either order,
    values before or after their labels; "Acceleration in g" states the units."""
    body = ".1E-01 -.2E-01 0.03\n-0.04 0.05 0.06\n"
    rec = read_record(_write(tmp_path, "fn.AT2", NGA_ROTATED.format(units="g", line=line) + body))
    np.testing.assert_allclose(rec.acc, G * np.array([0.01, -0.02, 0.03, -0.04, 0.05, 0.06]), rtol=1e-15)
    assert float(rec.dt) == 0.005 and rec.name == "fn"
    rec = read_record(_write(tmp_path, "cm.AT2", NGA_ROTATED.format(units="cm/s/s", line=line) + body))
    np.testing.assert_allclose(rec.acc, 0.01 * np.array([0.01, -0.02, 0.03, -0.04, 0.05, 0.06]), rtol=1e-15)
    with pytest.raises(JaxrockInputError, match="states units 'cm/s/s', but units = 'g' was given"):
        read_record(tmp_path / "cm.AT2", units="g")


def test_two_column_variants(tmp_path):
    text = "# header\n\n5.00, 0.1\n5.02,-0.2  # trailing comment\n5.04 , 0.3\n"
    rec = read_record(_write(tmp_path, "r.csv", text))
    np.testing.assert_allclose(rec.acc, G * np.array([0.1, -0.2, 0.3]), rtol=1e-15)
    assert float(rec.dt) == pytest.approx(0.02, rel=1e-12) and float(rec.t_start) == 0.0
    assert rec.name == "r"
    rec = read_two_column(_write(tmp_path, "r.txt", "0 1.5\n0.1 -2\n"), units="m/s2", name="x")
    np.testing.assert_array_equal(rec.acc, [1.5, -2.0])
    assert rec.name == "x"


# --- malformed input ----------------------------------------------------------------------------

BAD_AT2 = {
    "no_npts": (AT2_HEAD + "DT= .01 SEC\n0.1 0.2\n", r"no NPTS and DT in the first 6 line\(s\)"),
    "two_npts": (AT2_HEAD + "NPTS= 2, NPTS= 3, DT= .01\n0.1 0.2\n", r"line 4: NPTS = 2 and 3"),
    "npts_after_data": (AT2_HEAD + "0.1 0.2\n" * 9 + "NPTS= 2, DT= .01\n", r"no NPTS and DT in the first 12 line\(s\)"),
    "no_dt": (AT2_HEAD + "NPTS= 2, SEC\n0.1 0.2\n", r"line 4: no numeric DT="),
    "dt_zero": (AT2_HEAD + "NPTS= 2, DT= 0.0\n0.1 0.2\n", r"line 4: DT = 0 s; the time step must be > 0"),
    "dt_negative": (AT2_HEAD + "NPTS= 2, DT= -.01\n0.1 0.2\n", r"DT = -0.01 s; the time step must be > 0"),
    "npts_one": (AT2_HEAD + "NPTS= 1, DT= .01\n0.1\n", r"NPTS = 1; a record needs NPTS >= 2"),
    "nan": (AT2_HEAD + "NPTS= 3, DT= .01\n0.1 0.2\nNaN\n", r"line 6: non-finite value 'NaN'"),
    "inf": (AT2_HEAD + "NPTS= 3, DT= .01\n0.1 -inf 0.2\n", r"line 5: non-finite value '-inf'"),
    "token": (AT2_HEAD + "NPTS= 3, DT= .01\n0.1 0.2\n0.3x\n", r"line 6: non-numeric token '0.3x'"),
    "fewer": (AT2_HEAD + "NPTS= 4, DT= .01\n0.1 0.2\n0.3\n", r"3 values after the header, fewer than NPTS = 4"),
    "more": (AT2_HEAD + "NPTS= 2, DT= .01\n0.1 0.2\n0.3\n", r"3 values after the header, more than NPTS = 2"),
    "short_header": ("PEER\nEVENT\n", r"no NPTS and DT in the first 3 line\(s\)"),
    "empty": ("", r"the file is empty"),
    "blank": ("\n  \n", r"the file is empty"),
}


@pytest.mark.parametrize("case", sorted(BAD_AT2))
def test_bad_at2(tmp_path, case):
    text, message = BAD_AT2[case]
    path = _write(tmp_path, f"{case}.AT2", text)
    with pytest.raises(JaxrockInputError, match=message) as err:
        read_record(path)
    assert str(path) in str(err.value)


BAD_TWO_COLUMN = {
    "nonuniform": ("0 0.1\n0.01 0.2\n0.02 0.3\n0.035 0.4\n", r"line 4: time step 0.015 s differs .* must be uniform"),
    "decreasing": ("0 0.1\n0.01 0.2\n0.005 0.3\n", r"line 3: time 0.005 s does not exceed .* strictly increasing"),
    "repeated": ("# c\n0 0.1\n0 0.2\n", r"line 3: time 0 s does not exceed .* strictly increasing"),
    "nan": ("0 0.1\n0.01 nan\n", r"line 2: non-finite value 'nan'"),
    "inf": ("0 0.1\n0.01 0.2\ninf 0.3\n", r"line 3: non-finite value 'inf'"),
    "token": ("0 0.1\n0.01 zero\n", r"line 2: non-numeric token 'zero'"),
    "three_columns": ("0 0.1\n0.01 0.2 7\n", r"line 2: 3 value\(s\); expected two columns"),
    "one_row": ("# only one\n0 0.1\n", r"1 data line\(s\); a record needs at least 2"),
    "only_comments": ("# nothing\n# here\n", r"0 data line\(s\)"),
    "empty": ("", r"the file is empty"),
}


@pytest.mark.parametrize("case", sorted(BAD_TWO_COLUMN))
def test_bad_two_column(tmp_path, case):
    text, message = BAD_TWO_COLUMN[case]
    path = _write(tmp_path, f"{case}.txt", text)
    with pytest.raises(JaxrockInputError, match=message) as err:
        read_record(path)
    assert str(path) in str(err.value)


def test_unknown_units(tmp_path):
    path = _write(tmp_path, "u.txt", "0 0.1\n0.01 0.2\n")
    with pytest.raises(JaxrockInputError, match=r"units = 'furlong/s2' .*valid units are g, m/s2, cm/s2"):
        read_two_column(path, units="furlong/s2")


# --- units --------------------------------------------------------------------------------------
# (written, factor to m/s²): the header or `units` spellings a user meets
UNIT_SPELLINGS = [("G", G), ("g", G), ("CM/S/S", 0.01), ("CM/SEC/SEC", 0.01), ("cm/s^2", 0.01), ("gal", 0.01),
                  ("M/S/S", 1.0), ("m/s²", 1.0), ("m/sec**2", 1.0), ("MM/S/S", 1e-3), ("IN/S/S", 0.0254), ("ft/s2", 0.3048)]


@pytest.mark.parametrize("written, factor", UNIT_SPELLINGS)
def test_at2_reads_the_units_its_header_states(tmp_path, written, factor):
    """An AT2 whose header says 'UNITS OF CM/S/S' was read as g (the body overturned at 0.077 s):
    the stated unit now scales the values, checked against the naive oracle times the factor."""
    head = f"PEER\nTEST EVENT\nACCELERATION TIME HISTORY IN UNITS OF {written}. FILTER POINTS: HP=0.1 Hz\n"
    path = _write(tmp_path, "u.AT2", head + "NPTS= 3, DT= .01\n 12.5 -30.0 4.0\n")
    rec = read_record(path)
    np.testing.assert_allclose(rec.acc, np.array([12.5, -30.0, 4.0]) * factor, rtol=1e-15)


@pytest.mark.parametrize("written, factor", UNIT_SPELLINGS)
def test_two_column_units_argument(tmp_path, written, factor):
    rec = read_record(_write(tmp_path, "r.txt", "0 12.5\n0.01 -30\n"), units=written)
    np.testing.assert_allclose(rec.acc, np.array([12.5, -30.0]) * factor, rtol=1e-15)


def test_at2_units_refused_when_uninterpretable_or_contradicted(tmp_path):
    path = _write(tmp_path, "f.AT2", "PEER\nEVENT\nIN UNITS OF FURLONGS/FORTNIGHT2\nNPTS= 2, DT= .01\n0.1 0.2\n")
    with pytest.raises(JaxrockInputError, match=r"line 3: the header states units 'FURLONGS/FORTNIGHT2', which jaxrock cannot"):
        read_record(path)
    path = _write(tmp_path, "c.AT2", "PEER\nEVENT\nUNITS OF CM/S/S\nNPTS= 2, DT= .01\n0.1 0.2\n")
    with pytest.raises(JaxrockInputError, match=r"states units 'CM/S/S', but units = 'g' was given"):
        read_record(path, units="g")
    assert float(read_record(path, units="gal").acc[0]) == pytest.approx(0.001, rel=1e-15)
    # no statement: the PEER convention (g), or the unit given
    path = _write(tmp_path, "n.AT2", "PEER\nEVENT\nno statement here\nNPTS= 2, DT= .01\n0.1 0.2\n")
    assert float(read_record(path).acc[0]) == pytest.approx(0.1 * G, rel=1e-15)
    assert float(read_record(path, units="m/s2").acc[0]) == pytest.approx(0.1, rel=1e-15)


def test_lists_that_name_themselves_or_each_other_are_refused(tmp_path):
    """Issue 52: a .list naming itself, or two naming each other, was a RecursionError."""
    (tmp_path / "a.list").write_text("a.list\n")
    with pytest.raises(JaxrockInputError, match=r"the list .*a.list names itself"):
        read_records([tmp_path / "a.list"])
    (tmp_path / "b.list").write_text("elcentro\nc.list\n")
    (tmp_path / "c.list").write_text("b.list\n")
    with pytest.raises(JaxrockInputError, match=r"names itself \(.*b.list → .*c.list → .*b.list\)"):
        read_records([tmp_path / "b.list"])


def test_a_folder_or_a_fifo_is_not_read_as_a_record(tmp_path):
    """`read_record` on a folder was an IsADirectoryError; a FIFO was reported as "file not found"
    on the command line (and would have blocked a reader)."""
    with pytest.raises(JaxrockInputError, match="is a folder; read_record reads one record file"):
        read_record(tmp_path)
    os.mkfifo(tmp_path / "pipe.AT2")
    with pytest.raises(JaxrockInputError, match="is not a regular file"):
        read_record(tmp_path / "pipe.AT2")
    r = invoke("simulate", "--record", tmp_path / "pipe.AT2")
    assert r.exit_code == 2 and "is not a regular file" in r.output, r.output
