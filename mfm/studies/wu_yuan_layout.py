"""The Wu & Yuan semi-sub energy platform with 12 hinged WECs (2025; GEOMETRY.md §4): its layout
and data, and the configs written from them: configs/wu_yuan_m1.toml … wu_yuan_m5.toml at the
five WEC spacings L = 2D … 3D of the seed's Table 4; configs/wu_yuan_m1_td.toml, model 1 with a
band database for the time domain (K(t)); and configs/wu_yuan_wec.toml, one WEC alone hinged at
a fixed point (P_s of the interaction factors, :mod:`mfm.studies.wu_yuan`).

The five files are identical except the spacing-dependent positions (WEC centres, hinge points,
the model's name and its database); the loader has no way to share tables between configs, so
this module is their single source (values tagged as docs/GEOMETRY.md §4). From the repository
root (the configs' headers name the command)::

    python tools/wu_yuan_configs.py          # (re)writes the configs
    python tools/wu_yuan_configs.py --check  # exits 1 if a config differs from what it would write

(or ``python -m mfm.studies.wu_yuan_layout [--check]``, the same :func:`main`). Writing and
checking need a checkout (configs/ is not installed with the package); the layout and the texts
(:func:`wecs`, :func:`columns`, :func:`config_text`, :func:`wec_config_text`) do not.

Layout (heading 0 = waves travelling to +x):
- three columns at radius 47 m, column 1 (apex) on +x, columns 2 and 3 at ±120°;
- three rows of four WECs along the three sides; row 3 on the −x side (upwave), its hinge axis
  along y; rows 1 and 2 are row 3 rotated about z by +120° and −120° (row 1 on the −60° side,
  row 2 on the +60° side); within each row the WECs are numbered with y ascending in row 3's frame
  (WEC 9 at y = −1.5 L … WEC 12 at +1.5 L), and each rotated copy keeps that order;
- row 2 is written as the exact mirror image (y → −y) of row 1 (the same as the −120° rotation
  to round-off), so that the BEM sees a layout mirror-symmetric about y = 0 to the last bit.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]      # the repository (configs/), in a checkout

# ---- values (tags as GEOMETRY.md §4) -----------------------------------------------------------
D_WEC = 8.0                 # m WEC diameter [S]
SPACINGS = (2.0, 2.25, 2.5, 2.75, 3.0)   # L / D, models 1–5 [S]
R_COL_CENTRES = 47.0        # m [A]
R_COL = 15.05 / 2           # m [A] column radius
DRAFT_COL = 30.0            # m [S]
R_WEC, DRAFT_WEC = 4.0, 2.0  # m [S] radius; draft [S]; flat cylinder [A]
M_WEC = 1.1136e5            # kg [S]
I_WEC = (6.800e5, 9.545e5, 1.054e6)   # kg m² roll, pitch, yaw in the WEC's own axes [S]
ARM = 9.72                  # m hinge → CoG horizontally [S]
Z_HINGE = 5.44              # m above water [S]
C_PTO = 4.1e7               # N m s/rad [S]
RHO, G = 1025.0, 9.81       # [A]
DEPTH = 60.0                # m [S: anchors 60 m below water]
PERIODS = (5.0, 6.0, 7.0, 8.0, 8.3, 9.0, 10.0, 11.0, 11.4, 12.0)   # s [S]
DX_COL, DX_WEC = 2.0, 0.8   # m panel sizes [D]
TD_BAND = (0.25, 3.0, 56)   # rad/s: the time domain's band database (omega_min, omega_max, n) [D]
TD_STEP = (TD_BAND[1] - TD_BAND[0]) / (TD_BAND[2] - 1)
TD_MODELS = (1,)            # the models with a time-domain twin (wu_yuan_m<m>_td.toml)
WEC_HEADINGS = (-120.0, 0.0, 120.0)   # deg: the lone WEC's database (rows 2, 3, 1; see wec_config_text)
# the lone WEC's band for the time domain (omega_min, omega_max, n) [D]: step 0.05 rad/s (widest
# step left beside a seed period 0.059 rad/s: K(t) resolved to π/0.059 = 53 s; wec_omega_list);
# up to 2.5 rad/s, below the hull's first irregular frequency (2.66 rad/s), as there is no lid
WEC_BAND = (0.2, 2.5, 47)


def panel_radius(r, dx):
    """The radius whose panelled hull (a regular n-gon prism, vertices on the circle, n from
    hydro.geometry.n_azimuth) has the water-plane area and volume of the circle of radius r:
    the BEM's buoyancy (mfm takes ρgV from the database) is then the exact hull's."""
    from hydro import geometry as geo

    def n_of(rr):
        return geo.n_azimuth(geo.normalize_spec({"name": "h", "shape": "cylinder", "radius": rr,
                                                 "draft": 1.0, "base": "flat"}), dx)
    n = n_of(r)
    re = r * math.sqrt(math.pi / (n / 2 * math.sin(2 * math.pi / n)))
    assert n_of(re) == n, (r, dx)
    return round(re, 4), n

# the preload that holds the stated 2 m draft [D]: (m − ρ π R² T) g × arm
M_DISPLACED = RHO * math.pi * R_WEC ** 2 * DRAFT_WEC
PRELOAD = (M_WEC - M_DISPLACED) * G * ARM

# ---- geometry ----------------------------------------------------------------------------------


def rot(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def columns():
    y = R_COL_CENTRES * math.sin(math.radians(120.0))
    x = R_COL_CENTRES * math.cos(math.radians(120.0))
    return [("column1", np.array([R_COL_CENTRES, 0.0, 0.0])), ("column2", np.array([x, y, 0.0])),
            ("column3", np.array([x, -y, 0.0]))]


def x_hinge_row3():
    """Row 3's hinge line: the line joining the outer (−x) faces of columns 2 and 3 [A]."""
    return R_COL_CENTRES * math.cos(math.radians(120.0)) - R_COL


def wecs(L):
    """[(name, row, centre (3,), hinge (3,), axis (3,), x′ direction (3,))] for spacing L (m)."""
    xh = x_hinge_row3()
    row3 = []
    for k in range(4):
        y = (k - 1.5) * L
        row3.append((np.array([xh - ARM, y, 0.0]), np.array([xh, y, Z_HINGE]),
                     np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, 0.0])))
    R1 = rot(120.0)
    row1 = [tuple(R1 @ v for v in w) for w in row3]
    M = np.diag([1.0, -1.0, 1.0])
    # row 2 = row 3 rotated by −120° = the mirror image of row 1 in reverse order (positions exact
    # mirrors; the hinge axis, a direction along the row, is rotated, not mirrored)
    R2 = rot(-120.0)
    row2 = []
    for k in range(4):
        c1, h1, _, _ = row1[3 - k]
        _, _, a3, x3 = row3[k]
        row2.append((M @ c1, M @ h1, R2 @ a3, R2 @ x3))
    out = []
    for r, row in ((1, row1), (2, row2), (3, row3)):
        for k, w in enumerate(row):
            out.append((f"wec{4 * (r - 1) + k + 1}", r, *w))
    return out


def inertia(xdir):
    """Table 3's inertia (x′ along the arm, z′ up) in inertial axes [D]."""
    phi = math.atan2(xdir[1], xdir[0])
    R = rot(math.degrees(phi))
    return R @ np.diag(I_WEC) @ R.T


def clearances(L):
    """Smallest gaps (m) between WEC rims and column walls, and between WEC rims."""
    w = wecs(L)
    cols = columns()
    wc = min(np.hypot(*(c[:2] - p[:2])) - R_WEC - R_COL for _, _, c, *_ in w for _, p in cols)
    ww = min(np.hypot(*(a[2][:2] - b[2][:2])) - 2 * R_WEC
             for i, a in enumerate(w) for b in w[i + 1:])
    return wc, ww


# ---- writing -----------------------------------------------------------------------------------


def f(v, nd=6):
    """A float for TOML: round to nd decimals, no '-0.0'."""
    v = round(float(v), nd)
    return repr(0.0 if v == 0 else v)


def vec(v, nd=6):
    return "[" + ", ".join(f(a, nd) for a in v) + "]"


def omega_list():
    """The seed's ten ω = 2π/T (rad/s, rounded to 1e-6, ascending): the frequency-domain databases'."""
    return sorted(round(2 * math.pi / T, 6) for T in PERIODS)


def wec_omega_list():
    """The lone WEC's ω (rad/s, ascending): the seed's ten (:func:`omega_list`, exactly) and the
    band WEC_BAND, less each band point within a quarter step of a seed ω (so no two frequencies
    are closer than that; the widest step is then at most 1.25 steps)."""
    lo, hi, n = WEC_BAND
    seed = omega_list()
    step = (hi - lo) / (n - 1)
    band = [round(lo + k * step, 6) for k in range(n)]
    keep = [w for w in band if min(abs(w - s) for s in seed) > step / 4]
    return sorted(seed + keep)


def lines():
    out = []
    for g in range(3):
        for d in (-2.5, 2.5):
            a = math.radians(120 * g + d)
            c, s = math.cos(a), math.sin(a)
            out.append((f"line{len(out) + 1}", 120 * g + d, [54.5 * c, 54.5 * s, 15.0],
                        [830.0 * c, 830.0 * s, -60.0]))
    return out


HEADER = """\
# Semi-sub energy harvesting platform with 12 hinged point absorbers, model {m} (L = {ld:g} D = {L:g} m):
# H. Wu, Z. Yuan, "WEC spacing effects on the performance of a floating energy harvesting
# platform", Ocean Engineering (2025) (docs/references.md). Values tagged as in
# docs/GEOMETRY.md §4:
#   [S] stated in the seed, [D] derived from stated values, [A] assumed (no source found).
# MADE BY tools/wu_yuan_configs.py (the five models share everything but the spacing-dependent
#   positions; edit the script and rerun it, not this file).
#
# Platform [S, Table 1]: draft 30 m, displacement 1.64e7 kg, mass 1.61e7 kg, CoG 9.68 m below the
#   water line, radii of gyration 37, 37, 20 m. The body "platform" (dry, the root) carries all of
#   it; the hull is not published [A, checked]: three flat-bottomed columns D 15.05 m, draft 30 m,
#   centres at radius 47 m, column 1 (apex) on +x, massless hulls welded to the platform. They
#   displace 3 π 7.525² 30 × 1025 = 1.6411e7 kg (Table 1: 1.64e7) and put the column faces at
#   54.525 m (the fairlead radius, 54.5 m). Pontoons and braces: none [A].
# Degrees of freedom: the platform's 6 (the moorings restrain surge, sway and yaw; the water heave,
#   roll and pitch) + one hinge angle per WEC: 18 coordinates.
# Environment: ρ 1025 kg/m³ [A: "sea water"], g 9.81 [A], depth 60 m [S: anchors 60 m below the
#   water line], heading 0 = waves travelling to +x, from row 3 towards column 1 [S/A].
# Moorings [S, Table 2]: six catenary lines, 3 groups at 120° (at the columns: 0°, 120°, 240°) [A:
#   the groups' bearings], ±2.5° within a group; fairleads 15 m above water at radius 54.5 m;
#   anchors 60 m below water at radius 830 m; length 800 m; 0.303 t/m in water; EA 1.243e6 kN;
#   quasi-static MoorPy tables (mfm.loads.catenary), no seabed friction [A]. At rest per line
#   H ≈ 390 kN, T ≈ 613 kN; six vertical loads ≈ 289 t [D].
# WECs [S, Table 3]: 1.1136e5 kg, R 4 m, draft 2 m, top 2 m above water, CoG at the water line;
#   shape not stated: flat vertical cylinders [A]; inertias roll 6.800e5, pitch 9.545e5,
#   yaw 1.054e6 kg m² in the WEC's own axes (x′ along the arm, horizontal), rotated into each
#   row's axes here [D]. Each hinged to the platform (revolute) 9.72 m horizontally from its CoG
#   towards the platform and 5.44 m above water [S]. Each row's hinges lie on the line joining the
#   outer faces of that side's two columns [A] (row 3: x = {xh:.3f} m); WEC centres {xw:.3f} m.
# Layout [S/D]: rows of four, WECs spaced L = {ld:g} D = {L:g} m along each row, centred on the
#   side's midpoint [A]; row 3 (WECs 9–12) upwave on −x with its hinge axis along y; row 1
#   (WECs 1–4) = row 3 rotated by +120° (the −60° side), row 2 (WECs 5–8) = row 3 rotated by
#   −120° (the +60° side) [A: which copy is row 1]: axes at ±30° to x (Appendix A). Within a row
#   the WECs run with y ascending in row 3's frame (WEC 9 at y = −1.5 L) [A]. Mirror-symmetric
#   about y = 0 (row 2 is written as the exact mirror of row 1), so the BEM uses xOz symmetry.
#   Clearances here: WEC rim to column wall ≥ {cw:.2f} m, WEC rim to WEC rim ≥ {ww:.2f} m [D].
#   (docs/GEOMETRY.md's "the WECs clear the columns by 12.5 m" is model 1's gap, 12.48 m.)
# PTO [S]: rotary damper 4.1e7 N m s/rad on each hinge (joint damping); lock the hinges
#   (joint locked = true) for the severe sea.
# Hinge preload [D]: the WEC is heavier than the water it displaces at its stated 2 m draft
#   (1.1136e5 against ρ π 4² 2 = {md:.0f} kg); a constant torque of
#   ({mw:.0f} − {md:.0f}) × 9.81 × 9.72 = {pre:.4e} N m on each hinge ([[joint_loads]], positive
#   lifts the WEC) holds that draft in the static equilibrium (mfm.equilibrium) [D]. The platform
#   then carries the WECs' excess weight (12 × {dm:.0f} kg) on top of the lines' 289 t against its
#   300 t reserve: it settles ≈ 0.16 m below its 30 m draft (the seed's masses do not close; the
#   hinge angles take it up, the WECs keep their draft).
# Viscous damping: none (the seed's C_vis has no values) [A].
"""

BEM_NOTE_FD = """\
# BEM [D]: the ten periods of the seed (T = 5, 6, 7, 8, 8.3, 9, 10, 11, 11.4, 12 s) + ∞; finite
#   depth where kh < 5 (ω < 0.90 rad/s, T > 6.95 s), deep water above and at ∞; panels dx {dx_col:g} m on
#   the columns, {dx_wec:g} m on the WECs. The panelled hulls are regular polygons with their vertices on
#   the circle; each hull's radius here is the one whose {n_col}-gon (columns, {r_col:g} m) or {n_wec}-gon
#   (WECs, {r_wec:g} m) has the circle's area, so the database's volumes (from which mfm takes the
#   buoyancy) are the stated hulls' exactly (a 7.525 m 24-gon would lose 1.1 % of the displacement,
#   187 t: the platform would settle 0.34 m lower) [D]. No lid: the first irregular frequencies,
#   ω² = g k coth(k d) with k = 2.405 / a, are 1.77 rad/s (column) and 2.66 rad/s (WEC), above the
#   highest ω here (1.257 rad/s); xOz symmetry. One body per hull (15: 3 columns + 12 WECs), solved together.

"""

TABLES_FD = """\
[model]
name = "Wu-Yuan model {m}"
gravity = 9.81              # m/s² [A]
description = "Semi-sub energy platform with 12 hinged WECs, WEC spacing L = {ld:g} D (Wu & Yuan, model {m})"

[hydro]
database = "../hydro/data/wu_yuan_m{m}.nc"   # made by `mfm hydro configs/wu_yuan_m{m}.toml --threads 1`
body_coupling = true        # all interactions between the 15 hulls
rho = 1025.0                # kg/m³ [A]

[hydro.bem]
omega = {omega}   # rad/s: 2π/T, T = 12, 11.4, 11, 10, 9, 8.3, 8, 7, 6, 5 s [S]
headings_deg = [0.0]        # [S]
water_depth = 60.0          # m [S]
deep_water_kh = 5.0         # finite depth below kh = 5, deep water above [D]
dx = {dx_col}                    # m on the columns (the WECs set their own)
lid = false                 # first irregular frequencies 1.77 (column), 2.66 rad/s (WEC) > 1.257
symmetry = "auto"           # xOz (the layout mirrors about y = 0)
infinite_frequency = true

"""

BEM_NOTE_TD = """\
# THIS FILE is model {m} for the TIME DOMAIN: the same bodies, joints and loads as
#   configs/wu_yuan_m{m}.toml (which the frequency-domain study reads), with a database over a band
#   of frequencies for the radiation memory K(t) (mfm.simulate) instead of the seed's ten periods.
# BEM [D]: ω = {w_lo:g}, {w_2:g}, …, {w_hi:g} rad/s ({n_w}, step {dw:g} rad/s: K(t) sampled to
#   π/Δω = {tk:.0f} s) + ∞; finite depth where kh < 5 (ω < 0.90 rad/s), deep water above and at ∞;
#   panels as in wu_yuan_m{m}.toml: dx {dx_col:g} m on the columns ({n_col}-gons of radius {r_col:g} m,
#   the circle's area), {dx_wec:g} m on the WECs ({n_wec}-gons, {r_wec:g} m), so the band
#   database holds the frequency-domain database's hulls. Water-plane lids on every hull: the first
#   irregular frequencies, ω² = g k coth(k d) with k = 2.405 / a, are 1.77 rad/s (column) and
#   2.66 rad/s (WEC), inside the band. xOz symmetry. Panels per wavelength (deep water,
#   λ = 2π g / ω²): 5 panels of 2 m hold up to ω = 2.48 rad/s on the columns, 5 of 0.8 m up to
#   3.92 rad/s on the WECs; above 2.48 rad/s the columns' coefficients are coarser: one column
#   alone at 3.0 rad/s, dx 2 m against 1 m: surge damping +24 % (it is 10 % of its 1 rad/s
#   value there), pitch damping +12 %, surge excitation −4 % (2.0 rad/s: +7 %, +0.2 %, −4 %). Those
#   frequencies only shape K(t) near t = 0; the waves of the seed are below 1.26 rad/s. 1.4 m
#   panels on the columns (+8 % surge damping at 3 rad/s) would double the cost (≈ 1 h) [D].
#   (hydro/data/README.md)

"""

TABLES_TD = """\
[model]
name = "Wu-Yuan model {m} (time domain)"
gravity = 9.81              # m/s² [A]
description = "Semi-sub energy platform with 12 hinged WECs, WEC spacing L = {ld:g} D (Wu & Yuan, model {m}), band database for the time domain"

[hydro]
database = "../hydro/data/wu_yuan_m{m}_td.nc"   # made by `mfm hydro configs/wu_yuan_m{m}_td.toml --threads 1`
body_coupling = true        # all interactions between the 15 hulls
rho = 1025.0                # kg/m³ [A]

[hydro.bem]
omega_min = {w_lo}            # rad/s  }} the band of K(t) [D]
omega_max = {w_hi}             # rad/s  }}
n_omega = {n_w}                # step {dw:g} rad/s
headings_deg = [0.0]        # [S]
water_depth = 60.0          # m [S]
deep_water_kh = 5.0         # finite depth below kh = 5, deep water above [D]
dx = {dx_col}                    # m on the columns (the WECs set their own)
lid = true                  # first irregular frequencies 1.77 (column), 2.66 rad/s (WEC) in the band
symmetry = "auto"           # xOz (the layout mirrors about y = 0)
infinite_frequency = true

"""

PLATFORM = """\
# ---- the platform: a dry root with all the mass, and its three columns ------------------------

[[bodies]]
name = "platform"
notes = "Table 1's platform: mass, CoG and radii of gyration; its hull is the three columns"
mass = 1.61e7                        # kg [S]
com = [0.0, 0.0, -9.68]              # m [S]
radii_of_gyration = [37.0, 37.0, 20.0]   # m [S]
[bodies.joint]
type = "free"                        # 6 dofs: the lines restrain surge, sway, yaw
"""

COLUMN = """
[[bodies]]
name = "{name}"
notes = "{notes}"
mass = 0.0
com = {com}   # its hydro reference point: on its axis at the platform CoG's height
parent = "platform"
[bodies.joint]
type = "fixed"
[bodies.geometry]
shape = "cylinder"
radius = {r_col}                      # m: D 15.05 [A] as a {n_col}-gon of the same area [D]
draft = 30.0                         # m [S]
base = "flat"                        # [A]
"""

WEC = """
[[bodies]]
name = "{name}"
notes = "row {row}, WEC {k} of 4"
mass = 1.1136e5                      # kg [S]
com = {com}   # m: CoG at the water line [S]
inertia = {inertia}   # kg m² [S/D]
parent = "platform"
[bodies.joint]
type = "revolute"
axis = {axis}
point = {point}   # hinge: 9.72 m towards the platform, 5.44 m up [S]
damping = 4.1e7                      # N m s/rad, the PTO [S]
[bodies.geometry]
shape = "cylinder"
radius = {r_wec}                      # m: R 4 [S] as a {n_wec}-gon of the same area [D]
draft = 2.0                          # m [S]
base = "flat"                        # [A]
dx = {dx_wec}                             # m panels [D]
"""

LINE = """
[[catenary_lines]]
name = "{name}"
notes = "bearing {bearing:g}°"
body = "platform"
fairlead = {fairlead}   # m: radius 54.5 m, 15 m above water [S]
anchor = {anchor}   # m: radius 830 m, 60 m below water [S]
line_type = {line_type}
"""

LINE_TYPE_FIRST = ('{name = "chain", length = 800.0, mass_per_length = 303.0, EA = 1.243e9, '
                   'notes = "800 m, 0.303 t/m in water, EA 1.243e6 kN, D 0.12 m [S]"}')

LOCKED_NOTE = ("# SEVERE-SEA VARIANT (seed §4.3): every hinge locked, so no PTO damper and no preload;\n"
               "#   each WEC rigid on the platform at its design position (the text below on the\n"
               "#   preloads and the settling describes the operating model).\n")
WEC_DAMPER = "damping = 4.1e7                      # N m s/rad, the PTO [S]\n"
WEC_LOCKED = "locked = true                        # severe sea: the hinge locked [S]\n"
assert WEC_DAMPER in WEC
PRELOAD_ENTRY = """
[[joint_loads]]
name = "preload_{name}"
coordinate = "{name}.angle"
value = {value}   # N m [D]: holds the 2 m draft (positive lifts the WEC)
"""


DRIFT_MODELS = (1,)         # the models with a Kochin-function twin (wu_yuan_m<m>_drift.toml)
DRIFT_NOTE = """\
# MEAN-DRIFT TWIN: model {m} with its database made again with the layout's Kochin functions
#   ([hydro.bem] drift = "kochin": the same hulls, frequencies and solve as wu_yuan_m{m}.nc, plus the
#   far field of the diffraction and of every dof's radiation on 180 directions), from which
#   mfm.equilibrium(model, sea=...) takes the mean wave drift of the model's own motions
#   (mfm.frequency.drift; docs/nonlinear.md, "Mean wave drift").
"""


def config_text(m: int, td: bool = False, locked: bool = False, drift: bool = False) -> str:
    """The config of model m; ``td``: its time-domain twin (same bodies and loads, the band
    database ``wu_yuan_m<m>_td.nc``); ``drift``: its mean-drift twin (the same, its database
    ``wu_yuan_m<m>_drift.nc`` made with the Kochin functions as well: ``[hydro.bem] drift =
    "kochin"``); ``locked``: the severe-sea variant (seed §4.3: every hinge
    locked, so no PTO damper and no preload: each WEC rigid on the platform at its design
    position, the platform carrying its excess weight). Not written to configs/ (the same hulls
    and database as model m): :func:`mfm.studies.wu_yuan.platform_model` ``(m, locked=True)``
    loads it."""
    ld = SPACINGS[m - 1]
    L = ld * D_WEC
    cw, ww = clearances(L)
    r_col, n_col = panel_radius(R_COL, DX_COL)
    r_wec, n_wec = panel_radius(R_WEC, DX_WEC)
    xh = x_hinge_row3()
    values = dict(m=m, ld=ld, L=L, xh=xh, xw=xh - ARM, cw=cw, ww=ww, md=M_DISPLACED,
                  mw=M_WEC, pre=PRELOAD, dm=M_WEC - M_DISPLACED,
                  omega=vec(omega_list()), dx_col=DX_COL, r_col=r_col, n_col=n_col,
                  r_wec=r_wec, n_wec=n_wec, dx_wec=DX_WEC, w_lo=TD_BAND[0], w_hi=TD_BAND[1],
                  n_w=TD_BAND[2], w_2=TD_BAND[0] + TD_STEP, dw=TD_STEP, tk=math.pi / TD_STEP)
    parts = [(HEADER + (BEM_NOTE_TD + TABLES_TD if td else BEM_NOTE_FD + TABLES_FD)
              + PLATFORM).format(**values)]
    if drift:
        if td:
            raise ValueError("config_text: td and drift together; the drift twin is of the "
                             "frequency-domain database")
        fd_db = f"wu_yuan_m{m}.nc"
        text = parts[0].replace(f'"../hydro/data/{fd_db}"   # made by `mfm hydro configs/'
                                f'wu_yuan_m{m}.toml', f'"../hydro/data/wu_yuan_m{m}_drift.nc"   '
                                f'# made by `mfm hydro configs/wu_yuan_m{m}_drift.toml', 1)
        text = text.replace("infinite_frequency = true\n", "infinite_frequency = true\n"
                            "drift = \"kochin\"            # the layout's Kochin functions [D]\n", 1)
        text = text.replace(f'name = "Wu-Yuan model {m}"', f'name = "Wu-Yuan model {m} (drift)"',
                            1)
        if text.count("_drift") != 2 or 'drift = "kochin"' not in text:
            raise RuntimeError("config_text: the FD template no longer has the lines the drift "
                               "twin edits")
        parts[0] = DRIFT_NOTE.format(m=m) + text
    if locked:
        parts[0] = LOCKED_NOTE + parts[0].replace(f'name = "Wu-Yuan model {m}',
                                                  f'name = "Wu-Yuan model {m}, hinges locked', 1)
    notes = {"column1": "apex column on +x", "column2": "column at +120°", "column3": "column at −120°"}
    for name, c in columns():
        parts.append(COLUMN.format(name=name, notes=notes[name], com=vec([c[0], c[1], -9.68]),
                                   r_col=r_col, n_col=n_col))
    parts.append("\n# ---- the WECs, hinged to the platform ---------------------------------"
                 "---------------------\n")
    for name, row, c, h, a, xdir in wecs(L):
        I = inertia(xdir)
        k = (int(name[3:]) - 1) % 4 + 1
        text = WEC.format(name=name, row=row, k=k, com=vec(c), axis=vec(a, 9),
                          point=vec(h), r_wec=r_wec, n_wec=n_wec, dx_wec=DX_WEC,
                          inertia="[" + ", ".join(vec(r, 1) for r in I) + "]")
        if locked:
            text = text.replace(WEC_DAMPER, WEC_LOCKED)
        parts.append(text)
    if not locked:
        parts.append("\n# ---- hinge preloads: hold each WEC at its 2 m draft -------------------"
                     "---------------------\n")
        for name, *_ in wecs(L):
            parts.append(PRELOAD_ENTRY.format(name=name, value=f"{PRELOAD:.1f}"))
    parts.append("\n# ---- catenary moorings (Table 2) --------------------------------------"
                 "---------------------\n")
    for i, (name, bearing, fl, an) in enumerate(lines()):
        parts.append(LINE.format(name=name, bearing=bearing, fairlead=vec(fl), anchor=vec(an),
                                 line_type=LINE_TYPE_FIRST if i == 0 else '"chain"'))
    return "".join(parts)


WEC_ALONE = """\
# One WEC of the Wu & Yuan platform operating ALONE: P_s of the interaction factors q_s, q_r, q_a
# (Wu & Yuan 2025 eqs. 31–33: "P_s^i is the captured power of the i-th WEC when it operates alone").
# H. Wu, Z. Yuan, Ocean Engineering (2025) (docs/references.md); values tagged as in
# docs/GEOMETRY.md §4 ([S] stated, [D] derived, [A] assumed).
# MADE BY tools/wu_yuan_configs.py (the WEC's data are those of configs/wu_yuan_m1..m5.toml; edit
#   the script and rerun it, not this file).
#
# ASSUMED DEFINITION OF P_s [A]: the seed does not say how it computed a WEC "operating alone".
#   Here it is the same WEC on the same arm, hinged at a FIXED point (the inertial frame) instead
#   of the platform: hinge 9.72 m horizontally from its CoG towards where the platform was and
#   5.44 m above water [S], the same hinge axis, mass 1.1136e5 kg and inertias (Table 3, in the
#   WEC's own axes, x′ along the arm) [S], the same hull (flat cylinder R 4 m, draft 2 m, as the
#   platform configs' {n_wec}-gon of radius {r_wec:g} m: the circle's area) [S/A], the same PTO
#   (rotary damper 4.1e7 N m s/rad) [S] and the same hinge preload holding the 2 m draft
#   ({pre:.4e} N m, positive lifts the WEC) [D], in the same regular wave (heading 0: waves
#   travelling to +x) [S]. No other body, no platform motion, no line.
# This file is the row-3 WEC (arm along x: the WEC on the −x side of its hinge, hinge axis
#   along y){alpha_note}. The hull is axisymmetric, so a WEC whose arm is turned by α about z
#   absorbs in heading 0 what this one absorbs in heading −α: row 1 (α = +120°) → heading −120°,
#   row 2 (α = −120°) → +120°, row 3 → 0 (tools/wu_yuan.py: wec_alone_power). The database holds
#   those three headings.
# BEM [D]: the WEC alone, its CoG at the origin (one body of revolution on the z axis: capytaine's
#   rotation symmetry), reference point the CoG; the ten periods of the seed (T = 5, 6, 7, 8, 8.3,
#   9, 10, 11, 11.4, 12 s, the frequency-domain study's) and a band for the time domain's
#   radiation memory K(t): ω = {b_lo:g}–{b_hi:g} rad/s step {b_step:g} less the points within a
#   quarter step of a seed period ({n_w} frequencies; widest step {dw_max:.3g} rad/s: K(t) resolved
#   to π/Δω = {tk:.0f} s) + ∞; depth 60 m, finite where kh < 5, deep water above and at ∞; ρ 1025, g 9.81;
#   panels dx {dx_wec:g} m as in the platform configs; no lid (first irregular frequency
#   2.66 rad/s > {b_hi:g}), as in wu_yuan_m1..m5.nc.

[model]
name = "Wu-Yuan WEC alone"
gravity = 9.81              # m/s² [A]
description = "One WEC of the Wu & Yuan platform hinged at a fixed point: P_s of eqs. 31–33 [A]"

[hydro]
database = "{database}"   # made by `mfm hydro configs/wu_yuan_wec.toml --threads 1`
rho = 1025.0                # kg/m³ [A]

[hydro.bem]
omega = {omega}   # rad/s: 2π/T, T = 12, 11.4, 11, 10, 9, 8.3, 8, 7, 6, 5 s [S], and the band (see above) [D]
headings_deg = {headings}   # rows 2, 3, 1 (see above)
water_depth = 60.0          # m [S]
deep_water_kh = 5.0         # finite depth below kh = 5, deep water above [D]
dx = {dx_wec}                    # m [D]
lid = false                 # first irregular frequency 2.66 rad/s > {b_hi:g}
symmetry = "auto"           # rotation (one body of revolution on the z axis)
infinite_frequency = true

[[bodies]]
name = "wec"
notes = "one WEC alone, hinged at a fixed point{alpha_note}"
mass = 1.1136e5                      # kg [S]
com = [0.0, 0.0, 0.0]                # m: CoG at the water line [S], at the origin
inertia = {inertia}   # kg m² [S/D]
[bodies.joint]
type = "revolute"                    # to the inertial frame [A]
axis = {axis}
point = {point}   # hinge: 9.72 m from the CoG, 5.44 m up [S]
damping = 4.1e7                      # N m s/rad, the PTO [S]
[bodies.geometry]
shape = "cylinder"
radius = {r_wec}                      # m: R 4 [S] as a {n_wec}-gon of the same area [D]
draft = 2.0                          # m [S]
base = "flat"                        # [A]

[[joint_loads]]
name = "preload_wec"
coordinate = "wec.angle"
value = {preload}   # N m [D]: holds the 2 m draft (positive lifts the WEC)
"""


def wec_config_text(alpha_deg: float = 0.0, database: str = "../hydro/data/wu_yuan_wec.nc") -> str:
    """The lone WEC's config (configs/wu_yuan_wec.toml: ``alpha_deg`` = 0, row 3's arm along x).

    alpha_deg: the arm turned by α about z (the hinge point, hinge axis and inertia of row 3
    rotated; the hull stays at the origin, so the same database serves): the check that a turned
    arm in heading 0 is the row-3 arm in heading −α (tests/test_wu_yuan.py).
    database: the [hydro] database path as written in the file."""
    R = rot(alpha_deg)
    hinge = R @ np.array([ARM, 0.0, Z_HINGE])
    axis = R @ np.array([0.0, 1.0, 0.0])
    I = inertia(R @ np.array([-1.0, 0.0, 0.0]))
    r_wec, n_wec = panel_radius(R_WEC, DX_WEC)
    note = "" if alpha_deg == 0 else f", the arm turned by {alpha_deg:g}° about z"
    return WEC_ALONE.format(
        n_wec=n_wec, r_wec=r_wec, pre=PRELOAD, dx_wec=DX_WEC, omega=vec(wec_omega_list()),
        b_lo=WEC_BAND[0], b_hi=WEC_BAND[1], b_step=(WEC_BAND[1] - WEC_BAND[0]) / (WEC_BAND[2] - 1),
        n_w=len(wec_omega_list()), dw_max=float(np.diff(wec_omega_list()).max()),
        tk=math.pi / float(np.diff(wec_omega_list()).max()),
        headings="[" + ", ".join(f(h) for h in WEC_HEADINGS) + "]", database=database,
        inertia="[" + ", ".join(vec(r, 1) for r in I) + "]", axis=vec(axis, 9), point=vec(hinge),
        preload=f"{PRELOAD:.1f}", alpha_note=note)


def outputs(root=ROOT) -> dict:
    """{path: text} of every config this module writes, under ``root`` (the repository)."""
    root = Path(root)
    out = {root / "configs" / f"wu_yuan_m{m}.toml": config_text(m) for m in range(1, 6)}
    out.update({root / "configs" / f"wu_yuan_m{m}_td.toml": config_text(m, td=True)
                for m in TD_MODELS})
    out.update({root / "configs" / f"wu_yuan_m{m}_drift.toml": config_text(m, drift=True)
                for m in DRIFT_MODELS})
    out[root / "configs" / "wu_yuan_wec.toml"] = wec_config_text()
    return out


def main(argv=None, root=ROOT):
    """The command line: write the configs into ``root``/configs (printing each path), or with
    ``--check`` write nothing and print each config that differs from what it would write;
    returns the exit status (1 if one differs). ``root``: the repository (default this module's
    checkout; tools/wu_yuan_configs.py passes its own)."""
    import argparse

    ap = argparse.ArgumentParser(description="Write configs/wu_yuan_m1..m5.toml, wu_yuan_m1_td.toml "
                                             "and wu_yuan_wec.toml (Wu & Yuan 2025) from "
                                             "mfm.studies.wu_yuan_layout")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 if a config differs from what would be written")
    check = ap.parse_args(argv).check
    bad = 0
    for path, text in outputs(root).items():
        if check:
            if not path.exists() or path.read_text() != text:
                print(f"{path} differs from mfm.studies.wu_yuan_layout's output "
                      "(python tools/wu_yuan_configs.py rewrites it)")
                bad += 1
        else:
            path.write_text(text)
            print(f"wrote {path}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
