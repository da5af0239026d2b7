"""What each rung of the fidelity ladder changes in Wu & Yuan's line tensions (issue 53 item 4):
``mfm.reduce`` on model 1 with its time-domain database (configs/wu_yuan_m1_td.toml: the band
0.25–3 rad/s; the seed's 10-frequency database gives no K(t)), its six catenary lines, in two
scenes, each
level's error in the mean PTO power, the mean and standard deviation of every line's fairlead
tension against the full model (RK4, radiation "auto") over the pilot's settled part:

- the seed's H 3.8 m, T 8 s head sea with the twelve WECs working (their PTOs);
- the seed's severe sea, H 8.1 m, T 11.4 s, every hinge locked (the locked layout of
  mfm.studies.wu_yuan_layout.config_text on the same database).

Not a test; the table is in docs/fidelity.md ("Line tensions"). From the repository root, with mfm
installed:

    python tools/reduce_tensions.py          # about 2.5 minutes on 2 cores
"""
import argparse
import tempfile
import time
import warnings
from pathlib import Path

import hydro
import mfm
from mfm.studies import wu_yuan_layout as layout
from mfm.studies.wu_yuan import SEVERE

ROOT = Path(__file__).resolve().parents[1]


def locked_model():
    """Model 1 with every hinge locked, on the time-domain database."""
    text = layout.config_text(1, locked=True)
    rel = '"../hydro/data/wu_yuan_m1.nc"'
    if rel not in text:
        raise RuntimeError(f"mfm.studies.wu_yuan_layout no longer names the database as {rel}")
    text = text.replace(rel, '"' + (ROOT / "hydro" / "data" / "wu_yuan_m1_td.nc").as_posix() + '"')
    path = Path(tempfile.mkdtemp(prefix="wu_yuan_locked_td_")) / "wu_yuan_m1_locked_td.toml"
    path.write_text(text)
    return mfm.load(path)


def table(name, red):
    print(f"\n## {name}: reduce chose {red.level!r}\n{red.reason}\n")
    levels = list(red.errors)
    keys = [k for k in red.errors[levels[0]]]
    print("| measure | " + " | ".join(levels) + " |")
    print("|---|" + "---|" * len(levels))
    for k in keys:
        print(f"| {k} | " + " | ".join(f"{red.errors[lv][k]:.2%}" for lv in levels) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--severe", action="store_true", help="also the severe sea, hinges locked")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    scenes = [("H 3.8 m, T 8 s, WECs working", mfm.load(ROOT / "configs" / "wu_yuan_m1_td.toml"),
               hydro.Regular(height=3.8, period=8.0)),
              (f"H {SEVERE[0]} m, T {SEVERE[1]} s, hinges locked", locked_model(),
               hydro.Regular(height=SEVERE[0], period=SEVERE[1]))][:2 if args.severe else 1]
    for name, model, sea in scenes:
        start = time.perf_counter()
        red = mfm.reduce(model, sea, timing=False)
        table(name, red)
        print(f"\n({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
