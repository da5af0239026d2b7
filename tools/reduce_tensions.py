"""What each rung of the fidelity ladder changes in Wu & Yuan's line tensions (issue 53 item 4):
``mfm.reduce`` on model 1 (configs/wu_yuan_m1.toml, the six catenary lines) in two scenes, each
level's error in the mean PTO power, the mean and standard deviation of every line's fairlead
tension against the full model (RK4, radiation "auto") over the pilot's settled part:

- the seed's H 3.8 m, T 8 s head sea with the twelve WECs working (their PTOs);
- the seed's severe sea, H 8.1 m, T 11.4 s, every hinge locked (mfm.studies.wu_yuan.platform_model).

Not a test; the table is in docs/fidelity.md ("Line tensions"). From the repository root, with mfm
installed:

    python tools/reduce_tensions.py          # about 10 minutes on 2 shared cores
"""
import time
import warnings

import hydro
import mfm
from mfm.studies.wu_yuan import SEVERE, platform_model


def table(name, red):
    print(f"\n## {name}: reduce chose {red.level!r}\n{red.reason}\n")
    levels = list(red.errors)
    keys = [k for k in red.errors[levels[0]]]
    print("| measure | " + " | ".join(levels) + " |")
    print("|---|" + "---|" * len(levels))
    for k in keys:
        print(f"| {k} | " + " | ".join(f"{red.errors[lv][k]:.2%}" for lv in levels) + " |")


def main():
    warnings.simplefilter("ignore")
    scenes = [("H 3.8 m, T 8 s, WECs working", platform_model(1), hydro.Regular(height=3.8, period=8.0)),
              (f"H {SEVERE[0]} m, T {SEVERE[1]} s, hinges locked", platform_model(1, locked=True),
               hydro.Regular(height=SEVERE[0], period=SEVERE[1]))]
    for name, model, sea in scenes:
        start = time.perf_counter()
        red = mfm.reduce(model, sea, timing=False)
        table(name, red)
        print(f"\n({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
