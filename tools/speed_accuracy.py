"""The speed–accuracy chart of the engine (issue 14 item 1), from the command line: for three
systems, every integrator × time step, radiation models and fidelity levels, the error against a
reference solution against the warm wall time, with the Pareto front. The study, its grid, its
reference and its measures are mfm/studies/speed_accuracy.py (its docstring says exactly what is
run and measured); this script runs it per system and draws the figures. From the repository
root, with mfm installed (the script does not touch sys.path):

    python tools/speed_accuracy.py rm3          # 28 min on 2 shared cores (load 5–6)
    python tools/speed_accuracy.py m4_134       # 44 min (10 of them the convolution)
    python tools/speed_accuracy.py stansby_li   # ≈ 30 min
    python tools/speed_accuracy.py figures      # the PNGs from the stored numbers
    python tools/speed_accuracy.py stansby_li --slices integrators   # one slice

Each system's cases go to notebooks/figures/speed_accuracy/<system>.json as they finish (a rerun
skips the cases already there: delete the file to start afresh), the figures to
notebooks/figures/speed_accuracy/<system>.png. notebooks/speed_accuracy.ipynb reads them.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from mfm.studies.speed_accuracy import SYSTEMS, figure, study

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "notebooks" / "figures" / "speed_accuracy"


def main(argv):
    if not argv or argv[0] not in tuple(SYSTEMS) + ("figures",):
        print(__doc__)
        return 2
    OUT.mkdir(parents=True, exist_ok=True)
    if argv[0] == "figures":
        import matplotlib
        matplotlib.use("Agg")
        for system in SYSTEMS:
            p = OUT / f"{system}.json"
            if p.exists():
                figure(json.loads(p.read_text()), OUT / f"{system}.png")
                print("wrote", OUT / f"{system}.png")
        return 0
    slices = None
    if "--slices" in argv:       # e.g. --slices integrators,radiation: only these (and the reference)
        slices = tuple(argv[argv.index("--slices") + 1].split(","))
    start = time.perf_counter()
    study(argv[0], path=OUT / f"{argv[0]}.json", slices=slices, log=lambda s: print(s, flush=True))
    print(f"{argv[0]}: {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
