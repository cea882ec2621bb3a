import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import jax  # noqa: E402

import atlas  # noqa: E402,F401  (turns on float64 in JAX)
from atlas.core.config import CACHE_ENV, use_compile_cache  # noqa: E402

jax.config.update("jax_enable_x64", True)

# One persistent compilation cache for the whole run, shared by both xdist workers, the CLI
# subprocesses and the notebook kernels (which inherit the variable).  It saves ~30 % of a warm
# re-run; a cold run (CI) gains about nothing.
# Under .pytest_cache (git-ignored); ATLAS_JAX_CACHE=0 switches it off.
os.environ.setdefault(CACHE_ENV, str(Path(__file__).resolve().parents[1] / ".pytest_cache" / "jax"))
use_compile_cache(min_compile_seconds=0.2)
