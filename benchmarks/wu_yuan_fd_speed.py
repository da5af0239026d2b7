"""Wu & Yuan: the cost of the five models × ten periods in the frequency domain (issue 12's speed
aim: ≤ 5 s once the databases exist), first call (compilation included) and warm apart.

    python benchmarks/wu_yuan_fd_speed.py [--models 1 2 3 4 5] [--repeats 5]

Per model: mfm.load (MoorPy tables, the database), the first mfm.frequency_response at the
seed's ten periods (the linearisation compiles), and the median of ``--repeats`` warm calls;
then the sum over the models. Each model compiles its own linearisation: the database rides on
the model as identity-hashed static data (hydro.prepare.HydroSpec), so five spacings of one
topology are five compilations (issue 13).
"""
import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
from timing import first_and_warm  # noqa: E402  (benchmarks/timing.py, beside this script)


def main(argv=None) -> int:
    import mfm
    from hydro.database import HydroDatabaseWarning
    from mfm.studies.wu_yuan import seed_periods

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", HydroDatabaseWarning)
    w = 2 * np.pi / seed_periods()
    rows = []
    for k in args.models:
        t0 = time.perf_counter()
        model = mfm.load(ROOT / "configs" / f"wu_yuan_m{k}.toml")
        load = time.perf_counter() - t0
        first, warm = first_and_warm(lambda: mfm.frequency_response(model, w, 0.0, joint_reactions=False),
                                     args.repeats)
        rows.append((k, load, first, warm))
        print(f"model {k}: load {load:.1f} s, first frequency_response {first:.1f} s, "
              f"warm {warm * 1e3:.0f} ms (median of {args.repeats}; {w.size} periods)", flush=True)
    tot = np.sum([r[1:] for r in rows], axis=0)
    print(f"{len(rows)} models × {w.size} periods: load {tot[0]:.1f} s + first {tot[1]:.1f} s; "
          f"warm {tot[2]:.2f} s in all")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
