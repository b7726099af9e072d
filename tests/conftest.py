import os
import tempfile

import jax

import jaxrock  # noqa: F401  (enables float64)

# Reuse compiled XLA programs across test files of one run (and across runs on one machine).
jax.config.update(
    "jax_compilation_cache_dir", os.environ.get("JAXROCK_TEST_CACHE", os.path.join(tempfile.gettempdir(), "jaxrock-xla-cache"))
)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
