"""The paper's spring model (SM, sections 3–6) in OpenSeesPy — the peer of `jaxrock.SpringModel`.

Needs `openseespy` (Debian/Ubuntu: `apt-get install libblas3 liblapack3` first).

Model (ndm = 2, ndf = 3), SI units, unit out-of-plane thickness, conventions of SPEC "Spring model":

- node 1 at (0, 0) fully fixed; node 2 at (0, 0) with both translations fixed, rotation free (the
  base rotation θ). A `zeroLength` element 1–2 carries, in direction 3 (rotation), two materials in
  parallel:
  * the spring `ElasticMultiLinear`: the nonlinear-elastic backbone, as jaxrock's (`backbone`):
    bilinear (the paper's: linear to θy = smoothing·α′, then flat at My = m g b′ out
    to ±π/2; exact in ElasticMultiLinear), or (the default) M = My tanh(θ/θs) sampled symmetric about 0 (0,
    steps of 0.05 θs up to 4 θs, then 4.5, 5, 6, 8 θs, then flat at ±My out to ±π/2; largest
    deviation from tanh between samples, `backbone_error()`, 2.4e-4 My); both load and unload
    along the same path, as jaxrock's;
  * the damper `Viscous` (C = c, exponent 1), c = c̄ m g^0.5 R′^1.5, c̄ = 0.02 (α′/0.1)² (eq. 17).
- the column: nodes 2 … n+2 up to 2h, `elasticBeamColumn` elements with `geomTransf Corotational`,
  A = 2b, I = (2b)³/12, E, mass per length ρA as the element's *consistent* mass (`-cMass`), which,
  like jaxrock's, is exact for rigid rotation at any n (a lumped mass gives (2n²+1)/(6n²) m(2h)²
  instead of (4/3) m h² for the column's inertia: +50 % for one element, +0.5 % for ten);
- added rotational masses ΔI/(n+1) on each column node, ΔI = m(R²/3 + R′²) − (4/3) m h² (SPEC);
- gravity: the weight ρA le g of each element as two vertical nodal loads (the work-equivalent
  loads of a uniform axial load, which also give exactly m g h sinθ on a rigidly rotated column)
  applied in a static step (`LoadControl`, 10 increments), then `loadConst('-time', 0)`;
- column damping: stiffness-proportional Rayleigh on the beam elements only (`region -ele ...`),
  a₁ = ζ T₁/π from the first fixed-base mode (`eigen` on the same mesh with the base rotation
  fixed). The *current* tangent is used (`-rayleigh 0 a1 0 0`), not the initial one
  (`0 0 a1 0`): the initial stiffness lives in the undeformed frame, so at a base rotation θ it
  sees an axial strain rate ∝ sinθ θ̇ in a rigid rotation and would damp the rocking itself
  (a₁ EA sinθ θ̇ ≈ 70 m g at θ = 0.1 for the 50 m concrete column); the corotational current
  tangent acts on deformation only (its geometric part adds a₁ N θ̇ ≈ 1e-3 m g, negligible);
- ground motion: the effective loads −M r üg(t) of the consistent mass as a `Plain` pattern with a
  `Path` series sampled at dt/4 (Ricker pulse over ω_p t ∈ [−8, 8], |üg(±8)| = 7e-6 a_p), or at a
  record's own samples (`run_record`) — see `ground_motion_pattern` for why not `UniformExcitation`;
- time stepping: `Newmark` γ = 1/2, β = 1/4 (trapezoidal, no numerical damping), `Newton` with a
  `NormDispIncr` test (1e-10 α′, max 30 iterations), `BandGeneral`,
  dt = min(T_p, 2π/p′)/`steps_per_period` (default 400, i.e. dt ≤ T_p/400), on a record its
  sample step over `substeps`; a failed step is
  retried as 2, 4, … 64 substeps (`NewtonLineSearch` on the smallest ones);
- stop rule (as jaxrock's): overturned when |θ| ≥ α′; after the pulse, stop once the rigid
  mechanical energy ½ Itot θ̇² + My θs log cosh(θ/θs) − m g h (1 − cosθ) falls below
  (margin ×) the potential at the largest |θ| so far (margin 1 for the quasi-rigid scene, 0.9 for
  the flexible one), or at the pulse's or record's end + 20·2π/p′.

θ is positive counter-clockwise here (jaxrock: top to +x); only |θ| is compared.
"""

from __future__ import annotations

import math
import time

import numpy as np
import openseespy.opensees as ops

from ..scene import DEFAULT_BACKBONE, DEFAULT_SMOOTHING  # jaxrock's spring defaults (scene: no JAX import)

G = 9.81
X_PULSE = 8.0  # pulse window ω_p t ∈ [−X, X]
_X_PEAK = math.sqrt(9 - math.sqrt(54))  # where the antisymmetric shape of eq. 29 peaks
ANTI_BETA = abs((_X_PEAK**2 / 3 - 3) * (_X_PEAK / math.sqrt(3)) * math.exp(-(_X_PEAK**2) / 6))  # β ≈ 1.38011905


# ----------------------------------------------------------------------------------------------
# geometry
# ----------------------------------------------------------------------------------------------
class Scene:
    """Geometry and derived constants of a SM scene (full height `height`, width `width`)."""

    def __init__(self, height, width, *, E=None, rho=2500.0, n_elements=10, smoothing=None, backbone=None,
                 cbar=None, zeta=0.01, added_masses=True, base_width=None):
        self.h = 0.5 * height
        self.b = 0.5 * width
        self.bb = self.b if base_width is None else 0.5 * base_width
        self.E = 1e14 if E is None else float(E)  # None: quasi-rigid (paper: 1e11 kPa)
        self.rho = rho
        self.n = int(n_elements)
        self.A = 2 * self.b
        self.I = (2 * self.b) ** 3 / 12
        self.m = rho * self.A * 2 * self.h
        self.alpha = math.atan2(self.bb, self.h)
        self.R = math.hypot(self.h, self.b)
        self.Rr = math.hypot(self.h, self.bb)
        self.Itot = self.m * (self.R**2 / 3 + self.Rr**2) if added_masses else (4 / 3) * self.m * self.h**2
        self.dI = self.Itot - (4 / 3) * self.m * self.h**2
        self.p = math.sqrt(G * self.Rr * self.m / self.Itot)
        self.My = self.m * G * self.bb
        # jaxrock's defaults: E None is its quasi-rigid one-DOF model
        self.backbone = DEFAULT_BACKBONE["quasi-rigid" if E is None else "flexible"] if backbone is None else backbone
        self.theta_s = (DEFAULT_SMOOTHING[self.backbone] if smoothing is None else smoothing) * self.alpha
        self.cbar = 0.02 * (self.alpha / 0.1) ** 2 if cbar is None else cbar
        self.c = self.cbar * self.m * math.sqrt(G) * self.Rr**1.5
        self.zeta = zeta

    def rigid_energy(self, th, om):
        x = abs(th) / self.theta_s
        if self.backbone == "bilinear":
            spring = 0.5 * x * x if x <= 1 else x - 0.5
        else:
            spring = x + math.log1p(math.exp(-2 * x)) - math.log(2.0)
        return 0.5 * self.Itot * om**2 + self.My * self.theta_s * spring - self.m * G * self.h * (1 - math.cos(th))


def backbone_points(My, theta_s, theta_max=math.pi / 2, backbone="tanh"):
    """Points (θ, M) of the backbone, symmetric about 0. Bilinear: exact, (θy, My) then flat out to
    `theta_max`. Tanh: samples of My tanh(θ/θs), uniform steps 0.05 θs up to 4 θs (where the
    curvature is), then 4.5, 5, 6, 8 θs, then flat out to `theta_max`."""
    if backbone == "bilinear":
        th, M = np.array([theta_s, max(theta_max, 10 * theta_s)]), np.array([My, My])
        return np.concatenate([-th[::-1], [0.0], th]), np.concatenate([-M[::-1], [0.0], M])
    x = np.concatenate([np.linspace(0.0, 4.0, 81)[1:], [4.5, 5.0, 6.0, 8.0]])
    th = np.concatenate([x * theta_s, [max(theta_max, 10 * theta_s)]])
    M = np.concatenate([My * np.tanh(x), [My * math.tanh(8.0)]])
    return np.concatenate([-th[::-1], [0.0], th]), np.concatenate([-M[::-1], [0.0], M])


def backbone_error():
    """Largest |piecewise-linear − tanh| / My of the sampled backbone."""
    th, M = backbone_points(1.0, 1.0, 100.0)
    xs = np.linspace(0, 20, 400001)
    return float(np.max(np.abs(np.interp(xs, th, M) - np.tanh(xs))))


# ----------------------------------------------------------------------------------------------
# model
# ----------------------------------------------------------------------------------------------
def fixed_base_period(sc: Scene) -> float:
    """First fixed-base period of the mesh: `eigen` on a separate model (linear transformation,
    base clamped, added rotational masses included as in the dynamic model). Wipes the domain."""
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    n = sc.n
    le = 2 * sc.h / n
    nodes = list(range(2, n + 3))
    for k, nd in enumerate(nodes):
        ops.node(nd, 0.0, k * le)
    ops.fix(2, 1, 1, 1)
    ops.geomTransf("Linear", 1)
    for k in range(n):
        ops.element("elasticBeamColumn", 10 + k, nodes[k], nodes[k + 1], sc.A, sc.E, sc.I, 1,
                    "-mass", sc.rho * sc.A, "-cMass")
    if sc.dI > 0:
        for nd in nodes:
            ops.mass(nd, 0.0, 0.0, sc.dI / len(nodes))
    lam = (ops.eigen("-fullGenLapack", 1) if n < 3 else ops.eigen(1))[0]
    ops.wipe()
    return 2 * math.pi / math.sqrt(lam)


def build(sc: Scene, *, fixed_base=False, gravity=True, rayleigh=True):
    """Build the SM of scene `sc` (gravity preloaded); returns (beam element tags, column nodes)."""
    T1 = fixed_base_period(sc) if rayleigh else None
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.fix(1, 1, 1, 1)
    n = sc.n
    le = 2 * sc.h / n
    nodes = list(range(2, n + 3))
    for k, nd in enumerate(nodes):
        ops.node(nd, 0.0, k * le)
    ops.fix(2, 1, 1, 1 if fixed_base else 0)
    # base spring + damper
    th, M = backbone_points(sc.My, sc.theta_s, backbone=sc.backbone)
    ops.uniaxialMaterial("ElasticMultiLinear", 1, 0.0, "-strain", *th.tolist(), "-stress", *M.tolist())
    ops.uniaxialMaterial("Viscous", 2, sc.c, 1.0)
    if not fixed_base:
        ops.element("zeroLength", 1, 1, 2, "-mat", 1, 2, "-dir", 3, 3)
    # column
    ops.geomTransf("Corotational", 1)
    eles = []
    for k in range(n):
        tag = 10 + k
        ops.element("elasticBeamColumn", tag, nodes[k], nodes[k + 1], sc.A, sc.E, sc.I, 1,
                    "-mass", sc.rho * sc.A, "-cMass")
        eles.append(tag)
    if sc.dI > 0:
        for nd in nodes:
            ops.mass(nd, 0.0, 0.0, sc.dI / len(nodes))
    if gravity:
        ops.timeSeries("Linear", 1)
        ops.pattern("Plain", 1, 1)
        w = sc.rho * sc.A * le * G
        for k in range(n):
            ops.load(nodes[k], 0.0, -0.5 * w, 0.0)
            ops.load(nodes[k + 1], 0.0, -0.5 * w, 0.0)
        ops.system("BandGeneral")
        ops.numberer("RCM")
        ops.constraints("Plain")
        ops.test("NormDispIncr", 1e-12, 50)
        ops.algorithm("Newton")
        ops.integrator("LoadControl", 0.1)
        ops.analysis("Static")
        if ops.analyze(10) != 0:
            raise RuntimeError("gravity step failed")
        ops.loadConst("-time", 0.0)
        ops.wipeAnalysis()
    if rayleigh:
        a1 = sc.zeta * T1 / math.pi  # stiffness proportional: ζ = a₁ ω₁ / 2
        ops.region(1, "-ele", *eles, "-rayleigh", 0.0, a1, 0.0, 0.0)
    return eles, nodes


build_model = build


# ----------------------------------------------------------------------------------------------
# analyses
# ----------------------------------------------------------------------------------------------
def pushover(sc: Scene, theta_max=None, n_steps=200):
    """Static pushover: horizontal force F at mid-height (n even), displacement control of that
    node. Returns (θ, F/(m g)) arrays."""
    if sc.n % 2:
        raise ValueError("pushover needs an even number of elements (a node at mid-height)")
    eles, nodes = build_model(sc, rayleigh=False)
    mid = nodes[sc.n // 2]
    theta_max = 0.9 * math.pi / 2 if theta_max is None else theta_max
    ops.timeSeries("Linear", 2)
    ops.pattern("Plain", 2, 2)
    ops.load(mid, 1.0, 0.0, 0.0)
    ops.system("BandGeneral")
    ops.numberer("RCM")
    ops.constraints("Plain")
    ops.test("NormDispIncr", 1e-10, 50)
    ops.algorithm("Newton")
    du = sc.h * math.sin(theta_max) / n_steps
    ops.integrator("DisplacementControl", mid, 1, du)
    ops.analysis("Static")
    th, F = [], []
    for _ in range(n_steps):
        if ops.analyze(1) != 0:
            break
        th.append(-ops.nodeDisp(2, 3))
        F.append(ops.getLoadFactor(2) / (sc.m * G))
    ops.wipe()
    return np.array(th), np.array(F)


def ground_motion_pattern(sc: Scene, tag, series):
    """The ground motion as the effective earthquake loads −M r üg(t) of the consistent mass
    (a `Plain` pattern): per element −ρA le üg/2 on each end's x and the work-equivalent end
    moments ±ρA le² üg/12. (`UniformExcitation` is not used: with this model, openseespy 3.7.1
    applied twice the inertial moment m h üg — the quasi-static pre-uplift rotation came out
    2.00× M/k, with element or nodal masses alike — while these explicit loads give 1.000×.)"""
    ops.pattern("Plain", tag, series)
    le = 2 * sc.h / sc.n
    q = sc.rho * sc.A * le
    nodes = list(range(2, sc.n + 3))
    fx = np.zeros(len(nodes))
    mz = np.zeros(len(nodes))
    for k in range(sc.n):
        fx[k] -= 0.5 * q
        fx[k + 1] -= 0.5 * q
        # u_x = −θz (y − 2y²/L + y³/L²) near the bottom end of a vertical element
        mz[k] += q * le / 12
        mz[k + 1] -= q * le / 12
    for nd, f, mo in zip(nodes, fx, mz):
        ops.load(nd, f, 0.0, mo)


def ricker(a_p, omega_p, t):
    x = omega_p * t
    return a_p * (1 - x**2 / 2) * np.exp(-(x**2) / 4)


def run_pulse(sc: Scene, a_p, omega_p, *, steps_per_period=400, history=False, t_free=None,
              antisymmetric=False):
    """Ricker pulse (jaxrock.RickerPulse(a_p, omega_p)) on scene `sc`.

    Returns dict(max_theta (max|θ|/α′, capped at 1), overturned, time (s, model build included),
    steps, failed, and with `history` t, theta)."""
    t0 = time.perf_counter()
    build_model(sc)
    Tp = 2 * math.pi / omega_p
    dt = min(Tp, 2 * math.pi / sc.p) / steps_per_period
    t_start = -X_PULSE / omega_p
    dur = 2 * X_PULSE / omega_p
    ns = int(math.ceil(dur / (dt / 4))) + 1
    ts = t_start + np.arange(ns) * (dt / 4)
    if antisymmetric:
        x = omega_p * ts
        ug = a_p * (x**2 / 3 - 3) * (x / math.sqrt(3)) * np.exp(-(x**2) / 6) / ANTI_BETA
    else:
        ug = ricker(a_p, omega_p, ts)
    return _transient(sc, ug, dt / 4, dt, dur, t_start, t_free, history, t0)


def run_record(sc: Scene, acc, record_dt, scale=1.0, *, substeps=1, history=False, t_free=None):
    """Ground-motion record (jaxrock.Record(acc, record_dt).scaled(scale): linear between samples
    from t = 0, zero after its end) on scene `sc`, at dt = record_dt/`substeps` (what OpenSees users
    run: the record's step, or a fraction of it). Returns what `run_pulse` returns."""
    t0 = time.perf_counter()
    build_model(sc)
    ug = scale * np.asarray(acc, dtype=float)
    dur = record_dt * (len(ug) - 1)
    return _transient(sc, ug, record_dt, record_dt / substeps, dur, 0.0, t_free, history, t0)


def _transient(sc: Scene, ug, series_dt, dt, dur, t_start, t_free, history, t0):
    """The transient run on the built model: ground motion `ug` sampled at `series_dt` from
    `t_start` (lasting `dur`), Newmark steps of `dt`, the stop rule of the module docstring."""
    ops.timeSeries("Path", 3, "-dt", series_dt, "-values", *np.asarray(ug).tolist())
    ground_motion_pattern(sc, 3, 3)
    ops.system("BandGeneral")
    ops.numberer("RCM")
    ops.constraints("Plain")
    tol = 1e-10 * sc.alpha
    ops.test("NormDispIncr", tol, 30)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    t_free = 20 * 2 * math.pi / sc.p if t_free is None else t_free
    t_stop = dur + t_free
    margin = 1.0 if sc.E >= 1e13 else 0.9
    peak, over, failed, steps = 0.0, False, False, 0
    t = 0.0
    hist_t, hist_th = [0.0], [0.0]
    while t < t_stop - 1e-12:
        ok = ops.analyze(1, dt)
        if ok != 0:  # substep
            for k in (2, 4, 8, 16, 32, 64):
                if k >= 16:
                    ops.algorithm("NewtonLineSearch", "-type", "Bisection")
                ok = 0
                for _ in range(k):
                    ok = ops.analyze(1, dt / k)
                    if ok != 0:
                        break
                    th = ops.nodeDisp(2, 3)
                    peak = max(peak, abs(th))
                if ok == 0:
                    break
            ops.algorithm("Newton")
            if ok != 0:
                failed = True
                break
        steps += 1
        t = ops.getTime()
        th = ops.nodeDisp(2, 3)
        peak = max(peak, abs(th))
        if history:
            hist_t.append(t)
            hist_th.append(th)
        if peak >= sc.alpha:
            over = True
            break
        if t > dur:
            om = ops.nodeVel(2, 3)
            vref = margin * sc.rigid_energy(peak, 0.0)
            if sc.rigid_energy(th, om) < vref:
                break
    ops.wipe()
    out = dict(
        max_theta=1.0 if over else peak / sc.alpha,
        overturned=over,
        time=time.perf_counter() - t0,
        steps=steps,
        failed=failed,
        dt=dt,
    )
    if history:
        out["t"] = np.array(hist_t) + t_start
        out["theta"] = np.array(hist_th)
    return out
