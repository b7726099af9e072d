import os
import tempfile

import jax
import numpy as np
import pytest

import jaxrock  # noqa: F401  (enables float64)
from jaxrock.analyses.spectra import Spectrum

# Reuse compiled XLA programs across test files of one run (and across runs on one machine).
jax.config.update(
    "jax_compilation_cache_dir", os.environ.get("JAXROCK_TEST_CACHE", os.path.join(tempfile.gettempdir(), "jaxrock-xla-cache"))
)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)


@pytest.fixture(autouse=True)
def every_spectrum_is_self_consistent(monkeypatch):
    """Every `Spectrum` a test builds (computed or loaded) is checked on construction: no cell
    contradicts its own flags (`Spectrum.contradictions`)."""

    def check(spec):
        bad = spec.contradictions()
        assert not bad.any(), f"{int(bad.sum())} spectrum cells contradict their flags at (accel, omega) index {np.argwhere(bad)[:5].tolist()}"

    monkeypatch.setattr(Spectrum, "__check_init__", check, raising=False)
