"""Time of the radiation state-space fit (``m.hydro.state_space()``, defaults) per config (not a test).

    OMP_NUM_THREADS=1 nice -n 10 python benchmarks/fit_speed.py [--repeats 1] [--options "{...}"] [config ...]

For each config (default: RM3, Stansby–Li, Hallak FWWP, Wu & Yuan model 1, M4 111, 132, 134): the
wall time of a fresh fit (the K(t) transform, the fit, the passivity enforcement: all of
``fit_state_space``; the database is read before the clock starts), its states, pole sharing,
order, band error against the database and the passivity check. With ``--repeats n`` the median
of n fresh fits. One process, one fit at a time: the numbers are for a quiet core. The code
timed is the ``hydro`` on the path (printed): to time another commit, put its tree first on
PYTHONPATH (``git archive <commit> | tar -x -C /tmp/base; PYTHONPATH=/tmp/base python
benchmarks/fit_speed.py``; the configs and databases are this checkout's).
"""
import argparse
import ast
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
CONFIGS = Path(__file__).resolve().parents[1] / "configs"
DEFAULT = ["rm3", "stansby_li", "hallak_fwwp", "wu_yuan_m1", "m4_111", "m4_132", "m4_134"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("configs", nargs="*", default=DEFAULT)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--options", default="{}",
                    help="fit options as a Python dict literal, e.g. \"{'target': 0.02}\"")
    args = ap.parse_args()
    options = ast.literal_eval(args.options)
    print(f"hydro from {Path(hydro.__file__).parent}")
    print(f"{'config':<12} {'fit s':>7} {'states':>6} {'sharing':>7} {'order':>5} {'band err':>8} "
          f"{'passive':>7} {'min eig':>9} {'enf it':>6}")
    for name in args.configs:
        times = []
        for _ in range(args.repeats):
            m = mfm.load(CONFIGS / f"{name}.toml")
            m.hydro.database()
            if "hydro.fitcache" in sys.modules:   # fits kept by content in the process
                sys.modules["hydro.fitcache"].clear()
            t0 = time.perf_counter()
            ss = m.hydro.state_space(**options)
            times.append(time.perf_counter() - t0)
        r = ss.report
        print(f"{name:<12} {statistics.median(times):7.2f} {r['n_states']:6d} {r['pole_sharing']:>7} "
              f"{max(r['orders'].values()):5d} {r['overall_error']:8.4f} {str(r['passive']):>7} "
              f"{r['passivity_min_eig']:9.1e} {r['passivity_enforcement_iterations']:6d}", flush=True)


if __name__ == "__main__":
    main()
