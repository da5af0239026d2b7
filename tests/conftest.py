import os

# One BLAS thread: the state-space fits and small solves are faster and steadier that way on the
# 2-core CI machine (threaded BLAS measured up to 10× slower on first calls under load).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"


import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="module")
def _fresh_jax_caches():
    """Each test module starts without the compiled functions of the modules before it: the
    frequency domain's compiled linearisations are cached per model structure, and a worker that
    runs dozens of modules would otherwise keep every model's (and its database's) compilation."""
    yield
    jax.clear_caches()
