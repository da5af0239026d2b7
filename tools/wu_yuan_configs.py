"""Write configs/wu_yuan_m1.toml … wu_yuan_m5.toml: the Wu & Yuan semi-sub energy platform with 12
hinged WECs (seed 004; GEOMETRY.md §4) at the five WEC spacings L = 2D … 3D of the seed's Table 4;
configs/wu_yuan_m1_td.toml, model 1 with a band database for the time domain (K(t)); and
configs/wu_yuan_wec.toml, one WEC alone hinged at a fixed point (P_s of the interaction factors).

The layout, the values (tagged as docs/GEOMETRY.md §4) and the configs' texts are
mfm/studies/wu_yuan_layout.py, their single source: edit it, then rerun this script. Run from the
repository root, with mfm installed (the script does not touch sys.path):

    python tools/wu_yuan_configs.py          # (re)writes the configs
    python tools/wu_yuan_configs.py --check  # exits 1 if a config differs from what it would write

The configs go to this checkout's configs/ (``python -m mfm.studies.wu_yuan_layout [--check]``
does the same for the checkout mfm is imported from).
"""
from __future__ import annotations

import sys
from pathlib import Path

from mfm.studies.wu_yuan_layout import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:], root=Path(__file__).resolve().parents[1]))
