import os
import tempfile

import numpy as np
import pytest

# The tests keep their compiled kernels apart from the user's (jaxrock.cache), shared by the workers
# of a run and by the subprocesses the tests start (they inherit the variable).
os.environ.setdefault("JAXROCK_CACHE_DIR", os.path.join(tempfile.gettempdir(), "jaxrock-test-cache"))

import jaxrock  # noqa: E402,F401  (enables float64 and the persistent compilation cache)
from jaxrock.analyses.spectra import Spectrum  # noqa: E402


@pytest.fixture(autouse=True)
def every_spectrum_is_self_consistent(monkeypatch):
    """Every `Spectrum` a test builds (computed or loaded) is checked on construction: no cell
    contradicts its own flags (`Spectrum.contradictions`)."""

    def check(spec):
        bad = spec.contradictions()
        assert not bad.any(), f"{int(bad.sum())} spectrum cells contradict their flags at (accel, omega) index {np.argwhere(bad)[:5].tolist()}"

    monkeypatch.setattr(Spectrum, "__check_init__", check, raising=False)
