"""What several test files share: the command line run in-process, small files written and read,
and SPEC's closed forms written independently of jaxrock."""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
import sys
import threading
import time

from typer.testing import CliRunner

from jaxrock.cli import app

runner = CliRunner()
G = 9.81  # m/s², SPEC


def invoke(*args):
    """`jaxrock ARGS...` in this process (its jitted functions are shared with the library's)."""
    return runner.invoke(app, [str(a) for a in args])


def write(path, text: str):
    """`text` written to `path`; returns the path."""
    path.write_text(text)
    return path


def read_csv(path) -> list[dict]:
    """A CSV file's rows as dicts."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def spec_extended(height, tan_a, tan_base):
    """α′, p′, η′ from SPEC (exact rigid-body values, m = 1)."""
    h = height / 2
    b, bb = h * tan_a, h * tan_base
    R2, Rp = h * h + b * b, math.hypot(h, bb)
    io = R2 / 3 + Rp**2
    return math.atan(bb / h), math.sqrt(G * Rp / io), 1 - 2 * bb * bb / io


def jaxrock_process(*args, cwd, env=None):
    """A real `jaxrock` process (python -m jaxrock.cli), its output piped."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "JAX_PLATFORMS": "cpu", **(env or {})}
    return subprocess.Popen([sys.executable, "-m", "jaxrock.cli", *map(str, args)], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


class Watch:
    """Reads a process's stderr (progress bars write '\\r', not lines) as it comes."""

    def __init__(self, proc):
        self.proc, self.text = proc, ""
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()

    def _read(self):
        for ch in iter(lambda: self.proc.stderr.read(1), ""):
            self.text += ch

    def wait_for(self, pattern: str, timeout: float = 120.0):
        t0 = time.monotonic()
        while not re.search(pattern, self.text):
            if self.proc.poll() is not None or time.monotonic() - t0 > timeout:
                raise AssertionError(f"{pattern!r} never appeared; stderr:\n{self.text[-2000:]}")
            time.sleep(0.02)

    def finish(self, timeout: float = 240.0):
        rc = self.proc.wait(timeout)
        self._t.join(5)
        out = self.proc.stdout.read()
        self.proc.stdout.close()
        self.proc.stderr.close()
        return rc, out, self.text


def pre_yield_rotation(model, ratio: float) -> float:
    """θ/α′ of the spring model's base under a static M(θ) = ratio · My: smoothing · m⁻¹(ratio) for
    the model's backbone m (bisection: written apart from the backbones' own solves)."""
    lo, hi = 0.0, 50.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(model.backbone.unit_moment(mid)) < ratio else (lo, mid)
    return float(model.smoothing) * lo


# -- a command line in a fresh interpreter (this process has long imported JAX) --------------------
HEAVY = ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "matplotlib", "xarray", "scipy")

CLI = """
    import json, sys
    from jaxrock.cli import app
    try:
        app({args!r}, standalone_mode=True)
    except SystemExit as e:
        code = e.code
    print(json.dumps({{"code": code, "heavy": [m for m in {heavy!r} if m in sys.modules]}}))
"""


def fresh_python(code: str, env: dict | None = None) -> dict:
    """Run `code` in a fresh interpreter; it prints one JSON line last, returned."""
    import json
    import textwrap

    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=240,
                       env={**os.environ, **(env or {})})
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def fresh_cli(args) -> dict:
    """`jaxrock ARGS` in a fresh interpreter: its exit code and the heavy libraries (`HEAVY`) it imported."""
    return fresh_python(CLI.format(args=list(args), heavy=HEAVY))


def noisy(x, sigma, seed):
    """`x` with seeded Gaussian noise of standard deviation `sigma` (a measured channel)."""
    import numpy as np

    return x + np.random.default_rng(seed).normal(0.0, sigma, x.size)


def identification_coverage(truth_model, start_model, name, value, t, *, sigma, trials, alpha_r,
                            excitation=None, sigma_top=None):
    """Seeded noisy runs of `truth_model` (free rocking from 0.8 α′, or from rest under `excitation`;
    with `sigma_top`, its top displacement measured too, with that noise [m]) fitted from
    `start_model`: how many of the `trials` reported 95 % intervals hold `value`, and the errors."""
    import numpy as np

    import jaxrock as jr
    from jaxrock.analyses.identify import history

    start = (0.0, 0.8 * alpha_r, 0.0) if excitation is None else None
    clean = history(truth_model, excitation or jr.StillGround(), t, start=start, top=True)
    assert clean[-1] == jr.Status.ok
    inside, errors = 0, []
    for seed in range(trials):
        top = None if sigma_top is None else noisy(np.asarray(clean[1]), sigma_top, 200 + seed)
        measured = jr.Measured(t, noisy(np.asarray(clean[0]), sigma, 100 + seed), excitation, top=top)
        fit = jr.identify(measured, start_model, [name], n_boot=0, warn=False)
        inside += fit.interval[0, 0] <= value <= fit.interval[0, 1]
        errors.append(fit.estimate[0] - value)
    return inside, np.asarray(errors)
