"""The `jaxrock` command line (typer): spectra, single scenes, CSV batches, record spectra and the
damper calibration. `jaxrock COMMAND --help` describes each command.

Bad input ends with a one-line `Error: ...` message (the `JaxrockInputError` text, naming the
parameter and its valid range) and exit code 2, never a traceback. The package: `commands` (each
command parses, calls and prints), `options` (flags → values, summaries), `guards` (errors, exit
codes, estimates, locks, signals).
"""

from .commands import app, main
from .options import build_model, parse_values

__all__ = ["app", "main", "build_model", "parse_values"]
