"""Issue 35 item 3: preparing the radiation of a shipped config for a run gives no warning but the
documented data issues of data that are not ours (hydro.database.KNOWN_DATA_ISSUES, listed by
`mfm info`).

For each shipped config with [hydro]: the load (its load-time checks), the memory T_K (its
impulse response: the ringing and undecayed-K checks), A∞ "consistent" (the transform of K: the
ringing check again) and the strategy `radiation="auto"` takes for `mfm simulate`'s defaults
(dt 0.01 s, 10 s): for a convolution the grid check of its kernel (HydroSpec.check_grid, as
HydroSpec.kernel calls it), the kernel's weights themselves not formed (M4 134: 40 s of them).
The state-space fit (Stansby & Li, Wu & Yuan) checks ringing on the same damping nodes as the
memory (hydro.radiation._check_ringing), so its warnings are these; the fit itself (up to 16 min
uncached for Wu & Yuan's 90 dofs) is not run here. The checks' own warnings against analytic
cases: tests/test_hydro_radiation.py.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import pytest

import mfm
from hydro.database import HydroDatabaseWarning
from mfm.runner.choices import convolution_or_state_space

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
WET = sorted(p for p in [*CONFIGS.glob("*.toml"), *CONFIGS.glob("sensitivity/*.toml")]
             if "[hydro]" in p.read_text())
DT, N_STEPS = 0.01, 1000          # mfm simulate's defaults: --dt 0.01 --duration 10

# ours, and rightly warned: none. (The Wu & Yuan single-WEC database was here while it held only
# the paper's 10 wave periods, d omega 0.21 rad/s; it now holds them among a 0.05 rad/s band,
# hydro/data/README.md. A database put here must warn: the assertion below fails once it is fixed.)
RIGHTLY_WARNED: dict[str, str] = {}


@pytest.mark.slow            # ≈ 2–6 s a config on a shared 2-core machine (load and memory)
@pytest.mark.parametrize("path", WET, ids=lambda p: p.relative_to(CONFIGS).as_posix())
def test_radiation_preparation_of_shipped_configs_gives_no_warning(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", HydroDatabaseWarning)
        model = mfm.load(path)
        spec = model.hydro
        T_K = spec.memory()
        spec.added_mass_inf()
        name, _ = convolution_or_state_space(model, dt=DT, n_steps=N_STEPS)   # no fit needed
        if name == "convolution":
            n = max(int(-(-T_K // DT)), 2) + 1           # HydroSpec.kernel's lags
            if path.name in RIGHTLY_WARNED:
                with pytest.raises(HydroDatabaseWarning, match="too coarse"):
                    spec.check_grid((n - 1) * DT)
                return
            spec.check_grid((n - 1) * DT)
    assert path.name not in RIGHTLY_WARNED, "fixed: drop it from RIGHTLY_WARNED"
