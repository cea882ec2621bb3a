import os

os.environ.setdefault("MPLBACKEND", "Agg")

import jax  # noqa: E402

import atlas  # noqa: E402,F401  (turns on float64 in JAX)

jax.config.update("jax_enable_x64", True)
