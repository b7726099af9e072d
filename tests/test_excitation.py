"""Excitations as values (`jaxrock.excitation`): pulses peak at exactly a_p, a record is its samples
linearly interpolated and scales linearly, its next exceedance is the first crossing a dense scan
finds; and a new pulse kind is a class (here a function) and a line in the vocabulary
(`jaxrock.scene.PULSES`), nothing more."""

import csv

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.io.records import el_centro


def test_record_scaled_values():
    rec = el_centro()
    t = jnp.asarray(2.155)
    assert float(rec.scaled(2.5)(t)) == pytest.approx(2.5 * float(rec(t)), rel=1e-14)
    mid = 0.5 * (rec.acc[215] + rec.acc[216])
    assert float(rec(t)) == pytest.approx(float(mid), rel=1e-9)


def _first_dense_exceedance(rec, t0, level, per_step=40):
    """Brute force: dense numpy scan of the piecewise-linear record from t0; first time |üg| ≥ level."""
    ts = np.asarray(rec.times)
    acc = np.asarray(rec.scale * rec.acc)
    dense = np.linspace(t0, ts[-1], int((ts[-1] - t0) / float(rec.dt)) * per_step + 1)
    above = np.abs(np.interp(dense, ts, acc)) >= level
    return (dense[np.argmax(above)] if above.any() else np.inf), dense[1] - dense[0]


def test_next_exceedance_matches_dense_scan():
    rec = el_centro().scaled(1.3)
    pga = float(jnp.max(jnp.abs(rec.scale * rec.acc)))
    starts = np.array([0.0, 0.004, 1.0, 2.0, 2.153, 5.0, 12.345, 30.0])
    fractions = np.array([0.05, 0.3, 0.6, 0.9, 0.999])
    t0, frac = (a.ravel() for a in np.meshgrid(starts, fractions))
    levels = frac * pga
    taus = np.asarray(jax.vmap(rec.next_exceedance)(jnp.asarray(t0), jnp.asarray(levels)))
    for t, level, tau in zip(t0, levels, taus):
        brute, h = _first_dense_exceedance(rec, t, level)
        if not np.isfinite(brute):
            assert np.isinf(tau), (t, level)
            continue
        assert tau >= t
        assert brute - h - 1e-12 <= tau <= brute + 1e-12, (t, level, tau, brute)
        if tau > t:  # a crossing, not "already above": |üg(τ)| is the level itself
            assert abs(float(rec(tau))) == pytest.approx(level, rel=1e-9), (t, level)
        else:
            assert abs(float(rec(t))) >= level
    assert np.isinf(float(rec.next_exceedance(0.0, 1.01 * pga)))
    assert np.isinf(float(rec.next_exceedance(float(rec.t_end) + 0.1, 0.01 * pga)))


@pytest.mark.parametrize("pulse", ["symmetric", "antisymmetric"])
def test_pulse_peak_is_exactly_a_p(pulse):
    """max |üg| = a_p (SPEC; eq. 29's β is the unscaled peak, 1.3801 in the paper rounded): the
    peak is located by a bounded scalar search on the pulse itself, and a dense scan never exceeds it."""
    from scipy.optimize import minimize_scalar

    from jaxrock import AntisymmetricRickerPulse, RickerPulse

    a_p, omega_p = 2.345, 3.7
    exc = (RickerPulse if pulse == "symmetric" else AntisymmetricRickerPulse)(a_p, omega_p)
    f = lambda t: -abs(float(exc(t)))
    bracket = (-0.5 / omega_p, 0.5 / omega_p) if pulse == "symmetric" else (0.5 / omega_p, 2.5 / omega_p)
    peak = -minimize_scalar(f, bounds=bracket, method="bounded", options={"xatol": 1e-12}).fun
    assert abs(peak - a_p) <= 1e-14 * a_p
    ts = jnp.linspace(exc.t_start, exc.t_end, 2_000_001)
    assert float(jnp.max(jnp.abs(exc(ts)))) <= a_p * (1 + 1e-15)
    assert float(exc.peak) == a_p == float(type(exc)(-a_p, omega_p).peak)  # `peak`, any sign


def test_record_peak_is_its_largest_sample_within_its_length_times_its_scale():
    """`Record.peak` (the engine orders a batch's cells by it): max |üg| of the linear interpolant,
    i.e. of its samples, scaled; a padded record's zeros and the samples past `length` are not
    the record."""
    acc = np.array([0.1, -0.7, 0.3, 0.2, 0.0])
    rec = jr.Record(acc, 0.01, 2.0)
    assert float(rec.peak) == 1.4
    assert float(rec.padded(9).peak) == 1.4
    short = jr.Record(np.array([0.1, -0.2, 0.3, -5.0]), 0.01, 1.0, length=3)
    assert float(short.peak) == 0.3 == float(jnp.max(jnp.abs(short(jnp.linspace(0.0, 0.05, 501)))))
    assert float(jr.StillGround().peak) == 0.0


def flipped_ricker(a_p, omega_p):
    """A new pulse kind: the Ricker pulse with the ground moving the other way."""
    return jr.RickerPulse(-a_p, omega_p)


def test_a_new_pulse_kind_needs_only_the_vocabulary(tmp_path, monkeypatch):
    """Added to `PULSES` alone, a pulse kind is read from a scenes file (its ratios converted as
    any pulse's) and runs a spectrum; mirrored ground motion mirrors the response, so its spectrum
    is the symmetric pulse's."""
    monkeypatch.setitem(jr.scene.PULSES, "flipped", flipped_ricker)
    path = tmp_path / "scenes.csv"
    path.write_text("height,tan_alpha,pulse,accel_ratio,omega_ratio\n10,0.2,flipped,3,2\n")
    scenes = jr.read_scenes(path)
    (kind, exc), idx = next(iter(scenes.groups.items()))
    assert (kind, exc) == ("rigid", "flipped")
    pulse = scenes.excitation(exc, idx)
    a_p, w_p = jr.pulse_of_ratios(jr.Block.from_slenderness(10.0, 0.2), 3.0, 2.0)
    np.testing.assert_allclose([float(pulse.a_p[0]), float(pulse.omega_p[0])], [-float(a_p), float(w_p)], rtol=1e-15)
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    grid = dict(omega_ratio=[2.0, 5.0], accel_ratio=[1.5, 4.0], progress=False)
    flipped = jr.overturning_spectrum(model, pulse="flipped", **grid)
    plain = jr.overturning_spectrum(model, pulse="symmetric", **grid)
    assert flipped.attrs["pulse"] == "flipped_ricker"
    np.testing.assert_allclose(flipped.max_theta, plain.max_theta, rtol=1e-9)
    np.testing.assert_array_equal(flipped.overturned, plain.overturned)


# -- the sine pulse of N cycles: a pulse with a parameter beyond (a_p, ω_p) --------------------------
def test_sine_pulse_exceedance_is_its_closed_form_and_a_dense_scan_finds_the_same():
    """|a_p sin ω_p t| > level first at (kπ + asin(level/|a_p|))/ω_p within 0 ≤ t ≤ 2πN/ω_p: against
    a dense scan of the pulse itself, from before its start, inside it and after its end, for
    N = 1/2, 1, 5/2 and levels up to just below the peak (at the peak: never, strictly)."""
    rng = np.random.default_rng(57)
    for n_cycles in (0.5, 1.0, 2.5):
        exc = jr.SinePulse(-1.7, 4.3, n_cycles)
        t_end = float(exc.t_end)
        assert t_end == pytest.approx(2 * np.pi * n_cycles / 4.3, rel=1e-15) and float(exc.t_start) == 0.0
        t0 = np.concatenate([[-0.3, 0.0, t_end, t_end + 0.2], rng.uniform(-0.1, t_end, 40)])
        level = np.concatenate([[0.5, 0.0, 0.5, 0.1], rng.uniform(0.0, 0.999, 40)]) * 1.7
        taus = np.asarray(jax.vmap(exc.next_exceedance)(jnp.asarray(t0), jnp.asarray(level)))
        dense = np.linspace(-0.5, t_end + 0.5, 400_001)
        h = dense[1] - dense[0]
        above = np.abs(np.asarray(exc(jnp.asarray(dense))))
        for t, lv, tau in zip(t0, level, taus):
            hit = (dense >= t) & (above > lv)
            if not hit.any():
                assert np.isinf(tau), (n_cycles, t, lv)
                continue
            brute = dense[np.argmax(hit)]
            assert max(t, brute - h) - 1e-12 <= tau <= brute + 1e-12, (n_cycles, t, lv, tau, brute)
        assert np.isinf(float(exc.next_exceedance(0.0, 1.7)))  # the peak is the level: strictly never
        assert float(exc.peak) == 1.7 and float(jnp.max(jnp.abs(exc(jnp.linspace(0, t_end, 100_001))))) <= 1.7


def test_sine_pulse_refuses_what_is_not_whole_half_cycles():
    for bad, says in ((1.3, "n_cycles = 1.3: whole half cycles"), (0.0, r"n_cycles .*\[0.5, 100\]"), (101.0, r"\[0.5, 100\]")):
        with pytest.raises(jr.JaxrockInputError, match=says):
            jr.SinePulse(1.0, 2.0, bad)


@pytest.mark.parametrize("accel_ratio, omega_ratio, n_cycles", [(1.5, 2.0, 1.0), (3.0, 4.0, 0.5), (1.2, 6.0, 2.5), (6.0, 3.0, 1.0)])
def test_rigid_block_under_a_sine_pulse_matches_the_scipy_event_loop(accel_ratio, omega_ratio, n_cycles):
    """The RM under a sine pulse against the independent SciPy loop (`jaxrock.numerics.scipy_rigid`)
    given the same üg written in NumPy; the uplift time is the closed form asin(g tanα/a_p)/ω_p,
    and its derivative with respect to a_p is that of the closed form."""
    from jaxrock.numerics import scipy_rigid as sr

    block = jr.Block.from_slenderness(10.0, 0.2)
    a_p, w_p = (float(x) for x in jr.pulse_of_ratios(block, accel_ratio, omega_ratio))
    t_end = 2 * np.pi * n_cycles / w_p
    sol = jr.simulate(jr.RigidModel(block), jr.SinePulse(a_p, w_p, n_cycles))
    ref = sr.solve(block, lambda t: np.where((t >= 0) & (t <= t_end), a_p * np.sin(w_p * np.asarray(t)), 0.0), 0.0, t_end, tstops=[t_end])
    assert sol.ok and bool(sol.overturned) == ref.overturned
    if ref.overturned:
        assert abs(float(sol.t_overturn) - ref.t_overturn) < 1e-6
    else:
        assert abs(float(sol.max_theta) - ref.max_theta) < 1e-6
    g_tan = float(block.uplift_acceleration)
    assert float(sol.t_uplift) == pytest.approx(np.arcsin(g_tan / a_p) / w_p, rel=1e-12)
    dt_da = jax.grad(lambda a: jr.simulate(jr.RigidModel(block), jr.SinePulse(a, w_p, n_cycles)).t_uplift)(a_p)
    assert float(dt_da) == pytest.approx(-g_tan / (a_p**2 * np.sqrt(1 - (g_tan / a_p) ** 2)) / w_p, rel=1e-9)


def test_sine_pulse_and_its_cycles_reach_scenes_files_sweeps_and_spectra(tmp_path):
    """`n_cycles`, declared once (`jaxrock.scene.N_CYCLES`), is a scenes-file column (empty: 1), a
    sweep quantity and a spectrum's pulse parameter: every route gives `simulate`'s number; it is
    refused on a Ricker pulse and off its half cycles, in one line."""
    from jaxrock.analyses.sweep import Sweep, run_chunk

    block = jr.Block.from_slenderness(10.0, 0.2)
    model = jr.RigidModel(block)
    one = lambda a, w, n: float(jr.simulate(model, jr.SinePulse(*jr.pulse_of_ratios(block, a, w), n)).max_theta)
    path = tmp_path / "scenes.csv"
    path.write_text("height,tan_alpha,pulse,accel_ratio,omega_ratio,n_cycles\n10,0.2,sine,2,3,0.5\n10,0.2,sine,2,3,\n10,0.2,sine,2,3,3\n")
    jr.run_scenes(path, tmp_path / "out.csv", progress=False)
    got = [float(r["max_theta"]) for r in csv.DictReader(open(tmp_path / "out.csv"))]
    want = [one(2, 3, n) for n in (0.5, 1.0, 3.0)]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert len(set(np.round(want, 6))) == 3  # the cycles matter
    sw = Sweep.make("rigid", pulse="sine", n_cycles=[0.5, 3.0], accel_ratio=2.0, omega_ratio=3.0)
    np.testing.assert_allclose(run_chunk(sw, 0)["max_theta"].ravel(), [want[0], want[2]], rtol=0, atol=1e-12)
    spec = jr.overturning_spectrum(model, [2.0, 3.0], [1.5, 2.0], pulse="sine", pulse_params={"n_cycles": 2.5}, progress=False,
                                   refine=3)
    assert spec.attrs["pulse"] == "SinePulse" and spec.attrs["n_cycles"] == 2.5
    for i, a in enumerate(spec.accel_ratio):
        for j, w in enumerate(spec.omega_ratio):
            assert abs(spec.max_theta[i, j] - one(a, w, 2.5)) <= 1e-12
    for text, says in (("10,0.2,symmetric,2,3,1\n", "n_cycles.*applies only to pulse sine, not symmetric"),
                       ("10,0.2,sine,2,3,1.3\n", r"n_cycles.*1.3; valid: multiples of 0.5 in \[0.5, 100\]")):
        path.write_text("height,tan_alpha,pulse,accel_ratio,omega_ratio,n_cycles\n" + text)
        with pytest.raises(jr.JaxrockInputError, match=says):
            jr.read_scenes(path)
    with pytest.raises(jr.JaxrockInputError, match="n_cycles applies to pulse sine only, not symmetric"):
        Sweep.make("rigid", n_cycles=2.0, accel_ratio=2.0, omega_ratio=3.0)
    with pytest.raises(jr.JaxrockInputError, match=r"n_cycles = 1.75; valid: multiples of 0.5"):
        Sweep.make("rigid", pulse="sine", n_cycles=[1.0, 1.75], accel_ratio=2.0, omega_ratio=3.0)


def test_sine_pulse_on_the_command_line():
    """`jaxrock simulate --pulse sine --n-cycles N` runs the pulse `simulate` runs (its summary's
    max θ/α and uplift time); `--n-cycles` is refused on a Ricker pulse and on a record, in one
    line, exit 2."""
    from helpers import invoke

    block = jr.Block.from_slenderness(10.0, 0.2)
    r = invoke("simulate", "--pulse", "sine", "--n-cycles", "1.5", "--accel-ratio", "1.5", "--omega-ratio", "3")
    assert r.exit_code == 0, r.output
    sol = jr.simulate(jr.RigidModel(block), jr.SinePulse(*jr.pulse_of_ratios(block, 1.5, 3.0), 1.5))
    printed = float(next(line for line in r.output.splitlines() if line.startswith("max θ/α")).split("=")[1])
    assert abs(printed - float(sol.max_theta)) <= 1e-5 * float(sol.max_theta) and "n_cycles = 1.5" in r.output
    for args, says in ((("--n-cycles", "2"), "--n-cycles applies to --pulse sine only, not symmetric"),
                       (("--record", "elcentro", "--n-cycles", "2"), "--n-cycles applies to --pulse sine only, not --record")):
        r = invoke("simulate", *args)
        assert r.exit_code == 2 and says in r.output, r.output
