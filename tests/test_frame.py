"""The rocking frame (`jaxrock.RockingFrame`, Makris & Vassiliou 2013) against references written
here from the masses and the geometry: Lagrange's equation of N columns and a translating cap
beam (positions → energies → θ̈ by `jax.grad`), the impact by angular momentum about the new
pivots with vectors, whole runs against the SciPy reference given those numbers; the uplift level
independent of the beam, γ → 0 the solitary column, the heavier beam the more stable, gradients
against central differences, and the command line's `--model frame`."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.numerics import scipy_rigid

from helpers import invoke

G = 9.81  # m/s², SPEC


def _frame_mechanics(h, b, n_columns, m, m_beam, beam_offset):
    """Energies of N columns (half-height h, half-width b, mass m each, rocking on the corner of
    side s = +1 at the origin) and a beam of mass m_b riding on the top corner diagonal to each
    pivot, its centre `beam_offset` beside it: (mass M(θ), ∂V/∂θ, ∂X/∂θ) with V the gravity
    potential at g + üv (per unit (g + üv)) and X the mass-weighted horizontal position."""
    pivot = jnp.array([b, 0.0])  # the corner of side +1; θ > 0 rotates the column about it

    def rot(theta, r):  # rigid rotation by θ about the pivot (clockwise for θ > 0: the top moves to +x)
        c, s = jnp.cos(theta), jnp.sin(theta)
        d = r - pivot
        return pivot + jnp.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])

    centroid = lambda th: rot(th, jnp.array([0.0, h]))
    contact = lambda th: rot(th, jnp.array([-b, 2 * h]))  # the top corner diagonal to the pivot
    beam = lambda th: contact(th) + jnp.array([beam_offset, 0.0])  # translates with the contact point
    i_c = m * (4 * h * h + 4 * b * b) / 12

    def mass(th):
        vc, vb = jax.jacfwd(centroid)(th), jax.jacfwd(beam)(th)
        return n_columns * (i_c + m * vc @ vc) + m_beam * vb @ vb

    V = lambda th: n_columns * m * centroid(th)[1] + m_beam * beam(th)[1]
    X = lambda th: n_columns * m * centroid(th)[0] + m_beam * beam(th)[0]
    return mass, jax.grad(V), jax.grad(X), centroid, beam, pivot, i_c


def _lagrange_acceleration(h, b, gamma, theta, ug, uv, beam_offset=0.3):
    """θ̈ on side +1 by Lagrange: M θ̈ = −(g + üv) ∂V/∂θ − üg ∂X/∂θ (M is constant: rigid rotations)."""
    n, m = 3, 1.0
    mass, dV, dX, *_ = _frame_mechanics(h, b, n, m, gamma * n * m, beam_offset)
    return float((-(G + uv) * dV(theta) - ug * dX(theta)) / mass(theta))


def _momentum_eta(h, b, gamma, beam_offset=0.3):
    """θ̇₂/θ̇₁ across an impact from angular momentum about each column's new pivot O′ = (−b, 0),
    the beam's share of the impulse acting at the new contact corner D′ (above the old pivot)."""
    n, m = 4, 1.0
    m_b = gamma * n * m
    mass, _, _, centroid, beam, pivot, i_c = _frame_mechanics(h, b, n, m, m_b, beam_offset)
    o_new, d_new = jnp.array([-b, 0.0]), jnp.array([b, 2 * h])
    cross = lambda r, v: r[0] * v[1] - r[1] * v[0]
    # before: rotating about (b, 0) at θ = 0 with θ̇ = 1 (clockwise: ω = −1 about z)
    v_c1, v_b1 = jax.jacfwd(centroid)(0.0), jax.jacfwd(beam)(0.0)
    before = n * (-i_c + m * cross(centroid(0.0) - o_new, v_c1)) + m_b * cross(d_new - o_new, v_b1)
    # after: rotating about O′ with θ̇₂ (the same sense): velocities ω × (r − O′)
    w = -1.0
    v_c2 = jnp.array([-w * (centroid(0.0) - o_new)[1], w * (centroid(0.0) - o_new)[0]])
    v_b2 = jnp.array([-w * (d_new - o_new)[1], w * (d_new - o_new)[0]])
    after = n * (-i_c + m * cross(centroid(0.0) - o_new, v_c2)) + m_b * cross(d_new - o_new, v_b2)
    return float(before / after)


@pytest.mark.parametrize("gamma", [0.0, 0.4, 1.0, 5.0])
def test_frame_equation_of_motion_is_lagrange(gamma):
    """The frame's θ̈ (its equivalent block's eq. 2, with üv) equals Lagrange's equation of the
    columns and the beam, wherever the beam's centre sits, at random (θ, üg, üv)."""
    rng = np.random.default_rng(3)
    block = jr.Block.from_slenderness(5.0, 0.22)
    h, b = float(block.h), float(block.b)
    frame = jr.RockingFrame(block, gamma).equivalent
    for _ in range(6):
        theta = rng.uniform(0.0, float(block.alpha))
        ug, uv, offset = rng.uniform(-6, 6), rng.uniform(-4, 4), rng.uniform(-3, 3)
        ex = jr.WithVertical(jr.RickerPulse(ug, 1e-9), jr.RickerPulse(uv, 1e-9))  # üg, üv constant near t = 0
        got = float(frame.acceleration(0.0, theta, 1.0, ex))
        assert got == pytest.approx(_lagrange_acceleration(h, b, gamma, theta, ug, uv, offset), rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("tan_a", [0.1, 0.25, 0.5])
@pytest.mark.parametrize("gamma", [0.0, 0.3, 2.0, 20.0])
def test_frame_restitution_is_the_momentum_balance(tan_a, gamma):
    """η = [1 − 1.5 sin²α + 3γ cos 2α]/(1 + 3γ) against the momentum balance written with vectors;
    Housner's 1 − 1.5 sin²α at γ = 0."""
    block = jr.Block.from_slenderness(4.0, tan_a)
    eta = float(jr.RockingFrame(block, gamma).eta)
    assert eta == pytest.approx(_momentum_eta(float(block.h), float(block.b), gamma), rel=1e-12)
    if gamma == 0.0:
        assert eta == pytest.approx(1 - 1.5 * math.sin(math.atan(tan_a)) ** 2, rel=1e-14)


FRAME_SCENES = [  # (2h [m], tanα, γ, a_p/(g tanα), ω_p/p)
    (10.0, 0.2, 1.0, 2.0, 3.0),
    (10.0, 0.2, 3.0, 3.0, 2.0),
    (4.0, 0.15, 0.5, 1.5, 1.5),
    (20.0, 0.1, 0.2, 4.0, 6.0),
    (2.0, 0.3, 2.0, 1.8, 2.5),
    (8.0, 0.25, 10.0, 2.5, 4.0),
    (6.0, 0.12, 0.8, 5.0, 8.0),
    (12.0, 0.18, 1.5, 1.3, 1.2),
]


@pytest.mark.parametrize("scene", FRAME_SCENES)
def test_frame_runs_against_scipy_with_lagrange_numbers(scene):
    """A whole run of the frame against the SciPy reference (its own events and uplift scan) given
    p̂ from Lagrange's equation (θ̈ = −p̂² sin α at θ = 0, üg = 0) and η from the momentum balance."""
    height, tan_a, gamma, ap, wp = scene
    block = jr.Block.from_slenderness(height, tan_a)
    h, b, alpha = float(block.h), float(block.b), float(block.alpha)
    p_hat = math.sqrt(-_lagrange_acceleration(h, b, gamma, 0.0, 0.0, 0.0) / math.sin(alpha))
    eta = _momentum_eta(h, b, gamma)
    a_p, omega_p = jr.pulse_of_ratios(block, ap, wp)  # the axes are the columns' (α, p)
    sol = jr.simulate(jr.RockingFrame(block, gamma), jr.RickerPulse(a_p, omega_p))
    ref = scipy_rigid.solve_pulse((alpha, p_hat, eta), a_p, omega_p)
    assert sol.status == jr.Status.ok
    assert bool(sol.overturned) == ref.overturned
    assert float(sol.max_theta) == pytest.approx(ref.max_theta, abs=2e-6)


@pytest.mark.parametrize("gamma", [0.0, 0.5, 3.0, 30.0])
def test_frame_uplift_level_is_the_columns(gamma):
    """Uplift at max |üg| > g tanα whatever the beam's mass."""
    block = jr.Block.from_slenderness(6.0, 0.2)
    for factor, lifts in ((1 - 1e-7, False), (1 + 1e-7, True)):
        sol = jr.simulate(jr.RockingFrame(block, gamma), jr.RickerPulse(factor * G * 0.2, 4.0))
        assert bool(sol.uplifted) is lifts


def test_frame_without_beam_is_the_solitary_column():
    """γ = 0 is the column itself, bit for bit; γ → 0 tends to it."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    pulse = jr.RickerPulse(*jr.pulse_of_ratios(block, 2.0, 3.0))
    column = jr.simulate(jr.RigidModel(block), pulse)
    assert float(jr.simulate(jr.RockingFrame(block, 0.0), pulse).max_theta) == float(column.max_theta)
    gaps = [abs(float(jr.simulate(jr.RockingFrame(block, g), pulse).max_theta) - float(column.max_theta)) for g in (1e-2, 1e-4)]
    assert gaps[1] < 1e-3 and gaps[1] < 0.05 * gaps[0]


def test_heavier_beam_is_more_stable():
    """The paper's finding: the least overturning a_p/(g tanα) grows with γ (here at three ω_p/p),
    in one vmapped batch over γ and a_p."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    gammas = jnp.array([0.0, 1.0, 10.0])
    ratios = jnp.linspace(1.1, 12.0, 110)

    def overturns(gamma, ap, wp):
        return jr.simulate(jr.RockingFrame(block, gamma), jr.RickerPulse(*jr.pulse_of_ratios(block, ap, wp))).overturned

    for wp in (2.0, 3.0, 4.5):
        grid = jax.vmap(lambda g: jax.vmap(lambda ap: overturns(g, ap, wp))(ratios))(gammas)
        least = [float(ratios[np.argmax(np.asarray(row))]) if np.any(np.asarray(row)) else math.inf for row in grid]
        assert least[0] < least[1] < least[2], (wp, least)


@pytest.mark.slow  # 13-15 s warm (8 scenes × grad + 2 central differences; a batch, a history and both modes)
def test_frame_gradients_match_central_differences():
    """d max θ/α by the beam's mass ratio γ and the pulse amplitude, reverse mode, on 8 scenes."""
    checked = 0
    for height, tan_a, gamma, ap, wp in FRAME_SCENES:
        block = jr.Block.from_slenderness(height, tan_a)
        a_p, omega_p = jr.pulse_of_ratios(block, ap, wp)

        def peak(x):
            return jr.simulate(jr.RockingFrame(block, x[0]), jr.RickerPulse(x[1], omega_p)).max_theta

        x0 = jnp.asarray([gamma, a_p])
        if bool(jr.simulate(jr.RockingFrame(block, gamma), jr.RickerPulse(a_p, omega_p)).overturned):
            continue
        grad = np.asarray(jax.grad(peak)(x0))
        assert np.all(np.isfinite(grad))
        for i in range(2):
            eps = 1e-5 * float(x0[i])
            e = jnp.zeros(2).at[i].set(eps)
            fd = (float(peak(x0 + e)) - float(peak(x0 - e))) / (2 * eps)
            assert grad[i] == pytest.approx(fd, rel=2e-3, abs=1e-4 / float(x0[i])), (height, tan_a, gamma, i)
        checked += 1
    assert checked >= 6


def test_frame_refusals():
    block = jr.Block.from_slenderness(10.0, 0.2)
    with pytest.raises(jr.JaxrockInputError, match=r"mass_ratio .*valid"):
        jr.RockingFrame(block, -0.5)
    with pytest.raises(jr.JaxrockInputError, match="extended base"):
        jr.RockingFrame(jr.Block.from_slenderness(10.0, 0.2, 0.3), 1.0)
    assert float(jr.RockingFrame.from_beam(block, 6.0, 3).mass_ratio) == 2.0
    sol = jax.vmap(lambda g: jr.simulate(jr.RockingFrame(block, g), jr.RickerPulse(3.0, 4.0)))(jnp.array([1.0, -1.0]))
    assert list(np.asarray(sol.status == jr.Status.invalid_input)) == [False, True]


def test_cli_frame_spectrum(tmp_path):
    """`jaxrock spectrum --model frame --mass-ratio 1` runs and says so; a bad ratio is one line, exit 2."""
    out = tmp_path / "frame"
    r = invoke("spectrum", "--model", "frame", "--mass-ratio", "1", "--omega-ratio", "2,6", "--accel-ratio", "1.5,3,6", "--out", out)
    assert r.exit_code == 0, r.output
    assert "frame model" in r.output and (tmp_path / "frame.nc").exists()
    r = invoke("spectrum", "--model", "frame", "--mass-ratio", "-1", "--out", out)
    assert r.exit_code == 2 and "mass" in r.output.lower()
    r = invoke("spectrum", "--model", "frame", "--undamped", "--out", out)  # the frame's η is its impact law: nothing to switch off
    assert r.exit_code == 2 and "--undamped" in r.output and len(r.output.strip().splitlines()) == 1, r.output


def test_reproduce_frame_section(tmp_path):
    """`reproduce`'s extra section (no row of the paper's table): the spectra figure and the table
    of least overturning a_p/(g tanα), which never falls as the beam gets heavier."""
    from jaxrock.paper.beyond import frame_spectra

    assert frame_spectra(tmp_path, n=6, refine=2) == []
    assert (tmp_path / "frame_spectra.png").stat().st_size > 10_000
    rows = [line.split("|")[2:-1] for line in (tmp_path / "frame_boundaries.md").read_text(encoding="utf-8").splitlines()
            if line.startswith("| ") and line[2].isdigit()]
    assert len(rows) == 6
    for cells in rows:
        least = [math.inf if c.strip() == "none" else float(c) for c in cells]
        assert least == sorted(least), least


@pytest.mark.slow  # 13-15 s warm (8 scenes × grad + 2 central differences; a batch, a history and both modes)
def test_frame_in_a_scenes_file_a_history_and_both_autodiff_modes(tmp_path):
    """The frame through the other entry points: a scenes file row (model frame, mass_ratio) is
    `simulate`'s; a history's peak is the summary's; forward mode (jvp) equals reverse mode (grad)."""
    block = jr.Block.from_slenderness(8.0, 0.2)
    a_p, omega_p = (float(x) for x in jr.pulse_of_ratios(block, 2.0, 3.0))
    frame = jr.RockingFrame(block, 2.0)
    pulse = jr.RickerPulse(a_p, omega_p)
    sol = jr.simulate(frame, pulse)
    (tmp_path / "scenes.csv").write_text(f"height,tan_alpha,model,mass_ratio,pulse,a_p,omega_p\n8,0.2,frame,2,symmetric,{a_p!r},{omega_p!r}\n")
    r = invoke("batch", tmp_path / "scenes.csv", tmp_path / "out.csv", "-q")
    assert r.exit_code == 0, r.output
    row = (tmp_path / "out.csv").read_text().splitlines()[1].split(",")
    header = (tmp_path / "out.csv").read_text().splitlines()[0].split(",")
    assert float(row[header.index("max_theta")]) == pytest.approx(float(sol.max_theta), abs=1e-12)
    ts = jnp.linspace(float(pulse.t_start), float(pulse.t_end) + 5.0, 4001)
    hist = jr.simulate(frame, pulse, save=jr.Save(ts, ("theta",)))
    assert float(jnp.max(jnp.abs(hist.history["theta"]))) / float(block.alpha) == pytest.approx(float(sol.max_theta), abs=1e-4)

    def peak(gamma, integrator=None):
        return jr.simulate(jr.RockingFrame(block, gamma), pulse, integrator=integrator).max_theta

    reverse = float(jax.grad(peak)(2.0))
    forward = float(jax.jvp(lambda g: peak(g, jr.EventIntegrator(autodiff="forward")), (2.0,), (1.0,))[1])
    assert reverse < 0 and forward == pytest.approx(reverse, rel=1e-6)
