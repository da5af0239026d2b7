"""`mfm info` and the `mfm simulate` run summary name the same free coordinates, for every
shipped config: info's line on restoring against the summary line of a one-step run in regular
waves without a ramp (the excitation at t = 0 must not count as restoring), plus the smallest
restoring diagonal K_kk / max|K| (the margin of :func:`mfm.frequency.rest.free_coordinates`'s 1e-9).
Prints a table; exits 1 if any line differs. Minutes per large config (loading, compiling).

    python tools/restoring_check.py [configs/rm3.toml ...]      (default: every configs/**/*.toml)

Measured 2026-11-23 (`OMP_NUM_THREADS=1 nice -n 10 python tools/restoring_check.py`, stopped after
9 min on the shared 2-core machine; the first six configs, same line from both everywhere):

    config                              mfm info / run summary   min K_kk/max|K|
    configs/double_pendulum.toml        none                     2.50e-01
    configs/hallak_fowt.toml            none                     2.03e-03
    configs/hallak_fwwp.toml            none                     1.76e-03
    configs/hallak_hydro_coupled.toml   none                     1.50e-06
    configs/hallak_wec.toml             none                     9.72e-03
    configs/m4_111.toml                 float1.surge             2.24e-01

RM3 (spar.surge) and the slider on a pendulum are in tests/test_new_user.py.
"""
from __future__ import annotations

import contextlib
import io
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def main(paths):
    import hydro
    import mfm
    from mfm.io.cli import _restoring_text
    from mfm_cli import main as cli
    from mfm.frequency.rest import linearised_at_rest
    from mfm.timedomain.setup import model_loads

    warnings.simplefilter("ignore")
    bad = 0
    print(f"{'config':<42s} {'mfm info':<16s} {'run summary':<16s} {'min K_kk/max|K|':>15s}")
    for path in paths:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert cli(["info", str(path)]) == 0
        info, = [ln for ln in out.getvalue().splitlines() if "has restoring" in ln or "restoring in" in ln]
        model = mfm.load(path)
        sea, dt = None, 0.01
        if model.hydro is not None:
            om = np.asarray(model.hydro.database()["omega"].values)
            T = 2 * np.pi / float(np.median(om))
            sea, dt = hydro.Regular(height=0.01 * T**2, period=T), T / 50
        ds = mfm.simulate(model, sea, duration=dt, dt=dt, ramp=0.0, radiation="none")
        summary = "  " + _restoring_text(ds.attrs["no_restoring"])
        _, K = linearised_at_rest(model, np.zeros(model.n_coordinates),
                                  model_loads(model, None, dt=1.0, duration=1.0, radiation="none"))
        d = np.diag(K) / np.abs(K).max()
        margin = d[d > 1e-9].min() if (d > 1e-9).any() else float("nan")
        same = summary == info
        bad += not same
        name = lambda s: s.split(" (at q0)")[0].removeprefix("  no restoring in ") if "no restoring" in s else "none"  # noqa: E731
        print(f"{str(path.relative_to(ROOT)):<42s} {name(info):<16s} {name(summary):<16s} {margin:15.2e}"
              + ("" if same else "   DIFFERENT"), flush=True)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main([Path(a).resolve() for a in sys.argv[1:]] or sorted((ROOT / "configs").glob("**/*.toml"))))
