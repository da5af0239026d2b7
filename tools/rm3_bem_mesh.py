"""A capytaine database of RM3 for a moored RM3 with the drift of its own motions (issue 53), and
why it is not shipped: BEM meshes of RM3's two hulls revolved from the meridians of WEC-Sim's
geometry files (hydro/data/rm3/float.stl, plate.stl: drawing meshes of 516 and 356 triangles up
to 19.9 m across, which a BEM solve cannot use), a config for them on WEC-Sim's "Mooring Matrix"
spring, and the comparison of the database `mfm hydro` makes of it with NREL/Sandia's WAMIT
run (hydro/data/rm3): docs/nonlinear.md, "A moored RM3".

The meridians, read off those files (their vertices lie on three levels each), in the body axes
of the files (about each body's centre of gravity, as the STL files are):

- float (centre of gravity 0.72 m below the water line): outer wall r 10 m from z +2.72 (the
  deck, 2 m above water) to −1.28, a cone to r 5.029 m at −2.308, a flat bottom to the inner wall
  r 3.038 m, which rises to the deck (a moonpool 3.8 cm wider than the spar);
- spar and plate (centre of gravity 21.29 m below): a column r 3 m from z +29.2 down to −8.61,
  the heave plate r 15 m from −8.61 to −8.71 (0.1 m thick), its underside to the axis.

Only the wetted part is written (z ≤ 0 once placed at the config's origin); panels of about
``--dx-float`` m (default 0.8) and ``--dx-spar`` m (default 1.2: the sectors the plate's
15 m radius needs make the column's panels 0.24 m wide), quads (GDF, WAMIT's low-order format, which capytaine reads), the
number of sectors even so that each hull is symmetric about y = 0. From the repository root:

    python tools/rm3_bem_mesh.py                      # out/rm3_bem/: the meshes and the config
    mfm hydro out/rm3_bem/rm3_moored.toml --threads 1 # 6 minutes on one core
    python tools/rm3_bem_mesh.py --compare            # its A(ω), B(ω) against WAMIT's
"""
import argparse
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "rm3_bem"

# (r, z) in global coordinates (z 0 the still-water line), from the water line down to the keel
FLOAT_CG, SPAR_CG = -0.72, -21.29
FLOAT = [(10.0, 0.0), (10.0, -1.999), (5.029, -3.028), (3.038, -3.028), (3.038, 0.0)]
SPAR = [(3.0, 0.0), (3.0, -29.9), (15.0, -29.9), (15.0, -30.0), (0.0, -30.0)]


def _split(profile, dx):
    """The meridian's points, each segment cut into pieces of at most dx."""
    pts = [profile[0]]
    for (r0, z0), (r1, z1) in zip(profile[:-1], profile[1:]):
        k = max(1, math.ceil(math.hypot(r1 - r0, z1 - z0) / dx))
        pts += [(r0 + (r1 - r0) * j / k, z0 + (z1 - z0) * j / k) for j in range(1, k + 1)]
    return np.array(pts)


def revolve(profile, dx):
    """Quads (n_panels, 4, 3) of the surface swept by the meridian (top to keel: outward)."""
    P = _split(profile, dx)
    n = 2 * math.ceil(math.pi * P[:, 0].max() / dx)          # even: symmetric about y = 0
    th = 2 * np.pi * np.arange(n + 1) / n
    V = np.stack([P[None, :, 0] * np.cos(th)[:, None], P[None, :, 0] * np.sin(th)[:, None],
                  np.broadcast_to(P[:, 1], (n + 1, len(P)))], axis=-1)   # (sector, point, 3)
    quads = np.stack([V[:-1, :-1], V[:-1, 1:], V[1:, 1:], V[1:, :-1]], axis=2).reshape(-1, 4, 3)
    return quads, n


def write_gdf(path, quads, shift_z, what):
    """WAMIT's low-order geometry file: ULEN, g, no symmetry flags, the panels' four vertices,
    in the body's axes (z less the centre of gravity's depth)."""
    q = quads.copy()
    q[..., 2] -= shift_z
    with open(path, "w") as f:
        f.write(f"{what}: tools/rm3_bem_mesh.py\n1.0 9.81\n0 0\n{len(q)}\n")
        for panel in q:
            for x, y, z in panel:
                f.write(f"{x:.9f} {y:.9f} {z:.9f}\n")


CONFIG = """# RM3 on WEC-Sim's "Mooring Matrix" spring (1e5 N/m in surge at the origin, on the spar), with
# the Kochin functions of its hulls: written by tools/rm3_bem_mesh.py (not shipped: see
# docs/nonlinear.md, "A moored RM3"). Masses ρV of the meshes as placed (WEC-Sim's
# mass = 'equilibrium'); centres of mass and inertias as configs/rm3.toml.
[model]
name = "RM3 moored"
gravity = 9.81

[hydro]
database = "rm3_moored.nc"
body_coupling = true
added_mass_inf = "consistent"

[hydro.bem]
omega_min = 0.1
omega_max = 2.0
n_omega = 39
headings_deg = [0.0]
water_depth = "inf"
dx = {dx_spar}
lid = false
symmetry = "auto"
infinite_frequency = true
rho = 1000.0
drift = "kochin"

[[bodies]]
name = "spar"
mass = {m_spar:.2f}
com = [0.0, 0.0, -21.29]
principal_inertia = [94419614.57, 94407091.24, 28542224.82]
[bodies.joint]
type = "planar"
[bodies.hydro]
body = "spar"
[bodies.geometry]
shape = "mesh"
file = "plate_bem.gdf"
origin = [0.0, 0.0, -21.29]

[[bodies]]
name = "float"
parent = "spar"
mass = {m_float:.2f}
com = [0.0, 0.0, -0.72]
principal_inertia = [20907301.0, 21306090.66, 37085481.11]
[bodies.joint]
type = "prismatic"
axis = [0.0, 0.0, 1.0]
damping = 1.2e6
[bodies.hydro]
body = "float"
[bodies.geometry]
shape = "mesh"
file = "float_bem.gdf"
origin = [0.0, 0.0, -0.72]

[[moorings]]
name = "mooring"
body = "spar"
point = [0.0, 0.0, 0.0]
stiffness = [1.0e5, 0.0, 0.0]
"""

# the entries compared, and the frequencies (rad/s) of the printed ratios
PAIRS = [("float__Heave", "float__Heave"), ("spar__Heave", "spar__Heave"),
         ("float__Surge", "float__Surge"), ("spar__Surge", "spar__Surge"),
         ("spar__Pitch", "spar__Pitch"), ("float__Heave", "spar__Heave")]
AT = (0.3, 0.6, 0.8, 1.0, 1.3, 1.6)


def volume(quads):
    """ρ-free displaced volume of a closed-below-water surface of quads: Σ z n_z A (divergence)."""
    a, b, c, d = (quads[:, k] for k in range(4))
    n = 0.5 * np.cross(c - a, d - b)                                    # area-weighted normal
    return float(np.sum(quads.mean(axis=1)[:, 2] * n[:, 2]))


def compare():
    """The made database's A(ω), B(ω) against the WAMIT run's, as ratios at :data:`AT`."""
    import warnings

    import xarray as xr

    import mfm

    warnings.simplefilter("ignore")
    wamit = mfm.load(ROOT / "configs" / "rm3.toml").hydro.database()
    made = xr.load_dataset(OUT / "rm3_moored.nc")
    print("entry | " + " | ".join(f"{w:g} rad/s" for w in AT))
    for var in ("added_mass", "radiation_damping"):
        for i, j in PAIRS:
            a = made[var].sel(influenced_dof=i, radiating_dof=j).interp(omega=list(AT)).values
            b = wamit[var].sel(influenced_dof=i, radiating_dof=j).interp(omega=list(AT)).values
            print(f"{var} {i}, {j} (capytaine / WAMIT) | " + " | ".join(f"{x / y:.3f}" for x, y in zip(a, b)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dx-float", type=float, default=0.8, help="the float's panel size, m")
    ap.add_argument("--dx-spar", type=float, default=1.2, help="the spar's panel size, m")
    ap.add_argument("--compare", action="store_true",
                    help="compare out/rm3_bem/rm3_moored.nc (made by mfm hydro) with WAMIT's")
    a = ap.parse_args()
    if a.compare:
        return compare()
    OUT.mkdir(parents=True, exist_ok=True)
    mass = {}
    for name, profile, cg, dx in (("float_bem.gdf", FLOAT, FLOAT_CG, a.dx_float),
                                  ("plate_bem.gdf", SPAR, SPAR_CG, a.dx_spar)):
        quads, n = revolve(profile, dx)
        write_gdf(OUT / name, quads, cg, f"RM3 {name.split('_')[0]}, panels {dx} m")
        mass[name] = 1000.0 * volume(quads)
        print(f"{name}: {len(quads)} panels, {n} sectors, ρV {mass[name]:.2f} kg")
    (OUT / "rm3_moored.toml").write_text(CONFIG.format(
        dx_spar=a.dx_spar, m_spar=mass["plate_bem.gdf"], m_float=mass["float_bem.gdf"]))
    print(f"wrote {OUT / 'rm3_moored.toml'}")


if __name__ == "__main__":
    main()
