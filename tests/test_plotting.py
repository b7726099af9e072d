"""Plots: what they draw is the data they were given (boundaries, histories, record spectra).
No pixels are compared; the drawn lines are read back from the axes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import jaxrock as jr  # noqa: E402
from jaxrock.plotting import (  # noqa: E402
    plot_boundaries,
    plot_history,
    plot_record_spectrum,
    plot_spectra_grid,
    plot_spectrum,
)
from jaxrock.analyses.spectra import RecordSpectrum, Spectrum  # noqa: E402


def _spectrum(shift=0.0, status_bad=False):
    """A synthetic spectrum with the shape of the paper's: rocks above a_p = g tanα, overturns
    above a line rising with ω_p/p."""
    w = np.linspace(1.0, 10.0, 12)
    a = np.linspace(0.5, 8.0, 10)
    W, A = np.meshgrid(w, a)
    uplifted = A >= 1.0 + shift
    over = A >= 1.2 + 0.6 * W + shift
    theta = np.where(over, 1.0, np.where(uplifted, np.clip((A - 1) / (1.2 + 0.6 * W - 1), 0, 0.99), 0.0))
    status = np.zeros(A.shape, np.int32)
    if status_bad:
        status[3, 4] = 3
    return Spectrum(
        omega_ratio=w, accel_ratio=a, max_theta=theta, overturned=over, uplifted=uplifted, status=status,
        t_overturn=np.where(over, 1.0, np.inf), t_uplift=np.where(uplifted, 0.0, np.inf), n_impacts=np.zeros(A.shape, np.int64),
        sensitivity=np.full(A.shape, np.nan), uncertain=np.zeros(A.shape, bool),
        attrs={"model": "RigidModel", "tan_alpha": 0.2, "height": 10.0, "pulse": "RickerPulse", "alpha": 0.197, "p": 1.2},
    )


def _cells(s, rows: slice, cols: slice):
    """The spectrum's sub-grid of `rows` (a_p) × `cols` (ω_p)."""
    grid = {k: getattr(s, k)[rows, cols] for k in (*jr.results.OUTPUTS, "status")}
    return Spectrum(omega_ratio=s.omega_ratio[cols], accel_ratio=s.accel_ratio[rows], **grid, attrs=s.attrs)


def _lines_by_style(ax):
    return [(ln.get_linestyle(), ln.get_xdata(), ln.get_ydata()) for ln in ax.get_lines()]


def _has_line(ax, x, y, style=None):
    for ls, xd, yd in _lines_by_style(ax):
        if style is not None and ls != style:
            continue
        if len(xd) == len(x) and np.allclose(xd, x) and np.allclose(np.asarray(yd, float), y, equal_nan=True):
            return True
    return False


def test_plot_spectrum_draws_the_spectrum_boundaries(tmp_path):
    s = _spectrum(status_bad=True)
    fig = plot_spectrum(s, path=tmp_path / "s.png")
    ax = fig.axes[0]
    assert _has_line(ax, s.omega_ratio, s.uplift_boundary, "-")
    assert _has_line(ax, s.omega_ratio, s.overturn_boundary, "--")
    np.testing.assert_array_equal(fig.jaxrock_data["uplift"], s.uplift_boundary)
    np.testing.assert_array_equal(fig.jaxrock_data["overturn"], s.overturn_boundary)
    # the boundaries are where the data says: first uplifting / overturning row per column
    assert np.all(s.uplift_boundary >= 1.0) and np.all(s.uplift_boundary < 1.0 + 7.5 / 9 + 1e-12)
    assert ax.get_xlabel() == r"$\omega_p/p$" and "tan" in ax.get_ylabel()
    assert any(r"\theta_{\max}/\alpha" in a.get_ylabel() for a in fig.axes[1:])  # colourbar
    assert (tmp_path / "s.png").stat().st_size > 1000
    # the bad-status cell is marked
    assert _has_line(ax, [s.omega_ratio[4]], [s.accel_ratio[3]])
    assert fig.jaxrock_data["uncertain"] == 0 and "verdict uncertain" not in [t.get_text() for t in ax.get_legend().get_texts()]
    plt.close(fig)


def test_plot_spectrum_rings_the_uncertain_verdicts():
    """Cells whose verdict rounding could flip (`uncertain`) are ringed, each where it is, and the
    legend names them."""
    import equinox as eqx

    s = _spectrum()
    doubt = np.zeros(s.max_theta.shape, bool)
    doubt[[6, 7], [2, 9]] = True
    s = eqx.tree_at(lambda x: x.uncertain, s, doubt)
    fig = plot_spectrum(s)
    ax = fig.axes[0]
    assert fig.jaxrock_data["uncertain"] == 2
    assert _has_line(ax, s.omega_ratio[[2, 9]], s.accel_ratio[[6, 7]])
    assert "verdict uncertain" in [t.get_text() for t in ax.get_legend().get_texts()]
    plt.close(fig)


def test_plot_spectrum_on_given_axes_and_degenerate_grid():
    fig, ax = plt.subplots()
    s = _spectrum()
    one = _cells(s, slice(None), slice(0, 1))
    assert plot_spectrum(one, ax=ax, title="one column") is fig
    assert ax.get_title() == "one column"
    plt.close(fig)


@pytest.mark.parametrize("i", [0, 3, 9])  # below uplift, rocking, overturned
def test_plot_spectrum_of_one_cell_draws_it_and_writes_its_value(i):
    """A 1 × 1 grid drew an empty frame (a one-point axis gives pcolormesh no cell width): now the
    cell is drawn ±5 % around its point, in its colour, with its value written on it."""
    s = _spectrum()
    one = _cells(s, slice(i, i + 1), slice(4, 5))
    fig = plot_spectrum(one)
    ax = fig.axes[0]
    cell = ax.collections[0]
    assert np.asarray(cell.get_array()).ravel().tolist() == [pytest.approx(float(one.max_theta[0, 0]))]
    x0, x1 = ax.get_xlim()
    assert x0 < one.omega_ratio[0] < x1 and x1 - x0 == pytest.approx(0.1 * one.omega_ratio[0])
    text = " ".join(t.get_text() for t in ax.texts)
    assert f"θ_max/α = {float(one.max_theta[0, 0]):.4g}" in text
    assert ("overturned" in text) == bool(one.overturned[0, 0])
    plt.close(fig)


def test_grid_and_boundaries_figures(tmp_path):
    s1, s2 = _spectrum(), _spectrum(shift=0.5)
    fig = plot_spectra_grid([s1, s2, s1], ["RM", "SM", "SM + masses"], path=tmp_path / "g.png")
    titles = [a.get_title() for a in fig.axes]
    assert {"RM", "SM", "SM + masses"} <= set(titles)
    for ax, s in zip(fig.axes[:3], (s1, s2, s1)):
        assert _has_line(ax, s.omega_ratio, s.overturn_boundary, "--")
    plt.close(fig)
    fig = plot_boundaries([s1, s2], ["rigid", "flexible"], path=tmp_path / "b.png")
    ax = fig.axes[0]
    for s in (s1, s2):
        assert _has_line(ax, s.omega_ratio, s.uplift_boundary, "-")
        assert _has_line(ax, s.omega_ratio, s.overturn_boundary, "--")
    assert (tmp_path / "b.png").exists()
    plt.close(fig)


def test_plot_history_draws_theta_over_alpha_and_ground_motion(tmp_path):
    ts = np.linspace(-1.0, 3.0, 50)
    theta = 0.1 * np.sin(ts)
    sol = jr.Solution(
        max_theta=np.float64(0.5), overturned=np.bool_(True), t_overturn=np.float64(2.0), uplifted=np.bool_(True),
        t_uplift=np.float64(-0.5), n_impacts=np.int32(1), sensitivity=np.float64(np.nan), uncertain=np.False_, status=jr.Status.ok, ts=ts,
        history={"theta": theta},
    )
    exc = jr.RickerPulse(3.0, 4.0)
    alpha = 0.2
    fig = plot_history(sol, exc, alpha=alpha, path=tmp_path / "h.png")
    ax0, ax1 = fig.axes[:2]
    assert _has_line(ax0, ts, theta / alpha)
    ug = np.array([float(exc(t)) for t in ts]) / jr.G
    assert _has_line(ax1, ts, ug)
    assert ax0.get_ylabel() == r"$\theta/\alpha$"
    assert fig.jaxrock_data["t_overturn"] == 2.0
    assert any(list(ln.get_xdata()) == [2.0, 2.0] for ln in ax0.get_lines())  # overturn marker
    plt.close(fig)
    no_hist = jr.Solution(
        max_theta=np.float64(0.5), overturned=np.bool_(False), t_overturn=np.float64(np.inf), uplifted=np.bool_(True),
        t_uplift=np.float64(0.0), n_impacts=np.int32(1), sensitivity=np.float64(np.nan), uncertain=np.False_, status=jr.Status.ok,
    )
    with pytest.raises(ValueError, match="time history"):
        plot_history(no_hist, exc)


def test_plot_record_spectrum_lines(tmp_path):
    rs = RecordSpectrum(height=np.array([2.0, 5.0, 10.0]), scale=np.array([1.5, 2.5, np.inf]),
                        bracket_low=np.array([1.4, 2.4, np.nan]), attrs={"model": "RigidModel", "tan_alpha": 0.2, "tan_alpha_base": 0.2})
    fig = plot_record_spectrum([rs], ["RM"], path=tmp_path / "r.png")
    ax = fig.axes[0]
    assert _has_line(ax, [2.0, 5.0], [1.5, 2.5])  # the finite points; inf is marked apart
    plt.close(fig)
    fig = plot_record_spectrum([rs], ["RM"], x="p")
    p = np.sqrt(3 * jr.G / (4 * 0.5 * rs.height * np.sqrt(1 + 0.2**2)))
    np.testing.assert_allclose(fig.jaxrock_data["lines"][0]["x"], p)
    block = jr.Block.from_slenderness(5.0, 0.2)
    assert p[1] == pytest.approx(float(block.p))
    plt.close(fig)
