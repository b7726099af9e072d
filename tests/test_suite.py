"""Record suites: the intensity measures of the records (against independent computations), the
least overturning scale of each record (against a brute-force scale sweep) and the lognormal
fragility fit (recovering a known curve)."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

import jaxrock as jr
from jaxrock import G

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
needs_shared = pytest.mark.skipif(not SHARED.is_dir(), reason=f"shared data folder {SHARED} is absent")


def _naive_at2_g(path: Path) -> np.ndarray:
    """Every whitespace token after the 4 header lines (values in g), read without jaxrock."""
    return np.array(" ".join(path.read_bytes().decode().split("\n")[4:]).split(), dtype=float)


# -- intensity measures ------------------------------------------------------------------------------
@needs_shared
@pytest.mark.parametrize("name", ["A-TIN000.AT2", "ARL360.at2", "B-ELC000.AT2", "elCentro_peknold.AT2"])
def test_measures_match_independent_computation(name):
    path = SHARED / "records" / name
    rec = jr.read_record(path)
    m = jr.record_measures(rec)
    acc = _naive_at2_g(path) * G
    dt = float(rec.dt)
    assert m["pga"] == np.max(np.abs(acc))  # exactly: the samples as read
    # PGV, PGD: the acceleration's least-squares line removed, then trapezoidal integration from rest
    t = np.linspace(0.0, 1.0, acc.size)
    a = acc - np.polyval(np.polyfit(t, acc, 1), t)
    v = cumulative_trapezoid(a, dx=dt, initial=0.0)
    u = cumulative_trapezoid(v, dx=dt, initial=0.0)
    assert m["pgv"] == pytest.approx(np.max(np.abs(v)), rel=1e-9)
    assert m["pgd"] == pytest.approx(np.max(np.abs(u)), rel=1e-9)
    # the correction is small on processed records (the module's claim)
    v_raw = cumulative_trapezoid(acc, dx=dt, initial=0.0)
    assert m["pgv"] == pytest.approx(np.max(np.abs(v_raw)), rel=1e-3)
    # Arias intensity pi/(2g) int a^2 dt, and the 5-95 % significant duration to within one step
    ia = np.pi / (2 * G) * cumulative_trapezoid(acc**2, dx=dt, initial=0.0)
    assert m["arias"] == pytest.approx(ia[-1], rel=1e-12)
    t5, t95 = np.interp([0.05 * ia[-1], 0.95 * ia[-1]], ia, dt * np.arange(acc.size))
    assert m["d5_95"] == pytest.approx(t95 - t5, abs=2 * dt)
    assert m["dt"] == dt and m["duration"] == pytest.approx(dt * (acc.size - 1))


def test_measures_scale_with_the_record():
    rec = jr.el_centro()
    m1, m2 = jr.record_measures(rec), jr.record_measures(rec.scaled(2.5))
    for name, power in jr.intensity.SCALING.items():
        assert m2[name] == pytest.approx(2.5**power * m1[name], rel=1e-12), name
    assert m2["d5_95"] == m1["d5_95"]
    assert m1["pga"] / G == pytest.approx(0.3129, abs=5e-5)  # SPEC / the data README
