"""Record suites: the intensity measures of the records (against independent computations), the
least overturning scale of each record (against a brute-force scale sweep) and the lognormal
fragility fit (recovering a known curve)."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

import jaxrock as jr
from jaxrock.analyses import fragility
from jaxrock import G
from jaxrock.results import STATUS_NAMES
from helpers import invoke

RECORDS = Path(jr.__file__).parent / "data" / "records"  # the packaged records (jaxrock/data/README.md)


def _naive_at2_g(path: Path) -> np.ndarray:
    """Every whitespace token after the 4 header lines (values in g), read without jaxrock."""
    return np.array(" ".join(path.read_bytes().decode().split("\n")[4:]).split(), dtype=float)


# -- intensity measures ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["A-TIN000.AT2", "ARL360.at2", "B-ELC000.AT2", "elCentro_peknold.AT2"])
def test_measures_match_independent_computation(name):
    path = RECORDS / name
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


# -- least overturning scale -------------------------------------------------------------------------
def _records(*names):
    return jr.read_records([*names, "elcentro"])


def test_least_scale_brackets_and_flags():
    """Two records × 2 sizes (RM, models vmapped): each bracket's ends, run alone, overturn (least)
    and do not (low); its width is the sweep's step / 2^refine; the least lies in the sweep's first
    overturning interval; `windows` counts the sweep's own turns back to standing."""
    from jaxrock.analyses.sweep import run_values

    records = _records("arl360")
    coarse = np.linspace(0.25, 4.0, 16)
    sweep = jr.Sweep.make("rigid", records=records, height=[1.0, 4.0], tan_alpha=0.2, scale=coarse)
    ds = jr.least_overturning_scale(sweep, refine=6, progress=False)
    assert (ds.worst_status == 0).all()
    least, low, over = ds.least_scale.values, ds.bracket_low.values, ds.overturned.values
    found = np.isfinite(least)
    assert found.sum() >= 3 and np.array_equal(found, over.any(-1))
    np.testing.assert_allclose(ds.bracket_width.values[found], 0.25 / 2**6, rtol=1e-12)
    first = coarse[np.argmax(over, -1)]
    assert np.all((least[found] <= first[found]) & (least[found] > first[found] - 0.25 - 1e-12))
    assert np.array_equal(ds.windows.values, [[sum(o[i] and not o[i + 1] for i in range(15)) for o in row] for row in over])
    for r in range(len(records)):
        cells = sweep.values_at((slice(0, 2),), ("height",))
        ok = found[r]
        for ends, expect in ((least[r][ok], True), (low[r][ok], False)):
            out = run_values(sweep, {k: v[ok] for k, v in cells.items()} | {"record": np.full(ok.sum(), r), "scale": ends})
            assert np.all(out["overturned"] == expect), (records[r].name, ends, out["overturned"])


def test_bisection_is_kept_beside_the_store(tmp_path, monkeypatch):
    """With a store, each record's finished bisection is kept (`<store>.bisection.npz`): a rerun
    runs nothing and returns the same numbers; one with another `refine` bisects afresh."""
    from jaxrock.analyses import suite

    sweep = jr.Sweep.make("rigid", records=[jr.el_centro()], height=[1.0, 4.0], tan_alpha=0.2, scale=np.linspace(0.5, 3, 6))
    first = jr.least_overturning_scale(sweep, tmp_path / "s.zarr", refine=4, progress=False)
    assert (tmp_path / "s.zarr.bisection.npz").is_file()
    monkeypatch.setattr(suite, "run_values", lambda *a, **k: pytest.fail("a kept bisection was run again"))
    again = jr.least_overturning_scale(sweep, tmp_path / "s.zarr", refine=4, progress=False)
    assert again.least_scale.equals(first.least_scale) and again.bracket_low.equals(first.bracket_low)
    with pytest.raises(pytest.fail.Exception, match="run again"):
        jr.least_overturning_scale(sweep, tmp_path / "s.zarr", refine=5, progress=False)


def test_least_scale_equals_brute_force_scan_of_its_bracket():
    """A brute-force scan of each cell's first overturning interval of the sweep, at the bracket
    width (the dyadic points the bisection may visit, run as one batch of their own): the bisected
    least factor is a point where the scan turns from standing to overturned, and the scan's first
    if the scan turns once. (Overturning is not monotone in the factor at any step: between 0.60 and
    0.72 at step 0.0025 the outcome of ARL360 on a 0.5-m column, tanα = 0.15, turns 14 times.)"""
    from jaxrock.analyses.sweep import run_values

    records = _records("arl360")
    coarse = np.linspace(0.25, 4.0, 16)
    sweep = jr.Sweep.make("rigid", records=records, height=[0.5, 1.0], tan_alpha=0.15, scale=coarse)
    refine = 5
    ds = jr.least_overturning_scale(sweep, refine=refine, progress=False)
    width = 0.25 / 2**refine
    checked = 0
    for r in range(len(records)):
        for i, h in enumerate((0.5, 1.0)):
            least = float(ds.least_scale[r, i])
            if not np.isfinite(least):
                continue
            k = int(np.argmax(ds.overturned.values[r, i]))
            start = coarse[k - 1] if k > 0 else 0.0
            scan = start + width * np.arange(1, 2**refine + 1)  # exact dyadic values: the bisection's midpoints
            out = run_values(sweep, {"height": np.full(scan.size, h), "tan_alpha": np.full(scan.size, 0.15),
                                     "record": np.full(scan.size, r), "scale": scan})["overturned"].astype(bool)
            j = int(np.flatnonzero(scan == least)[0])
            assert out[j] and (j == 0 or not out[j - 1]), (records[r].name, h, least, out)
            if out[-1] and (out[:-1] <= out[1:]).all():  # the scan turns once: the least is its first
                assert least == scan[np.argmax(out)]
            checked += 1
    assert checked >= 3, checked


# -- fragility -----------------------------------------------------------------------------------------
def _synthetic(n_records, median=0.6, beta=0.4, seed=1):
    """Outcomes of `n_records` records at 15 intensities each, drawn from a known lognormal."""
    rng = np.random.default_rng(seed)
    x = np.tile(np.geomspace(0.1, 3.0, 15), (n_records, 1)) * rng.lognormal(0.0, 0.2, (n_records, 1))
    y = rng.random(x.shape) < fragility.probability(x, median, beta)
    return x, y, np.repeat(np.arange(n_records), 15).reshape(x.shape)


def test_fragility_fit_recovers_a_known_lognormal():
    from scipy.optimize import minimize
    from scipy.stats import norm

    x, y, g = _synthetic(40)
    fit = jr.fit_lognormal(x, y, g, n_boot=400)
    lo, hi = fit["median_ci"]
    assert lo < 0.6 < hi and lo < fit["median"] < hi
    lo, hi = fit["beta_ci"]
    assert lo < 0.4 < hi and lo < fit["beta"] < hi
    # the same likelihood maximised by a general-purpose optimiser
    nll = lambda p: -np.sum(np.where(y, norm.logcdf((np.log(x) - p[0]) / np.exp(p[1])),
                                     norm.logcdf(-(np.log(x) - p[0]) / np.exp(p[1]))))
    ref = minimize(nll, [0.0, np.log(0.5)], method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000}).x
    assert fit["median"] == pytest.approx(np.exp(ref[0]), rel=1e-6)
    assert fit["beta"] == pytest.approx(np.exp(ref[1]), rel=1e-6)
    # consistency: 100 times the records, 10 times narrower
    big = jr.fit_lognormal(*_synthetic(4000, seed=2), n_boot=0)
    assert big["median"] == pytest.approx(0.6, rel=0.02) and big["beta"] == pytest.approx(0.4, rel=0.04)
    # deterministic: the same seed, the same bits
    again = jr.fit_lognormal(x, y, g, n_boot=400)
    assert np.array_equal(again["median_boot"], fit["median_boot"]) and np.array_equal(again["beta_boot"], fit["beta_boot"])


def test_fragility_fit_takes_probabilities_as_their_ensembles():
    """An uncertain observation enters as the fraction q of its ensemble that overturned: the fit
    on fractions is the fit on the ensembles' runs themselves (each of 4 runs an observation, the
    bootstrap still over records), bools are the special case q ∈ {0, 1}, and a value outside
    [0, 1] is refused."""
    x, y, g = (a.ravel() for a in _synthetic(40))
    rng = np.random.default_rng(5)
    runs = np.where(rng.random(x.size) < 0.3, rng.random((4, x.size)) < 0.5, np.broadcast_to(y, (4, x.size)))  # 4 perturbed runs each
    q = runs.mean(0)
    assert np.any((q > 0) & (q < 1))
    frac = jr.fit_lognormal(x, q, g, n_boot=50)
    each = jr.fit_lognormal(np.tile(x, 4), runs.ravel(), np.tile(g, 4), n_boot=50)
    for key in ("median", "beta"):
        assert frac[key] == pytest.approx(each[key], rel=1e-9), key
    np.testing.assert_allclose(frac["median_boot"], each["median_boot"], rtol=1e-8)
    assert frac["n_overturned"] == pytest.approx(q.sum()) and frac["n"] == x.size
    assert jr.fit_lognormal(x, y.astype(float), g, n_boot=0)["median"] == pytest.approx(jr.fit_lognormal(x, y, g, n_boot=0)["median"], rel=1e-12)
    with pytest.raises(jr.JaxrockInputError, match="probability in"):
        jr.fit_lognormal(x, q * 1.5, g)


def test_an_uncertain_verdict_becomes_its_ensembles_probability():
    """El Centro on a 1.5 m column (tanα 0.2), factors around 1.95× its uplift factor, where the
    verdict turns at ×(1 ± 1e-9): `overturning_probability` keeps each certain verdict and gives
    each uncertain one the fraction of its 16 perturbed runs that overturn — the same fraction as
    `run_batch` of those factors directly, strictly between 0 and 1 for at least one run; the
    fragility fitted on them counts the probabilities."""
    rec = jr.el_centro()
    uplift = 9.81 * 0.2 / float(np.max(np.abs(np.asarray(rec.acc))))
    sweep = jr.Sweep.make("rigid", records=[rec], height=1.5, tan_alpha=0.2, scale=uplift * np.array([1.2, 1.95, 2.6]),
                          sensitivity=True)
    ds = jr.least_overturning_scale(sweep, refine=0, progress=False)
    doubt = ds.uncertain.values
    assert doubt.any()
    p = jr.overturning_probability(sweep, ds, 16)
    np.testing.assert_array_equal(p[~doubt], ds.overturned.values[~doubt].astype(float))
    model = jr.RigidModel(jr.Block.from_slenderness(1.5, 0.2))
    for i in np.flatnonzero(doubt.ravel()):
        k = float(ds.scale.values[i]) * (1 + 1e-7 * np.linspace(-1, 1, 16))
        direct = jr.run_batch(model, jax.vmap(rec.scaled)(jnp.asarray(k)))
        assert p.ravel()[i] == pytest.approx(np.mean(np.asarray(direct.overturned)), abs=1 / 16 + 1e-12)  # batch neighbours' last bits
    assert np.any((p > 0) & (p < 1)), p
    ds["p_overturn"] = (sweep.dims, p)
    frag = jr.analyses.suite.suite_fragility(ds, jr.suite_measures(sweep.records), "scale", n_boot=0)
    assert float(frag.n_overturned.values.ravel()[0]) == pytest.approx(p.sum())


def test_fragility_edge_cases():
    x = np.geomspace(0.1, 3.0, 20)
    none = jr.fit_lognormal(x, np.zeros(20, bool), n_boot=10)
    assert np.isnan(none["median"]) and np.isnan(none["beta"])
    sep = jr.fit_lognormal(x, x > 1.0, n_boot=0)  # one intensity separates the outcomes exactly
    assert sep["beta"] == fragility.BETA_MIN
    assert sep["median"] == pytest.approx(np.sqrt(x[x <= 1.0].max() * x[x > 1.0].min()), rel=1e-12)
    with pytest.raises(jr.JaxrockInputError, match="im"):
        jr.fit_lognormal(-x, x > 1.0)


def test_three_models_on_one_suite_agree():
    """The RM, the quasi-rigid SM and the flexible SM on the same suite (El Centro, 2h = 4 m,
    tanα = 0.2): none uplifts below the closed-form threshold (factor × PGA ≤ g tanα: 0.639 for
    El Centro); every run of the RM and the quasi-rigid SM ends ok; the flexible SM's ok or
    `inaccurate` (issue 29: at factors 1 and 1.5 its peak is ill-conditioned — generalized-α at
    1e-6…1e-9 gives 0.340, 0.451, 0.416, 0.317 at factor 1 — and its default says so); the least
    overturning factors agree within 10 % (1.57, 1.54 and 1.52 at refine 5, issue 27's closing
    note), and the fits share the records' measures."""
    from jaxrock.analyses.suite import run_suite

    scale = np.array([0.25, 0.5, 1.0, 1.25, 1.5, 1.75, 2.0])
    ds = run_suite(("rigid", "spring", "spring-flexible"), [jr.el_centro()], scale=scale, height=4.0, tan_alpha=0.2, refine=3,
                   im="pga", n_boot=20, progress=False)
    assert (ds.worst_status.sel(model=["rigid", "spring"]) == 0).all()
    assert ds.worst_status.sel(model="spring-flexible").isin([0, STATUS_NAMES.index("inaccurate")]).all()
    threshold = G * 0.2 / float(ds.pga[0])
    assert threshold == pytest.approx(0.639, abs=1e-3)
    assert not ds.uplifted.sel(model="rigid").values[..., scale < threshold].any()
    assert (ds.max_theta.sel(model="rigid").values[..., scale < threshold] == 0).all()
    assert ds.uplifted.sel(model="rigid").values[..., scale > threshold].all()
    least = ds.least_scale.values.ravel()
    assert np.isfinite(least).all() and least.max() / least.min() < 1.10, least


# -- the command ---------------------------------------------------------------------------------------
def test_suite_command_writes_the_dataset_tables_and_figures(tmp_path):
    """`jaxrock suite`: the dataset holds the measures, the sweep, the least factors and the fit;
    the fragility table is the fit of the stored outcomes at factor × PGA; the store resumes."""
    import xarray as xr

    from helpers import invoke, read_csv

    recs = ["arl360"]
    args = ("suite", *recs, "elcentro", "--model", "rigid", "--height", "1,4", "--scale", "0.5:3:6", "--refine", "3",
            "--boot", "50", "--ensemble", "8", "--out", tmp_path / "s", "-q")
    r = invoke(*args)
    assert r.exit_code == 0, r.output
    for name in ("suite.zarr", "least_scale.csv", "least_scale.png", "fragility.csv", "fragility.md", "fragility.png", "rigid.zarr"):
        assert (tmp_path / "s" / name).exists(), name
    ds = xr.open_zarr(tmp_path / "s" / "suite.zarr").load()
    assert list(ds.model.values) == ["rigid"] and ds.sizes["record"] == len(recs) + 1
    rows = read_csv(tmp_path / "s" / "fragility.csv")
    for i, row in enumerate(rows):
        one = ds.isel(model=0, height=i)
        x = one.scale.values[None, :] * one.pga.values[:, None]
        # the outcomes: each run's verdict, an uncertain one's ensemble fraction (--ensemble)
        p = one.p_overturn.values
        np.testing.assert_array_equal(p[~one.uncertain.values], one.overturned.values[~one.uncertain.values])
        fit = jr.fit_lognormal(x, p, np.repeat(np.arange(x.shape[0])[:, None], x.shape[1], 1), n_boot=50)
        assert float(row["median"]) == fit["median"] and float(row["beta"]) == fit["beta"]
        assert float(row["n_overturned"]) == pytest.approx(p.sum())
    table = [line for line in (tmp_path / "s" / "fragility.md").read_text(encoding="utf-8").splitlines() if line.startswith("|")]
    assert len(table) == 2 + len(rows) and len({line.count("|") for line in table}) == 1 and "|  |" not in table[0], table
    least_rows = read_csv(tmp_path / "s" / "least_scale.csv")
    assert all(np.isfinite(float(row["least_scale"])) == (row["bracket_low"] != "nan") for row in least_rows)
    # every run's verdict judged (the suite's default): its flag is its own numbers', and a least
    # factor decided by an uncertain run of the sweep says so, in the dataset, the table and the summary
    one = ds.isel(model=0)
    np.testing.assert_array_equal(one.uncertain.values, jr.verdict_uncertain(one.sensitivity.values, one.max_theta.values,
                                                                             one.overturned.values))
    assert np.all(np.isfinite(one.sensitivity.values))
    decided = (one.uncertain & (one.scale <= one.least_scale)).any("scale").values
    assert np.all(one.least_scale_uncertain.values[decided])
    assert [int(row["uncertain"]) for row in least_rows] == [int(x) for x in one.least_scale_uncertain.values.ravel()]
    assert f"verdict uncertain: {int(one.least_scale_uncertain.sum())} of {one.least_scale.size} least factor(s)" in r.output, r.output
    again = invoke(*args)  # the sweep's store is resumed: the same numbers
    assert again.exit_code == 0, again.output
    assert xr.open_zarr(tmp_path / "s" / "suite.zarr").load().least_scale.equals(ds.least_scale)


@pytest.mark.parametrize("args, words", [
    (["--model", "rigid,block"], "--model"),
    (["--im", "sa"], "im"),
    (["--scale", "2"], "--scale"),
    (["--refine", "-1"], "--refine"),
    (["--height", "0"], "height"),
    (["--boot", "0"], "--boot"),
    (["nowhere/x.AT2"], "records"),
    (["--ensemble", "-1"], "--ensemble"),
    (["--ensemble", "4", "--no-sensitivity"], "--ensemble"),
])
def test_suite_command_refuses_bad_input_in_one_line(tmp_path, args, words):
    from helpers import invoke

    r = invoke("suite", *args, "--out", tmp_path / "s", "-q")
    assert r.exit_code == 2, r.output
    assert words in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not (tmp_path / "s" / "rigid.zarr").exists()


def test_a_list_file_names_a_suite(tmp_path):
    """A `.list` file: one record file, folder or 'elcentro' per line, relative to the list, `#`
    comments; the same records as naming them directly. A missing entry is refused with its line."""
    from helpers import write

    rec = write(tmp_path / "one.txt", "0 0.0\n0.01 0.1\n0.02 -0.05\n")
    lst = write(tmp_path / "suite.list", "# my suite\none.txt\n\nelcentro   # the packaged record\n")
    recs = jr.read_records([lst])
    assert [r.name for r in recs] == ["one", "El Centro 1940 NS"]
    assert np.array_equal(np.asarray(recs[0].acc), np.asarray(jr.read_record(rec).acc))
    write(tmp_path / "bad.list", "one.txt\nmissing.AT2\n")
    with pytest.raises(jr.JaxrockInputError, match="line 2: missing.AT2"):
        jr.read_records([tmp_path / "bad.list"])


def test_interrupted_suite_resumes_to_the_same_numbers(tmp_path):
    """A real `jaxrock suite` process stopped by SIGINT after its first record's chunk (in the sweep
    or, warm, already in the bisection): exit 130, what the store keeps and the resume command; the
    same command then finishes with the numbers of an uninterrupted run."""
    import signal

    import xarray as xr

    from helpers import Watch, jaxrock_process

    args = ("suite", "arl360", "elcentro_peknold", "elcentro", "--model", "rigid",
            "--height", "1,4", "--scale", "0.25:4:16", "--refine", "3", "--boot", "20")
    whole = jaxrock_process(*args, "--out", tmp_path / "whole", "-q", cwd=tmp_path)
    assert whole.wait(300) == 0, whole.stderr.read()
    w = Watch(jaxrock_process(*args, "--out", tmp_path / "cut", cwd=tmp_path))
    w.wait_for(r"\b32/96")
    w.proc.send_signal(signal.SIGINT)
    rc, out, err = w.finish()
    assert rc == 130 and "interrupted: the sweeps kept in" in err and "resume with: jaxrock suite" in err, err[-500:]
    kept = int(xr.open_zarr(tmp_path / "cut" / "rigid.zarr", chunks=None).chunk_done.sum())
    assert 1 <= kept <= 3, kept  # the stop lands in the sweep (its finished chunks kept) or in the bisection (rerun)
    again = jaxrock_process(*args, "--out", tmp_path / "cut", "-q", cwd=tmp_path)
    assert again.wait(300) == 0, again.stderr.read()
    a, b = (xr.open_zarr(tmp_path / d / "suite.zarr", chunks=None) for d in ("whole", "cut"))
    for name in ("least_scale", "bracket_low", "overturned", "fragility_median", "fragility_beta", "pga"):
        assert a[name].equals(b[name]), name


def test_records_without_motion_or_too_short_for_a_duration(tmp_path):
    """Issue 52: a 2-sample or an all-zero record in a suite was an IndexError inside eqsig's
    significant duration. D5-95 is NaN where undefined (every other measure is still given), and
    a record without motion is refused by the suite in one line, before any run."""
    from jaxrock.intensity import record_measures
    from jaxrock.io.records import read_record

    two = jr.Record(np.array([0.1, 0.2]) * jr.G, 0.01, name="two")
    m = record_measures(two)
    assert np.isnan(m["d5_95"]) and m["pga"] == pytest.approx(0.2 * jr.G) and m["duration"] == pytest.approx(0.01)
    zero = tmp_path / "zero.txt"
    zero.write_text("".join(f"{i * 0.01:.2f} 0\n" for i in range(200)))
    assert np.isnan(record_measures(read_record(zero))["d5_95"])
    r = invoke("suite", zero, "--model", "rigid", "--height", 2, "--scale", "1,2", "--out", tmp_path / "s", "-q", "--yes")
    assert r.exit_code == 2 and "zero: every sample is 0 (no ground motion)" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
