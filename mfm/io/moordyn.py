"""MoorDyn v2 input files (an export format): catenary lines as MoorDyn's lumped-mass lines, one line
type, fixed anchors and coupled fairleads whose motion the caller prescribes each coupling step.

Plain text from the lines' data; writing needs nothing beyond the standard library (running the
file needs the optional ``moordyn`` package, ``pip install -e .[moordyn]``). Used by
tools/moordyn_check.py (the Wu & Yuan lines against MoorDyn in the severe sea) and
tests/test_catenary.py (MoorDyn's slow limit is the quasi-static line).

Units SI: positions in m (inertial axes, z up), lengths in m, EA in N, weights in N/m.
"""
from __future__ import annotations

import math

# a studless chain's usual hydrodynamic coefficients (DNV / OrcaFlex and MoorPy's chain defaults,
# referred to the nominal diameter): normal drag, axial drag, normal added mass, axial added mass
CHAIN = {"Cd": 2.4, "CdAx": 1.15, "Ca": 1.0, "CaAx": 0.5}

TITLE = "catenary lines, written by mfm.io.moordyn"


def moordyn_input(anchors, fairleads, length, EA, weight, rho, g, depth, segments, drag, dtM, *,
                  diameter, coefficients=None, title=TITLE):
    """A MoorDyn v2 input file: one line type, fixed anchors, coupled fairleads.

    anchors, fairleads: (n, 3) positions (m), line k from anchor k to fairlead k; length (m), EA
    (N) and weight (N/m, in water) of every line; rho (kg/m³), g (m/s²), depth (m, MoorDyn's
    WtrDpth); segments per line; drag: a factor on the drag coefficients (Cd and CdAx); dtM (s):
    MoorDyn's own time step. diameter (m): the volume-equivalent diameter MoorDyn takes; the mass
    per length in air written is weight / g + ρ π D² / 4, so that the wet weight is ``weight``
    exactly. coefficients: {"Cd", "CdAx", "Ca", "CaAx"} (default :data:`CHAIN`). Internal damping
    80 % of critical per segment (BA = −0.8), seabed contact stiffness 3e6 Pa/m and damping
    3e5 Pa s/m (MoorDyn's defaults), no friction; MoorDyn's dynamic relaxation for the initial
    state (ICgenDynamic, up to 300 s), no output files. ``title``: the file's second line."""
    c = CHAIN if coefficients is None else coefficients
    mass = weight / g + rho * math.pi * diameter ** 2 / 4          # kg/m in air: the wet weight kept
    pts, lines = [], []
    for k, (a, f) in enumerate(zip(anchors, fairleads)):
        pts.append(f"{2 * k + 1} Fixed {a[0]:.9f} {a[1]:.9f} {a[2]:.9f} 0 0 0 0")
        pts.append(f"{2 * k + 2} Coupled {f[0]:.9f} {f[1]:.9f} {f[2]:.9f} 0 0 0 0")
        lines.append(f"{k + 1} chain {2 * k + 1} {2 * k + 2} {length:.6f} {segments} -")
    return f"""--------------------- MoorDyn Input File ------------------------------------
{title}
---------------------- LINE TYPES ----------------------------------------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI         Cd     Ca     CdAx    CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (N-m^2)    (-)    (-)    (-)     (-)
chain {diameter} {mass:.6f} {EA:.6e} -0.8 0 {c['Cd'] * drag} {c['Ca']} {c['CdAx'] * drag} {c['CaAx']}
---------------------- POINTS ---------------------------------------
ID   Attachment  X       Y     Z      Mass   Volume  CdA    Ca
(#)   (word/ID) (m)     (m)   (m)    (kg)   (m^3)   (m^2)  (-)
{chr(10).join(pts)}
---------------------- LINES ----------------------------------------
ID   LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#)   (name)     (ID)     (ID)      (m)       (-)      (-)
{chr(10).join(lines)}
---------------------- OPTIONS -----------------------------------------
0             writeLog
1             disableOutput
1             disableOutTime
{dtM}         dtM
3.0e6         kbot
3.0e5         cbot
{depth}       WtrDpth
{rho}         rho
{g}           g
1             ICgenDynamic
1.0           dtIC
300           TmaxIC
1e-5          threshIC
---------------------- OUTPUTS -----------------------------------------
------------------------- need this line -------------------------------------
"""
