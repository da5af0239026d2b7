"""The mean drift check database: a fixed vertical cylinder (radius 1 m, draft 8 m, deep water),
its far-field mean drift by capytaine 3.0 (``hydro.bem.solve(drift="fixed")``), written to
hydro/data/drift_cylinder.nc for tests/test_drift_53.py, which compares it with Havelock's
closed form for a vertical cylinder of infinite draft (MacCamy–Fuchs diffraction, near-field
pressure integration). 8 m of draft is infinite here: the waves' e^{2kz} at the keel is
e^{-2 k d} <= 1.5e-3 at the lowest omega (2 rad/s, k = 0.41 /m).

    PYTHONPATH=. python tools/drift_cylinder.py [--dx 0.18] [--out hydro/data/drift_cylinder.nc]

Cost: 1,836 hull + 216 lid panels, rotation symmetry, 4 frequencies x 2 headings: about 10 s on
one thread.
"""
import argparse
import time
from pathlib import Path

import numpy as np

from hydro import bem

OMEGA = [2.0, 2.5, 3.0, 3.5]                     # rad/s: kR 0.41 ... 1.25
HEADINGS = [0.0, np.pi / 2]                     # rad: the second checks the drift turns with the waves
SPEC = {"name": "cylinder", "shape": "cylinder", "radius": 1.0, "draft": 8.0,
        "reference_point": [0.0, 0.0, 0.0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.18, help="panel size, m")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "hydro" / "data"
                                         / "drift_cylinder.nc"))
    args = ap.parse_args()
    t0 = time.perf_counter()
    ds = bem.solve([SPEC], omega=OMEGA, dx=args.dx, wave_directions=HEADINGS, rho=1000.0, g=9.81,
                   drift="fixed", cache=False, progress=False, n_threads=1)
    ds.attrs["generated_by"] = f"PYTHONPATH=. python tools/drift_cylinder.py --dx {args.dx}"
    bem.save(ds, args.out)
    D = ds["mean_drift"].sel(wave_direction=0.0, influenced_dof="cylinder__Surge").values
    print(f"wrote {args.out} in {time.perf_counter() - t0:.1f} s: surge drift / (rho g R) at "
          f"omega {OMEGA}: {np.round(D[:len(OMEGA)] / (1000.0 * 9.81), 4).tolist()}")


if __name__ == "__main__":
    main()
