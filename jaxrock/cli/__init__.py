"""The `jaxrock` command line (typer): spectra, single scenes, CSV batches, record spectra and the
damper calibration. `jaxrock COMMAND --help` describes each command.

Bad input ends with a one-line `Error: ...` message (the `JaxrockInputError` text, naming the
parameter and its valid range) and exit code 2, never a traceback. The package: `commands` (each
command parses, calls and prints), `options` (flags → values, summaries), `guards` (errors, exit
codes, estimates, locks, signals). Model kinds of other packages (`jaxrock.scene.load_plugins`)
are registered before the options are built from the registry.
"""

from ..scene import load_plugins

PLUGIN_ERRORS = load_plugins()  # before the options are built: a plugin's model kinds and parameters are flags too

from .commands import app, main  # noqa: E402
from .options import build_model, parse_values

__all__ = ["app", "main", "build_model", "parse_values"]
