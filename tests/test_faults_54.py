"""Issue 54 items 15, 16 and 18: faults of a run's process and of a sweep's cluster.

- 18: ``progress=True`` (the command line's path) gives the bits of the run without a bar, every
  output variable; a warm cache copied to another folder is used there (nothing compiled anew).
"""
from __future__ import annotations

import io

import numpy as np
import pytest

from conftest import CONFIGS

import hydro
import mfm

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def test_a_progress_bar_gives_the_bits_of_the_run_without_one():
    """The bar runs in chunks whose outputs are made in each chunk after its steps, in groups of
    DEFERRED_RECORD_WIDTH samples; a chunk of 10 blocks (RM3, 200 samples: chunk_plan's 20
    updates) put each sample elsewhere in its group than the run in one program did, and XLA's
    vectorised outputs differ in the last bits with the place (q̈, joint and hydro forces up to
    2e-7 relative, item 18). Reference: the same call without a bar; tolerance: none."""
    model = mfm.load(CONFIGS / "rm3.toml")
    sea = hydro.Regular(height=2.5, period=8.0)
    kw = dict(duration=20.0, dt=0.1, ramp=10.0)
    plain = mfm.simulate(model, sea, **kw)
    barred = mfm.simulate(model, sea, progress={"file": io.StringIO()}, **kw)
    assert set(plain.data_vars) == set(barred.data_vars)
    differ = [v for v in plain.data_vars
              if not np.array_equal(plain[v].values, barred[v].values, equal_nan=True)]
    assert not differ, differ
