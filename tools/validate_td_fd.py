"""Time domain against the frequency domain of the same model: a table of errors (not a test;
tests/test_water.py asserts the 0.5 % bounds).

    python tools/validate_td_fd.py

For RM3 (regular wave H 0.2 m, T 8 s) coupled and uncoupled, with convolution and with state space,
and the sphere (H 0.05 m, T 3 s): the complex amplitude of each coordinate over the last 10 periods
of a 60-period run at dt = T/100, against frequency_response with the same radiation model and with
the raw database A(ω), B(ω). Prints |x_TD/x_FD − 1|.
"""
import argparse
import math
import os
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def harmonic(t, y, w, extra):
    cols = [np.ones_like(t), t, np.cos(w * t), np.sin(w * t)]
    for wn in extra:
        cols += [np.cos(wn * t), np.sin(wn * t), t * np.cos(wn * t), t * np.sin(wn * t)]
    c = np.linalg.lstsq(np.stack(cols, 1), y, rcond=None)[0]
    return c[2] + 1j * c[3]


def row(model, T, H, radiation, label):
    w = 2 * math.pi / T
    same = mfm.frequency_response(model, [w], radiation=radiation)
    raw = mfm.frequency_response(model, [w])
    ds = mfm.simulate(model, hydro.Regular(height=H, period=T), duration=60 * T, dt=T / 100,
                      ramp=5 * T, radiation=radiation)
    wn = mfm.natural_frequencies(model)["eigen"].values
    wn = wn[np.abs(wn - w) > 0.1 * w]
    t = ds.time.values
    sel = t > t[-1] - 10 * T
    errs = []
    for c in model.coordinates:
        x = harmonic(t[sel], ds.q.sel(coordinate=c).values[sel], w, wn)
        errs.append((c, abs(x / (complex(same.rao.sel(coordinate=c)[0]) * H / 2) - 1),
                     abs(x / (complex(raw.rao.sel(coordinate=c)[0]) * H / 2) - 1)))
    print(f"{label:<34s} " + "  ".join(f"{c}: {a:.1e} / {b:.1e}" for c, a, b in errs))


def main():
    print("|x_TD/x_FD − 1| per coordinate: against FD of the same radiation model / of the raw database")
    for coupling in (True, False):
        m = mfm.load(CONFIGS / "rm3.toml", body_coupling=coupling)
        for rad in ("convolution", "state_space"):
            row(m, 8.0, 0.2, rad, f"RM3 {'coupled' if coupling else 'uncoupled'} {rad}")
    m = mfm.load(CONFIGS / "sphere.toml")
    for rad in ("convolution", "state_space"):
        row(m, 3.0, 0.05, rad, f"sphere {rad}")


if __name__ == "__main__":
    # no options: --help prints what the script does instead of running it
    argparse.ArgumentParser(description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    main()
