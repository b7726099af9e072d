"""What several test files share: the command line run in-process, small files written and read,
and SPEC's closed forms written independently of jaxrock."""

from __future__ import annotations

import csv
import math

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
