"""Intensity measures beyond the suite's table: the spectral acceleration (against the closed-form
steady state of a harmonic motion, the PGA at short periods and an independent integration with
`scipy.signal.lsim`), the CAV and pgv/pga, and the `--im` forms of a fragility (`parse_im`,
`parse_ims`, `intensity_of`)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

import jaxrock as jr
from jaxrock import intensity
from jaxrock._validate import JaxrockInputError
from jaxrock.intensity import (
    intensity_of,
    parse_im,
    parse_ims,
    record_measures,
    spectral_acceleration,
)


@pytest.fixture(scope="module")
def elcentro():
    return jr.el_centro()


def _samples(rec):
    return np.asarray(rec.acc, dtype=float) * float(rec.scale), float(rec.dt)


# -- spectral acceleration ---------------------------------------------------------------------------
def _ramped_sine(amp, period, dt, n_ramp=60, n_steady=100):
    """amp sin(Ωt) under an envelope that rises over n_ramp cycles (a C² quintic step: its transient is
    negligible), holds for n_steady cycles and falls again."""
    dur = (2 * n_ramp + n_steady) * period
    t = dt * np.arange(round(dur / dt) + 1)
    x = np.clip(np.minimum(t, dur - t) / (n_ramp * period), 0.0, 1.0)
    return amp * np.sin(2 * np.pi / period * t) * x**3 * (10 - 15 * x + 6 * x**2)


@pytest.mark.parametrize("damping", [0.02, 0.05, 0.2])
def test_sa_of_a_harmonic_motion_is_the_steady_state_amplitude(damping):
    """Sa = ω² U of the steady state U = A / √((ω² − Ω²)² + (2ζωΩ)²), at and off resonance. The
    record is the sine linear between samples, whose fundamental is the sine's × sinc²(Ω dt / 2)
    (3e-4 at 100 samples a cycle). Measured: within 3e-4 off resonance (the ramp's slight overshoot), 1e-7 at it."""
    amp, tg = 2.0, 0.5
    dt = tg / 100
    rec = jr.Record(_ramped_sine(amp, tg, dt), dt)
    w_g = 2 * np.pi / tg
    periods = tg / np.array([0.5, 0.8, 1.0, 1.25, 2.0])
    w = 2 * np.pi / periods
    exact = np.sinc(w_g * dt / (2 * np.pi)) ** 2 * w**2 * amp / np.sqrt((w**2 - w_g**2) ** 2 + (2 * damping * w * w_g) ** 2)
    sa = spectral_acceleration(rec, periods, damping)
    np.testing.assert_allclose(sa, exact, rtol=1e-3)
    assert sa[2] == pytest.approx(exact[2], rel=1e-5)  # at resonance: no overshoot


def test_sa_at_short_periods_is_the_pga(elcentro):
    """T ≪ dt: the oscillator follows üg, Sa → PGA (measured 4e-6 at dt/100, 3e-4 at dt/10)."""
    acc, dt = _samples(elcentro)
    pga = np.max(np.abs(acc))
    np.testing.assert_allclose(spectral_acceleration(elcentro, [dt / 100, dt / 10]), pga, rtol=1e-3)
    # any shape of periods; repeated periods give the same value
    sa = spectral_acceleration(elcentro, [[0.5, 1.0], [0.5, 2.0]])
    assert sa.shape == (2, 2) and sa[0, 0] == sa[1, 0]
    assert spectral_acceleration(elcentro, 0.5).shape == ()


def _lsim_sa(acc, dt, period, damping):
    """Sa by `scipy.signal.lsim` (first-order hold: exact for üg linear between points) on the record
    resampled at ≥ 300 points a period, with one period of free vibration after its end."""
    w = 2 * np.pi / period
    sub = max(4, int(np.ceil(300 * dt / period)))
    n_tail = int(np.ceil(period / dt)) + 2
    t = dt * np.arange(acc.size)
    tf = dt / sub * np.arange((acc.size - 1 + n_tail) * sub + 1)
    a = np.where(tf <= t[-1] + 1e-9 * dt, np.interp(tf, t, acc), 0.0)
    _, u, _ = scipy.signal.lsim(([-1.0], [1.0, 2 * damping * w, w**2]), a, tf)
    return w**2 * np.max(np.abs(u))


def test_sa_against_an_independent_integration(elcentro):
    """El Centro against `scipy.signal.lsim`: measured within 1e-4 (this module's points, ≥ 128 a
    period, and the reference's, ≥ 300, miss the peak by < 3e-4 and 5e-5 at worst)."""
    acc, dt = _samples(elcentro)
    periods = np.array([0.05, 0.3, 1.0, 3.0])
    sa = spectral_acceleration(elcentro, periods, 0.05)
    ref = np.array([_lsim_sa(acc, dt, t, 0.05) for t in periods])
    np.testing.assert_allclose(sa, ref, rtol=1e-3)


def test_sa_refuses_bad_periods_and_damping(elcentro):
    for bad in ([0.5, 0.0], [-1.0], [np.nan], [np.inf]):
        with pytest.raises(JaxrockInputError, match="periods"):
            spectral_acceleration(elcentro, bad)
    for bad in (-0.01, 1.0, np.nan):
        with pytest.raises(JaxrockInputError, match="damping"):
            spectral_acceleration(elcentro, [0.5], bad)


# -- CAV, pgv/pga, scaling ---------------------------------------------------------------------------
def test_cav_of_a_sine():
    """∫|A sin Ωt| dt over n half cycles = 2 n A / Ω (trapezoidal: within (Ω dt)²/12 = 2e-5)."""
    amp, period, n = 3.0, 0.4, 7
    dt = period / 400
    t = dt * np.arange(round(n * period / 2 / dt) + 1)
    m = record_measures(jr.Record(amp * np.sin(2 * np.pi / period * t), dt))
    assert m["cav"] == pytest.approx(2 * n * amp / (2 * np.pi / period), rel=1e-4)
    assert m["pgv_pga"] == pytest.approx(m["pgv"] / m["pga"], rel=1e-15)


def test_cav_and_sa_scale_linearly_and_pgv_pga_does_not(elcentro):
    s = 2.5
    m1, m2 = record_measures(elcentro), record_measures(elcentro.scaled(s))
    assert m2["cav"] == pytest.approx(s * m1["cav"], rel=1e-12)
    assert m2["pgv_pga"] == pytest.approx(m1["pgv_pga"], rel=1e-12)
    assert intensity.SCALING["cav"] == 1 and intensity.SCALING["pgv_pga"] == 0
    assert {"cav", "pgv_pga"} <= set(intensity.MEASURES)
    periods = [0.05, 0.5, 2.0]
    np.testing.assert_allclose(spectral_acceleration(elcentro.scaled(s), periods), s * spectral_acceleration(elcentro, periods), rtol=1e-12)
    # a record without motion: pgv/pga undefined, CAV 0
    still = record_measures(jr.Record(np.zeros(50), 0.01))
    assert np.isnan(still["pgv_pga"]) and still["cav"] == 0.0


# -- the --im forms ----------------------------------------------------------------------------------
def test_parse_im_forms():
    assert parse_im("pga") == ("pga", "m/s2", 1, ())
    assert parse_im(" PGV ") == ("pgv", "m/s", 1, ())
    assert parse_im("arias") == ("arias", "m/s", 2, ())
    assert parse_im("cav") == ("cav", "m/s", 1, ())
    assert parse_im("sa:0.50") == ("sa:0.5", "m/s2", 1, ())
    assert parse_im("Sa:1e-1")[0] == "sa:0.1"
    assert parse_im("sa:t1") == ("sa:T1", "m/s2", 1, ("period",))
    assert parse_im("pga_ratio") == ("pga_ratio", "1", 1, ("tan_alpha",))
    assert parse_im("pgv_ratio") == ("pgv_ratio", "1", 1, ("tan_alpha", "p"))
    assert parse_im("pgv_pga") == ("pgv_pga", "s", 0, ())  # a record measure that does not scale
    assert parse_ims("sa:T1, PGV,sa:2") == ["sa:T1", "pgv", "sa:2"]
    assert parse_ims("scale,pga", allow_scale=True) == ["scale", "pga"]
    with pytest.raises(JaxrockInputError, match="'scale'"):
        parse_ims("scale,pga")


@pytest.mark.parametrize("spec", ["pgx", "d5_95", "duration", "sa", "sa:", "sa:T2", "sa(0.5)", ""])
def test_unknown_im_refused_in_one_line(spec):
    with pytest.raises(JaxrockInputError) as e:
        parse_im(spec)
    msg = str(e.value)
    assert "\n" not in msg and "--im" in msg and repr(spec.strip()) in msg
    if not spec.startswith("sa:"):
        assert "sa:T1" in msg and "pgv_ratio" in msg  # the valid forms listed


@pytest.mark.parametrize("spec", ["sa:0", "sa:-0.5", "sa:nan", "sa:inf", "sa:abc"])
def test_sa_of_a_bad_period_refused(spec):
    with pytest.raises(JaxrockInputError, match=r"--im .*finite number > 0"):
        parse_im(spec)


def test_parse_ims_refuses_duplicates_and_empty_items():
    with pytest.raises(JaxrockInputError, match="sa:0.5 twice"):
        parse_ims("sa:0.5,pgv,sa:.50")
    with pytest.raises(JaxrockInputError, match="pga twice"):
        parse_ims("pga,PGA")
    with pytest.raises(JaxrockInputError, match="scale twice"):
        parse_ims("scale,Scale", allow_scale=True)
    with pytest.raises(JaxrockInputError, match="empty item"):
        parse_ims("pga,,pgv")
    with pytest.raises(JaxrockInputError, match="'bad'"):
        parse_ims("pga,bad")


def test_intensity_of_record_measures_and_ratios():
    recs = jr.read_records("builtin")
    m = [record_measures(r) for r in recs]
    pga, pgv = np.array([x["pga"] for x in m]), np.array([x["pgv"] for x in m])
    assert intensity_of("pga", recs).shape == (len(recs),)
    np.testing.assert_array_equal(intensity_of("cav", recs), [x["cav"] for x in m])
    np.testing.assert_array_equal(intensity_of("pgv_pga", recs), pgv / pga)
    ta = np.array([[0.1, 0.2, 0.25]])  # cells (1, 3)
    p = np.array([[1.5], [2.0]])  # cells (2, 1): the cells broadcast to (2, 3)
    got = intensity_of("pgv", recs, tan_alpha=ta, p=p)  # a record measure over the cells
    assert got.shape == (len(recs), 2, 3) and np.all(got == pgv[:, None, None])
    np.testing.assert_allclose(intensity_of("pga_ratio", recs, tan_alpha=ta[0]), pga[:, None] / (jr.G * ta[0]), rtol=1e-15)
    np.testing.assert_allclose(intensity_of("pgv_ratio", recs, tan_alpha=ta, p=p),
                               pgv[:, None, None] * p / (jr.G * ta), rtol=1e-15)
    assert jr.G == 9.81
    # needed arguments: missing, or not finite > 0
    with pytest.raises(JaxrockInputError, match="--im pga_ratio needs tan_alpha"):
        intensity_of("pga_ratio", recs)
    with pytest.raises(JaxrockInputError, match="--im pgv_ratio needs p"):
        intensity_of("pgv_ratio", recs, tan_alpha=0.2)
    with pytest.raises(JaxrockInputError, match="tan_alpha"):
        intensity_of("pga_ratio", recs, tan_alpha=[0.2, -0.1])
    with pytest.raises(JaxrockInputError, match="do not broadcast"):
        intensity_of("pgv_ratio", recs, tan_alpha=[0.1, 0.2], p=[1.0, 2.0, 3.0])


def test_intensity_of_sa_once_per_record_for_its_unique_periods(monkeypatch):
    recs = jr.read_records(["elcentro", "ARL360"])
    calls = []
    peaks = intensity._sdof_peaks

    def counted(acc, dt, periods, damping):
        calls.append(np.array(periods))
        return peaks(acc, dt, periods, damping)

    monkeypatch.setattr(intensity, "_sdof_peaks", counted)
    t1 = np.array([[0.3, 0.5, 0.3], [1.0, 0.5, 0.5]])  # cells (2, 3), the same for every record
    got = intensity_of("sa:T1", recs, period=t1)
    assert got.shape == (2, 2, 3) and len(calls) == 2
    assert all(np.array_equal(c, [0.3, 0.5, 1.0]) for c in calls)  # once per record, its unique periods
    for i, rec in enumerate(recs):
        np.testing.assert_array_equal(got[i], spectral_acceleration(rec, t1))
    # one period per record and cell: shape (n_records, *cells), with the cells given by tan_alpha
    per_record = np.array([[0.2, 0.4], [0.6, 0.8]])
    got = intensity_of("sa:T1", recs, period=per_record, tan_alpha=[0.1, 0.2])
    for i, rec in enumerate(recs):
        np.testing.assert_array_equal(got[i], spectral_acceleration(rec, per_record[i]))
    # a fixed period, over the cells
    got = intensity_of("sa:0.5", recs, tan_alpha=[0.1, 0.2, 0.3])
    assert got.shape == (2, 3)
    np.testing.assert_array_equal(got[:, 0], [spectral_acceleration(r, 0.5) for r in recs])
    with pytest.raises(JaxrockInputError, match="--im sa:T1 needs period"):
        intensity_of("sa:T1", recs)
    with pytest.raises(JaxrockInputError, match="period"):
        intensity_of("sa:T1", recs, period=[0.5, 0.0])


@pytest.mark.parametrize("tg", [0.4, 1.2, 3.0])
def test_pulse_period_of_a_harmonic_motion_is_its_velocity_resonance(tg):
    """Under a long harmonic üg of period Tg the pseudo-velocity spectrum is the steady state's,
    PSV(T) = A/ω / sqrt((1 − r²)² + (2ζr)²), r = Tg/T... written from the SDOF's closed form: its
    peak (found here by scipy) is Tp; `pulse_period` finds it on its grid refined by a parabola,
    within 0.2 %; ω_p/p follows from it."""
    from scipy.optimize import minimize_scalar

    from jaxrock.intensity import intensity_of, pulse_period

    dt, zeta = min(0.01, tg / 100), 0.05
    rec = jr.Record(_ramped_sine(1.0, tg, dt, n_ramp=20, n_steady=40), dt)
    W = 2 * np.pi / tg

    def psv(T):  # the steady-state amplitude of u under sin(W t), times ω
        w = 2 * np.pi / T
        return w / np.sqrt((w**2 - W**2) ** 2 + (2 * zeta * w * W) ** 2)

    ref = minimize_scalar(lambda lt: -psv(np.exp(lt)), bounds=(np.log(tg / 2), np.log(2 * tg)), method="bounded",
                          options={"xatol": 1e-10}).x
    tp = pulse_period(rec)
    assert tp == pytest.approx(np.exp(ref), rel=2e-3)  # measured 8e-4 … 1.0e-3
    p = np.array([1.5, 3.0])
    np.testing.assert_allclose(intensity_of("omega_ratio", [rec], p=p)[0], 2 * np.pi / tp / p, rtol=1e-12)
    assert intensity_of("tp", [rec.scaled(3.0)])[0] == pytest.approx(tp, rel=1e-9)  # scaling power 0
