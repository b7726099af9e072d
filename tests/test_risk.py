"""From fragility to risk (`jaxrock.analyses.risk`, `jaxrock suite --damage-states --im --hazard`):
damage-state fragilities recovered from synthetic outcomes of known curves, nested states, IDA
curves that flat-line at overturning, intensity measures of the scaled records, and the hazard
integral against its closed form on a real suite."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.special import ndtr

import jaxrock as jr
from jaxrock.analyses.hazard import HazardCurve
from jaxrock.analyses.risk import check_damage_states, ida_curves, risk_analysis
from jaxrock.analyses.suite import run_suite
from helpers import invoke, read_csv


def _synthetic_suite(theta, beta, n_records=40, seed=1):
    """A suite dataset (one model, one column) whose outcomes are drawn from known lognormal curves:
    a run at intensity x = s · PGA reaches state d with P = Φ(ln(x/θ_d)/β), the states nested (one
    uniform number per run decides all of them); its records are sines of spread amplitudes."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 4.0, 0.01)
    amps = np.exp(rng.uniform(np.log(0.5), np.log(4.0), n_records))
    records = [jr.Record(a * np.sin(2 * np.pi * t), 0.01, name=f"r{i}") for i, a in enumerate(amps)]
    pga = np.array([jr.record_measures(r)["pga"] for r in records])
    scale = np.geomspace(0.25, 4.0, 16)
    x = pga[:, None] * scale[None, :]
    u = rng.uniform(size=x.shape)
    reached = {d: u < ndtr(np.log(x / th) / beta) for d, th in theta.items()}
    over = reached[1.0]
    peak = np.where(over, 1.0, np.where(reached[0.5], 0.7, 0.2))
    has = over.any(1)
    least = np.where(has, scale[np.argmax(over, 1)], np.inf)
    dims = ("model", "record", "height", "scale")
    ds = xr.Dataset(
        {"overturned": (dims, over[None, :, None, :]), "max_theta": (dims, peak[None, :, None, :]),
         "status": (dims, np.zeros((1, n_records, 1, scale.size), np.int32)),
         "least_scale": (dims[:-1], least[None, :, None]),
         "windows": (dims[:-1], (over[:, :-1] & ~over[:, 1:]).sum(1)[None, :, None])},
        coords={"model": ["rigid"], "record": [r.name for r in records], "height": [4.0], "scale": scale, "tan_alpha": 0.2})
    return ds, records


def test_damage_states_recover_known_curves_and_the_hazard_closed_form():
    """Two nested states drawn from known curves (θ = 1.5 and 3 m/s², β = 0.4): each fit within 3
    bootstrap standard errors of the truth, medians in the states' order; the mean annual frequency
    against a power-law hazard equals k0 θ^-k exp(k²β²/2) of each fit (Cornell et al. 2002)."""
    truth = {0.5: 1.5, 1.0: 3.0}
    ds, records = _synthetic_suite(truth, 0.4)
    k0, k = 1e-4, 2.5
    risk = risk_analysis(ds, records, damage_states=[0.5, 1.0], ims=["pga"], hazard=HazardCurve.power_law(k0, k), n_boot=300)
    for s, (d, theta) in enumerate(truth.items()):
        f = risk.isel(model=0, height=0, im=0, damage_state=s)
        m_se, b_se = np.nanstd(f.ds_median_boot.values), np.nanstd(f.ds_beta_boot.values)
        assert abs(float(f.ds_median) - theta) < 3 * m_se, (d, float(f.ds_median), m_se)
        assert abs(float(f.ds_beta) - 0.4) < 3 * b_se, (d, float(f.ds_beta), b_se)
        assert m_se < 0.15 * theta  # informative: 640 runs
    med = risk.ds_median.isel(model=0, height=0, im=0).values
    assert med[0] < med[1]
    m, b = risk.ds_median.isel(im=0).values, risk.ds_beta.isel(im=0).values
    np.testing.assert_allclose(risk.maf.values, k0 * m**-k * np.exp(0.5 * k**2 * b**2), rtol=1e-8)
    np.testing.assert_allclose(risk.p_years.values, 1 - np.exp(-50.0 * risk.maf.values), rtol=1e-12)
    lo, hi = risk.maf_band.values[..., 0], risk.maf_band.values[..., 1]
    assert np.all(lo <= risk.maf.values * 1.5) and np.all(hi >= risk.maf.values / 1.5) and np.all(lo < hi)
    # the deaggregation is a density over ln x that holds (nearly) all of the frequency
    lx = np.log(risk.hazard_im.values)
    share = np.trapezoid(risk.deaggregation.values, lx, axis=-1)
    assert np.all(np.abs(share - 1) < 0.02), share


@pytest.fixture(scope="module")
def real_suite():
    """The RM on the packaged records (2h = 2, 4 m, tanα = 0.2), a coarse sweep."""
    records = jr.read_records("builtin")
    ds = run_suite("rigid", records, scale=np.geomspace(0.25, 6.0, 10), height=[2.0, 4.0], tan_alpha=0.2, refine=3,
                      n_boot=50, progress=False)
    return ds, records


def test_risk_of_a_real_suite_is_consistent_with_its_runs(real_suite):
    """On a real suite: the states are nested run by run; the overturning state's fit is the suite's
    own fragility (the same outcomes); each run's Sa(T₁) is the factor × the record's Sa at the
    column's eq.-21 period; the IDA flat-lines at 1 exactly where a run overturned; the truncated-IDA
    fit of every record that overturned is the sample's lognormal (mean and std of ln x) when none
    is censored."""
    from jaxrock.analyses.risk import _outcomes
    from jaxrock.intensity import spectral_acceleration
    from jaxrock.spring import Column

    ds, records = real_suite
    risk = risk_analysis(ds, records, damage_states=[0.1, 0.5, 1.0], ims=["pga", "sa:T1"], n_boot=50)
    reached = _outcomes(ds, [0.1, 0.5, 1.0])
    assert np.all(reached[..., 0] >= reached[..., 1]) and np.all(reached[..., 1] >= reached[..., 2])
    last = risk.isel(damage_state=-1).sel(im="pga")
    np.testing.assert_array_equal(last.ds_median.values, ds.fragility_median.values)
    np.testing.assert_array_equal(last.ds_beta.values, ds.fragility_beta.values)
    for k, h in enumerate(ds.height.values):
        T1 = float(jr.first_period_eq21(h, 0.2, Column.concrete().E, Column.concrete().rho))
        for r, rec in enumerate(records):
            sa = float(spectral_acceleration(rec, np.array([T1]))[0])
            np.testing.assert_allclose(risk.ida_im.sel(im="sa:T1").values[r, k], sa * ds.scale.values, rtol=1e-12)
    edp, over = risk.ida_edp.values, ds.overturned.transpose("model", "record", ...).values
    assert np.all(edp[over] == 1.0) and np.all(edp[~over] <= 1.0)
    least = ds.least_scale.transpose("model", "record", ...).values
    pga = ds.pga.values
    for k in range(ds.sizes["height"]):
        cap = least[0, :, k] * pga
        if np.isfinite(cap).all():
            lx = np.log(cap)
            assert float(risk.ida_median.sel(im="pga")[0, k]) == pytest.approx(np.exp(lx.mean()), rel=1e-6)
            assert float(risk.ida_beta.sel(im="pga")[0, k]) == pytest.approx(lx.std(), rel=1e-6)
    # the percentile curves: within each record's range, between the records' own values
    x, e = risk.ida_im.sel(im="pga").values[:, 0], edp[0, :, 0]
    grid, (p16, p50, p84) = ida_curves(e, x)
    ok = np.isfinite(p50)
    assert ok.any() and np.all(p16[ok] <= p50[ok]) and np.all(p50[ok] <= p84[ok]) and np.all((p50[ok] >= 0) & (p50[ok] <= 1))


def test_damage_states_are_checked():
    assert list(check_damage_states([0.1, 0.5, 1])) == [0.1, 0.5, 1.0]
    for bad in ([0.5, 0.1], [0.0, 1.0], [0.5, 1.5], [0.2, 0.2]):
        with pytest.raises(jr.JaxrockInputError, match="damage states"):
            check_damage_states(bad)


def test_suite_command_writes_fragility_family_ida_and_risk(tmp_path):
    """The issue's command on the packaged records: the damage states' table and figure, pelicun's
    fragility table (its columns; medians in g for Sa), the IDA table and figure, the efficiency
    table, and the risk table whose frequencies are the hazard integral of the fits."""
    from jaxrock.analyses.hazard import mean_annual_frequency
    from jaxrock.geometry import G

    hz = tmp_path / "hazard.csv"
    hz.write_text("sa [g],rate\n0.01,0.2\n0.1,0.01\n0.5,0.001\n1.0,0.0002\n3.0,0.00001\n", encoding="utf-8")
    out = tmp_path / "s"
    r = invoke("suite", "builtin", "--model", "rigid", "--height", "2,4", "--scale", "0.25:6:8", "--refine", "2", "--boot", "40",
               "--damage-states", "0.1,0.5,1", "--im", "sa:T1,pgv", "--hazard", hz, "--out", out, "-q")
    assert r.exit_code == 0, r.output
    for name in ("damage_states.csv", "damage_states.png", "pelicun_fragility.csv", "ida.csv", "ida.png", "ida_fractiles.csv", "efficiency.csv",
                 "efficiency.md", "risk.csv", "risk.md", "deaggregation.png"):
        assert (out / name).is_file(), name
    rows = read_csv(out / "damage_states.csv")
    assert len(rows) == 2 * 2 * 3  # heights × measures × states
    pel = read_csv(out / "pelicun_fragility.csv")
    assert {"ID", "Demand-Type", "Demand-Unit", "LS1-Family", "LS1-Theta_0", "LS1-Theta_1", "LS3-Theta_0"} <= set(pel[0])
    sa_rows = [p for p in pel if p["Demand-Type"].startswith("Peak Spectral Acceleration|")]
    assert len(sa_rows) == 2 and all(p["Demand-Unit"] == "g" for p in sa_rows)
    ds_sa = [row for row in rows if row["im"] == "sa:T1"]
    for p in sa_rows:
        mine = [row for row in ds_sa if f"height={float(row['height']):g}" in p["ID"]]
        for s, row in enumerate(mine):
            assert float(p[f"LS{s + 1}-Theta_0"]) == pytest.approx(float(row["median"]) / G, rel=1e-12)
    risk = read_csv(out / "risk.csv")
    assert len(risk) == 2 * 3
    curve = HazardCurve.read(hz)
    for row, d in zip(risk, rows[:3] + rows[6:9]):
        assert row["damage_state"] == d["damage_state"] and d["im"] == "sa:T1"
        lam = float(mean_annual_frequency(np.array(float(d["median"])), np.array(float(d["beta"])), curve))
        assert float(row["maf"]) == pytest.approx(lam, rel=1e-12)
    assert "Most efficient" in (out / "efficiency.md").read_text(encoding="utf-8")
    assert "MAF" in r.output or "risk" in r.output


@pytest.mark.parametrize("args, words", [
    (["--damage-states", "0.5,0.1"], "damage states"),
    (["--damage-states", "0,1"], "damage states"),
    (["--im", "sa:-1"], "sa:-1"),
    (["--im", "pga,pga"], "pga"),
    (["--years", "0"], "--years"),
    (["--hazard", "nowhere.csv"], "nowhere.csv"),
    (["--hazard", "power:1,-2"], "power"),
    (["--im", "scale", "--hazard", "power:1e-4,2"], "--hazard"),
])
def test_suite_risk_options_refuse_bad_input_in_one_line(tmp_path, args, words):
    r = invoke("suite", *args, "--out", tmp_path / "s", "-q")
    assert r.exit_code == 2, r.output
    assert words in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not (tmp_path / "s" / "rigid.zarr").exists()
