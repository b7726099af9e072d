"""One output schema (`jaxrock.outputs.SUMMARY`): every summary output reaches `Solution`,
`Spectrum`, the netCDF file, the batch results file and the command line's summaries, and a new
output needs nothing but its line in the schema and the code that computes it."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import jaxrock as jr
from jaxrock.analyses.spectra import Spectrum
from jaxrock.cli.options import solution_summary, spectrum_summary
from jaxrock.results import OUTPUTS, RESULT_COLUMNS, SUMMARY

ROOT = Path(__file__).resolve().parents[1]


def _grid(o, shape):
    return {"float": np.full(shape, 1.0), "bool": np.ones(shape, bool), "int": np.full(shape, 3, np.int64)}[o.kind]


def test_every_summary_output_reaches_every_product(tmp_path):
    shape = (2, 3)
    fields = set(jr.Solution.__dataclass_fields__)
    assert set(OUTPUTS) <= fields and set(OUTPUTS) <= set(Spectrum.__dataclass_fields__)
    assert RESULT_COLUMNS == (*OUTPUTS, "status")
    spec = Spectrum(omega_ratio=np.array([1.0, 2.0, 3.0]), accel_ratio=np.array([1.0, 2.0]),
                    **{o.name: _grid(o, shape) for o in SUMMARY}, status=np.zeros(shape, np.int32),
                    attrs={"model": "RigidModel", "pulse": "RickerPulse", "threshold": 1.0, "tan_alpha": 0.2, "alpha": 0.197,
                           "p": 1.2, "height": 10.0, "width": 2.0})
    ds = spec.to_xarray()
    back = Spectrum.load(spec.save(tmp_path / "s.nc"))
    text = spectrum_summary(spec, 1.0)
    for o in SUMMARY:
        assert ds[o.name].attrs["long_name"] == o.meaning and ds[o.name].shape == shape
        np.testing.assert_array_equal(getattr(back, o.name), getattr(spec, o.name))
        assert getattr(back, o.name).dtype == o.dtype
        assert f"\n{o.label}: " in text
    one = jr.Solution(**{o.name: np.asarray(_grid(o, ())) for o in SUMMARY}, status=jr.Status.ok)
    lines = solution_summary(one, jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))).splitlines()
    assert [ln.split(":")[0].split(" = ")[0] for ln in lines[: len(SUMMARY)]] == [o.label for o in SUMMARY]


def test_a_spectrum_file_without_an_output_is_refused_by_name(tmp_path):
    spec = Spectrum(omega_ratio=np.array([1.0]), accel_ratio=np.array([1.0]), **{o.name: _grid(o, (1, 1)) for o in SUMMARY},
                    status=np.zeros((1, 1), np.int32), attrs={"jaxrock_version": "0.0.1"})
    ds = spec.to_xarray().drop_vars("n_impacts")
    ds.to_netcdf(tmp_path / "old.nc", engine="scipy")
    with pytest.raises(jr.JaxrockInputError, match="no variable.*n_impacts.*0.0.1"):
        Spectrum.load(tmp_path / "old.nc")


# A new output, added as a user would add one: a line in the schema and its computation in the
# bookkeeping (the peak |θ| in radians, from the run's record), in a copy of the package.
NEW_OUTPUT = '''    Output("peak_rad", "peak |θ| [rad]", "max |theta| over the response in radians", "rad", "float"),\n)'''
SCRIPT = textwrap.dedent("""
    import csv, sys
    import numpy as np, xarray as xr
    import jaxrock as jr
    from typer.testing import CliRunner
    from jaxrock.cli import app
    out = sys.argv[1]
    block = jr.Block.from_slenderness(10.0, 0.2)
    spec = jr.overturning_spectrum(jr.RigidModel(block), [2.0, 4.0], [1.5, 3.0], progress=False)
    still = ~spec.overturned
    assert still.any() and np.allclose(spec.peak_rad[still], spec.max_theta[still] * float(block.alpha_r)), spec.peak_rad
    spec.save(out + "/s.nc")
    assert "peak_rad" in xr.open_dataset(out + "/s.nc", engine="scipy")
    with open(out + "/scenes.csv", "w") as fh:
        fh.write("height,tan_alpha,accel_ratio,omega_ratio\\n10,0.2,3,4\\n10,0.2,1.5,2\\n")
    jr.run_scenes(out + "/scenes.csv", out + "/results.csv", progress=False)
    rows = list(csv.DictReader(open(out + "/results.csv")))
    assert all(float(r["peak_rad"]) > 0 for r in rows), rows
    r = CliRunner().invoke(app, ["simulate", "--accel-ratio", "3", "--omega-ratio", "4"])
    assert r.exit_code == 0 and "peak |θ| [rad] = " in r.output, r.output
    print("new output everywhere")
""")


def test_a_new_output_needs_only_its_schema_line_and_its_computation(tmp_path):
    pkg = tmp_path / "pkg"
    shutil.copytree(ROOT / "jaxrock", pkg / "jaxrock", ignore=shutil.ignore_patterns("__pycache__"))
    outputs, bookkeeping = pkg / "jaxrock" / "outputs.py", pkg / "jaxrock" / "bookkeeping.py"
    schema = outputs.read_text()
    end = schema.index("\n)\n", schema.index("SUMMARY: tuple[Output, ...] = (")) + 1  # the tuple's closing parenthesis
    outputs.write_text(schema[:end] + NEW_OUTPUT + schema[end + 1:])
    code = bookkeeping.read_text()
    anchor = '            "t_uplift": record.t_uplift,\n'
    assert code.count(anchor) == 1
    bookkeeping.write_text(code.replace(anchor, anchor + '            "peak_rad": record.peak,\n'))
    env = {**os.environ, "PYTHONPATH": str(pkg), "JAX_PLATFORMS": "cpu"}
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], env=env, capture_output=True, text=True, timeout=280,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "new output everywhere" in r.stdout
