"""The `jaxrock` command line (typer): spectra, single scenes, CSV batches, record spectra and the
damper calibration. `jaxrock COMMAND --help` describes each command.

Bad input ends with a one-line `Error: ...` message (the `JaxrockInputError` text, naming the
parameter and its valid range) and exit code 2, never a traceback. The package: `app` (the
program and what its commands share), one module per command (`spectrum`, `simulate`, `batch`,
`record_spectrum`, `sweep`, `suite`, `calibrate`, `reproduce`, `stability`, `work_precision`,
`identify`: each parses, calls and prints), `options` (flags → values, summaries), `guards` (errors, exit
codes, estimates, locks, signals, `--json`). Model kinds of other packages
(`jaxrock.scene.load_plugins`) are registered before the options are built from the registry.
"""

from ..scene import load_plugins

PLUGIN_ERRORS = load_plugins()  # before the options are built: a plugin's model kinds and parameters are flags too

from .app import app, main  # noqa: E402
from . import (spectrum, simulate, batch, record_spectrum, sweep, suite, calibrate, reproduce,  # noqa: E402,F401  (each registers its command, in this order)
               stability, work_precision, identify)
from .options import build_model, parse_values  # noqa: E402

__all__ = ["app", "main", "build_model", "parse_values"]
