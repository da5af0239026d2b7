"""Wu & Yuan (2025) in the frequency domain: the power of each WEC operating alone, P_s of the
interaction factors (eqs. 31–33: q_s = P_m^i / P_s^i, q_r and q_a their sums over a row or the
array), from the lone-WEC model configs/wu_yuan_wec.toml; the five spacings at the seed's ten
periods (H 3.8 m, heading 0) and the severe sea with locked hinges (H 8.1 m, T 11.4 s), from
configs/wu_yuan_m1..m5.toml and their databases (:func:`fd_study`, :func:`severe_study`). The
layout and the configs: :mod:`mfm.studies.wu_yuan_layout`. notebooks/wu_yuan.ipynb draws the
seed's Figs. 4–14 from :func:`fd_study` and :func:`severe_study`; ``python tools/wu_yuan_study.py``
prints them. Needs a checkout (the configs in configs/)::

    from mfm.studies import wu_yuan
    Ps = wu_yuan.wec_alone_power(3.8)      # DataArray (wec: 12, period: 10), W, H = 3.8 m
    ds = wu_yuan.fd_study([1, 2])          # models 1 and 2 at the seed's ten periods

P_s (an ASSUMED definition: the seed does not say how it computed a WEC "operating alone"; see
the header of configs/wu_yuan_wec.toml): one WEC hinged at a fixed point with the platform's arm
(9.72 m horizontally, 5.44 m up), hinge axis, inertias, PTO damper (4.1e7 N m s/rad) and draft
preload, in the same regular wave. Its hull is axisymmetric, so WEC i, whose arm (hinge − CoG,
horizontal) points at the angle α_i from +x, absorbs in a wave of heading β what the lone row-3
WEC (arm along +x, α = 0) absorbs in heading β − α_i: turning the whole scene by −α_i about z
turns WEC i into the row-3 WEC and the wave into heading β − α_i. With the layout of
:mod:`mfm.studies.wu_yuan_layout` (row 1 = row 3 turned by +120°, row 2 by −120°) and β = 0:
row 1 → −120°, row 2 → +120°, row 3 → 0, the three headings of hydro/data/wu_yuan_wec.nc.

For a regular wave of height H (amplitude a = H/2) the mean power is
P = pto_power · a², pto_power = ½ c ω² |θ̂|² per m² of amplitude (mfm.frequency_response).

The platform's regular-wave steady states are those of the linearised system (moorings linearised
at the static equilibrium, hinge preloads included): mfm.frequency_response, per hinge
P = ½ c ω² |θ̂|² (H/2)². Interaction factors (seed eqs. 31–33, the upper limit "2a" of eq. 33
read as 12): q_s = P_m^i / P_s^i, q_r = Σ_row P_m / Σ_row P_s, q_a = Σ P_m / Σ P_s, with P_s
from the lone WEC. CWR by eq. 34 as printed: the array's power over the deep-water flux
ρ g² H² T / (32 π) times 8 m × 12. The five models differ only in numbers, so they share one
compiled linearisation (the first model's compile is most of its first call).
"""
from __future__ import annotations

import functools
import math
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from hydro.database import HydroDatabaseWarning, read_netcdf

from ..runner.frequency import frequency_response
from ..io.build import load
from ..loads.body_matrix import LinearBodyMatrix
from . import wu_yuan_layout as layout

ROOT = Path(__file__).resolve().parents[2]      # the repository (configs/), in a checkout
WEC_CONFIG = ROOT / "configs" / "wu_yuan_wec.toml"
H_AVERAGE = 3.8              # m, the seed's average wave height
SEVERE = (8.1, 11.4)         # m, s: the seed's severe sea (hinges locked)
ROWS = {1: [f"wec{k}" for k in range(1, 5)], 2: [f"wec{k}" for k in range(5, 9)],
        3: [f"wec{k}" for k in range(9, 13)]}
RHO, G, WIDTH, N_WEC = 1025.0, 9.81, 8.0, 12     # eq. 34: ρ, g, WEC diameter, number of WECs


def arm_angles() -> dict[str, float]:
    """{"wec1": α_1, …, "wec12": α_12}: the direction (deg, from +x towards +y) of each WEC's arm
    from its CoG to its hinge in the platform configs (the same in every model: only the
    positions along a row change with the spacing). Row 3: 0; row 1: +120; row 2: −120."""
    out = {}
    for name, _row, centre, hinge, _axis, _x in layout.wecs(layout.SPACINGS[0] * layout.D_WEC):
        d = np.asarray(hinge) - np.asarray(centre)
        out[name] = math.degrees(math.atan2(d[1], d[0]))
    return out


def lone_headings(heading_deg: float = 0.0) -> dict[str, float]:
    """{"wec1": β − α_1, …}: the heading (deg, in (−180, 180]) in which the lone row-3 WEC sees
    what WEC i sees in the platform's wave of heading β = ``heading_deg``."""
    out = {}
    for name, a in arm_angles().items():
        h = (heading_deg - a) % 360.0
        h = h - 360.0 if h > 180.0 + 1e-9 else h
        out[name] = round(h, 9) + 0.0
    return out


@functools.lru_cache(maxsize=None)
def platform_model(m: int, locked: bool = False, drift: bool = False):
    """Model ``m`` (1–5) of the platform: configs/wu_yuan_m<m>.toml, or with ``locked`` its
    severe-sea variant (every hinge locked: no PTO, no preload; 6 coordinates), written by
    :func:`mfm.studies.wu_yuan_layout.config_text` into a temporary file that reads the same
    database. ``drift``: the mean-drift twin (configs/wu_yuan_m<m>_drift.toml: the database with
    the layout's Kochin functions, models in ``layout.DRIFT_MODELS``), locked or not. Loaded once
    per process (a model keeps its compiled linearisation: a second study of it is cheap)."""
    if m not in (1, 2, 3, 4, 5):
        raise ValueError(f"m: {m!r}; the seed's models are 1, 2, 3, 4, 5")
    if drift and m not in layout.DRIFT_MODELS:
        raise ValueError(f"m: {m!r} with drift: the models with a Kochin-function database are "
                         f"{list(layout.DRIFT_MODELS)} (configs/wu_yuan_m<m>_drift.toml)")
    name = f"wu_yuan_m{m}_drift" if drift else f"wu_yuan_m{m}"
    if not locked:
        return load(ROOT / "configs" / f"{name}.toml")
    text = layout.config_text(m, locked=True, drift=drift)
    rel = f'"../hydro/data/{name}.nc"'
    if rel not in text:
        raise RuntimeError(f"mfm.studies.wu_yuan_layout no longer names the database as {rel}")
    text = text.replace(rel, '"' + (ROOT / "hydro" / "data" / f"{name}.nc").as_posix() + '"')
    path = Path(tempfile.mkdtemp(prefix="wu_yuan_locked_")) / f"{name}_locked.toml"
    path.write_text(text)
    return load(path)


def mean_offset(m: int = 1, sea=None, *, locked: bool = True) -> xr.Dataset:
    """The platform's mean position and its catenary lines' tensions in a sea, against still
    water (issue 53 item 3): :func:`mfm.equilibrium` with and without ``sea`` on the mean-drift
    twin of model ``m`` (its database's Kochin functions: the far-field drift of the model's own
    motions, the layout's total on the platform, :mod:`mfm.frequency.drift`).

    sea: default the seed's severe regular wave (H 8.1 m, T 11.4 s, head seas); locked: every
    hinge locked (the seed's severe-sea state; False: the WECs working on their PTOs).
    Returns a Dataset: ``q_rest``, ``q_mean`` (coordinate) the equilibria (m, rad),
    ``tension_rest``, ``tension_mean`` (line) each line's fairlead tension √(H² + V²) (N),
    ``mooring_force_rest``, ``mooring_force_mean`` (axis: x, y) the lines' total horizontal force
    on the platform (N), ``drift_force`` (component: surge, sway, yaw) the mean drift on the platform (N, N m), and
    attributes naming the drift taken."""
    import hydro
    from ..frequency.drift import model_mean_drift
    from ..frequency.rest import system_loads
    from ..loads.catenary import CatenaryLines
    from ..mechanics.kinematics import kinematics
    from ..runner.frequency import equilibrium

    sea = hydro.Regular(height=SEVERE[0], period=SEVERE[1]) if sea is None else sea
    model = platform_model(m, locked=locked, drift=True)
    lines = next(ld for ld in system_loads(model) if isinstance(ld, CatenaryLines))
    zero = np.zeros(model.n_coordinates)

    def tension(q):
        H, V, _ = lines.tensions(lines.fairleads.positions(kinematics(model, q, zero)))
        return np.hypot(np.asarray(H), np.asarray(V))

    def pull(q):
        # the lines' total horizontal force on the platform (x, y)
        f = lines.fairlead_forces(lines.fairleads.positions(kinematics(model, q, zero)))
        return np.asarray(f)[:, :2].sum(axis=0)

    rest, _ = equilibrium(model)
    mean, info = equilibrium(model, q_guess=rest, sea=sea)
    table = model_mean_drift(model, q0=rest)
    comps = sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    F = table.table().at(comps).T @ np.asarray(comps.amplitude, float) ** 2   # Σ_j D_j a_j²
    root = table.attrs["dofs"].split(", ")
    return xr.Dataset(
        {"q_rest": (("coordinate",), rest, {"units": "m or rad"}),
         "q_mean": (("coordinate",), mean, {"units": "m or rad",
                                            "long_name": "mean position in the sea"}),
         "tension_rest": (("line",), tension(rest), {"units": "N"}),
         "tension_mean": (("line",), tension(mean), {"units": "N"}),
         "mooring_force_rest": (("axis",), pull(rest), {"units": "N", "long_name": "the lines' "
                                                        "total horizontal force on the platform"}),
         "mooring_force_mean": (("axis",), pull(mean), {"units": "N"}),
         "drift_force": (("component",), [F[list(table.dofs).index(d)] for d in root],
                         {"units": "N, N, N m"})},
        coords={"coordinate": list(model.coordinates), "line": list(lines.names),
                "component": ["surge", "sway", "yaw"], "axis": ["x", "y"]},
        attrs={"model": model.name, "sea": repr(sea), "mean_drift": info["mean_drift"],
               "locked": str(bool(locked))})


@functools.lru_cache(maxsize=1)
def wec_alone_model():
    """The lone WEC (configs/wu_yuan_wec.toml with its database), loaded once per process."""
    return load(WEC_CONFIG)


def wec_alone_power(H, periods=None, *, heading_deg: float = 0.0, model=None, q0=None,
                    radiation: str = "database") -> xr.DataArray:
    """P_s^i: the mean power (W) of each of the 12 WECs operating alone (module docstring), in a
    regular wave of height ``H`` (m) and heading ``heading_deg`` (deg; the seed's 0: waves
    travelling to +x) at the periods ``periods`` (s; default the seed's ten, 2π/ω for the ten ω of
    wu_yuan_layout.omega_list, which the database holds exactly among its band).

    P_s^i(T) = pto_power(ω = 2π/T, β − α_i) · (H/2)², pto_power from
    ``mfm.frequency_response(model, ω, β − α_i, radiation=radiation)`` (W per m² of amplitude).

    model: the lone WEC (default :func:`wec_alone_model`); q0: the state it is linearised about
    (default its static equilibrium, mfm.equilibrium: 1.2e-6 rad, the preload holds the draft).
    Each heading β − α_i must be one of
    the database's (no interpolation across 120° of heading): otherwise a ValueError names it.

    Returns a DataArray (wec: "wec1" … "wec12", period: T), W, with coordinates ``omega``
    (period) and ``lone_heading_deg`` (wec).
    """
    H = float(H)
    if not math.isfinite(H) or H <= 0:
        raise ValueError(f"H: {H!r} m; give a positive wave height")
    model = wec_alone_model() if model is None else model
    db = model.hydro.db
    if periods is None:
        # the seed's ten ω, exactly as the database holds them among its band (wu_yuan_layout)
        omega = np.asarray(layout.omega_list(), dtype=float)[::-1]   # ascending period
    else:
        T = np.atleast_1d(np.asarray(periods, dtype=float))
        if T.ndim != 1 or T.size == 0 or not np.all(np.isfinite(T)) or np.any(T <= 0):
            raise ValueError(f"periods: {periods!r}; give positive wave periods in s")
        omega = 2.0 * math.pi / T
    T = 2.0 * math.pi / omega
    have = np.degrees(np.asarray(db["wave_direction"].values, dtype=float))
    heads = lone_headings(heading_deg)
    power = {}
    for h in sorted(set(heads.values())):
        if not np.any(np.abs(((have - h + 180.0) % 360.0) - 180.0) < 1e-6):
            raise ValueError(f"heading_deg: {heading_deg!r} needs the lone WEC in heading {h:g}°, "
                             f"which the lone WEC's database does not hold (headings {np.round(have, 6).tolist()}°); add it to "
                             f"WEC_HEADINGS in mfm/studies/wu_yuan_layout.py and regenerate")
        fr = frequency_response(model, omega, math.radians(h), q0=q0, radiation=radiation,
                                joint_reactions=False)
        power[h] = np.asarray(fr["pto_power"].sel(pto="wec.angle").values) * (H / 2.0) ** 2
    names = list(heads)
    data = np.stack([power[heads[n]] for n in names])
    return xr.DataArray(
        data, dims=("wec", "period"),
        coords={"wec": names, "period": T, "omega": ("period", omega),
                "lone_heading_deg": ("wec", [heads[n] for n in names])},
        name="P_s", attrs={"units": "W", "wave_height_m": H, "heading_deg": float(heading_deg),
                           "definition": "one WEC hinged at a fixed point with the platform's arm, "
                                         "PTO and preload (assumed; configs/wu_yuan_wec.toml)",
                           "radiation": radiation})


def seed_periods() -> np.ndarray:
    """The seed's ten periods (s, ascending): those of the databases (2π/ω, rounded to 0.1 s)."""
    return _seed_periods().copy()


@functools.lru_cache(maxsize=1)
def _seed_periods() -> np.ndarray:
    # read once per process: every study call asks for them, and the file is read whole (with
    # hydro.database.read_netcdf, never a bare xr.open_dataset: hydro/database.py)
    w = np.asarray(read_netcdf(ROOT / "hydro" / "data" / "wu_yuan_m1.nc").omega.values)
    return np.sort(np.round(2 * np.pi / w[np.isfinite(w) & (w > 0)], 1))


def _platform_rao(fr) -> xr.DataArray:
    """|surge| (m/m), |heave| (m/m), |pitch| (deg/m) of the platform's CoM: (omega, motion)."""
    br = fr.body_rao.sel(body="platform")
    return xr.concat([np.abs(br.sel(dof="x")), np.abs(br.sel(dof="z")),
                      np.degrees(np.abs(br.sel(dof="ry")))], dim="motion").drop_vars(
        "dof", errors="ignore").assign_coords(motion=["surge", "heave", "pitch"]).transpose("omega", "motion")


def fd_study(models=(1, 2, 3, 4, 5), periods=None, H: float = H_AVERAGE, *,
             platform_damping: float | None = None, verbose: bool = False) -> xr.Dataset:
    """The five spacings in regular waves of height ``H`` (m), heading 0, at ``periods`` (s;
    default the seed's ten). ``platform_damping``: a viscous damping of the platform's heave, roll
    and pitch as a fraction of critical (mfm.loads.body_matrix.LinearBodyMatrix ``damping_ratio``;
    the seed's C_vis, whose values it does not give; default none). Returns a Dataset (model,
    period, wec, row, motion, line):

    power (W) per WEC, P_s (W) the lone WEC's (assumed definition), q_s, row_power (W) and q_r
    per row, array_power (W), q_a, CWR; platform_rao (surge, heave m/m; pitch deg/m);
    tension_rao (N/m) per line; heave_rao (complex, m/m) of the platform's and WEC1's CoM (Fig. 5);
    settings and provenance in the attributes.
    """
    T = seed_periods() if periods is None else np.sort(np.atleast_1d(np.asarray(periods, float)))
    w = 2 * np.pi / T
    a2 = (H / 2) ** 2
    Ps = wec_alone_power(H, T).transpose("period", "wec")
    out = []
    for k in models:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", HydroDatabaseWarning)
            model = platform_model(k)
            loads = []
            if platform_damping:
                z = float(platform_damping)
                # the fractions of critical, set from the model's linearisation by create
                loads = [LinearBodyMatrix.create(model, "platform", name="platform_viscous",
                                                 damping_ratio={"heave": z, "roll": z, "pitch": z})]
            fr = frequency_response(model, w, 0.0, loads=loads, joint_reactions=False)
        wec = [p.split(".")[0] for p in fr.pto.values]
        P = xr.DataArray(fr.pto_power.values * a2, dims=("period", "wec"), coords={"period": T, "wec": wec})
        heave = fr.body_rao.sel(dof="z", body=["platform", "wec1"]).values
        ds = xr.Dataset({
            "power": P,
            "platform_rao": (("period", "motion"), _platform_rao(fr).values),
            "tension_rao": (("period", "line"), np.abs(fr.fairlead_tension_rao.values)),
            "heave_rao": (("period", "heave_of"), heave)},
            coords={"period": T, "wec": wec, "motion": ["surge", "heave", "pitch"],
                    "line": fr.mooring_line.values, "heave_of": ["platform", "wec1"]})
        out.append(ds.expand_dims(model=[k]))
        if verbose:
            print(f"  model {k}: {time.perf_counter() - t0:.0f} s", flush=True)
    ds = xr.concat(out, dim="model")
    ds["P_s"] = Ps.assign_coords(period=T).drop_vars(["omega", "lone_heading_deg"], errors="ignore")
    ds["q_s"] = ds.power / ds.P_s
    rows = list(ROWS)
    ds["row_power"] = xr.concat([ds.power.sel(wec=ROWS[r]).sum("wec") for r in rows], dim="row").assign_coords(row=rows)
    ds["q_r"] = ds.row_power / xr.concat([ds.P_s.sel(wec=ROWS[r]).sum("wec") for r in rows], dim="row").assign_coords(row=rows)
    ds["array_power"] = ds.power.sum("wec")
    ds["q_a"] = ds.array_power / ds.P_s.sum("wec")
    flux = RHO * G**2 * H**2 * ds.period / (32 * np.pi)                 # W/m, deep water, eq. 34
    ds["CWR"] = ds.array_power / (flux * WIDTH * N_WEC)
    units = {"power": "W", "P_s": "W", "row_power": "W", "array_power": "W", "q_s": "1", "q_r": "1",
             "q_a": "1", "CWR": "1", "platform_rao": "m/m (surge, heave), deg/m (pitch)",
             "tension_rao": "N/m", "heave_rao": "m/m (complex, x(t) = Re[x̂ e^{-iωt}])"}
    for name, u in units.items():
        ds[name].attrs["units"] = u
    ds.period.attrs["units"] = "s"
    ds.attrs.update(title="Wu & Yuan: five WEC spacings in regular waves (frequency domain)",
                    wave_height_m=H, heading_deg=0.0, made_by="mfm.studies.wu_yuan.fd_study",
                    platform_damping_ratio=float(platform_damping or 0.0),
                    P_s_definition=Ps.attrs["definition"], mfm_version=fr.attrs.get("mfm_version", ""),
                    configs=", ".join(f"configs/wu_yuan_m{k}.toml" for k in models))
    return ds


def severe_study(models=(1, 2, 3, 4, 5), H: float = SEVERE[0], T: float = SEVERE[1], periods=None, *,
                 verbose: bool = False) -> xr.Dataset:
    """The severe sea of the seed (H 8.1 m, T 11.4 s), every hinge locked
    (:func:`platform_model` ``(m, locked=True)``): the platform's RAOs and each line's tension RAO per model
    at ``periods`` (s; default the seed's ten, which include T) — Fig. 14 reads them at T; the
    curves show where the locked platform's resonances sit — and the motions' and tensions'
    amplitudes at (H, T) (linear: RAO × H/2)."""
    Ts = seed_periods() if periods is None else np.sort(np.atleast_1d(np.asarray(periods, float)))
    if not np.any(np.isclose(Ts, T)):
        Ts = np.sort(np.append(Ts, T))
    out = []
    for k in models:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", HydroDatabaseWarning)
            model = platform_model(k, locked=True)
            fr = frequency_response(model, 2 * np.pi / Ts, 0.0, joint_reactions=False)
        out.append(xr.Dataset({
            "platform_rao": (("period", "motion"), _platform_rao(fr).values),
            "tension_rao": (("period", "line"), np.abs(fr.fairlead_tension_rao.values)),
            "heave_offset": fr.equilibrium.sel(coordinate="platform.heave").values},
            coords={"period": Ts, "motion": ["surge", "heave", "pitch"],
                    "line": fr.mooring_line.values}).expand_dims(model=[k]))
        if verbose:
            print(f"  locked model {k}: {time.perf_counter() - t0:.0f} s", flush=True)
    ds = xr.concat(out, dim="model")
    at = ds.sel(period=Ts[np.argmin(np.abs(Ts - T))])
    ds["platform_amplitude"] = at.platform_rao * H / 2
    ds["tension_amplitude"] = at.tension_rao * H / 2
    for name, u in {"platform_rao": "m/m (surge, heave), deg/m (pitch)", "tension_rao": "N/m",
                    "heave_offset": "m", "platform_amplitude": "m (surge, heave), deg (pitch)",
                    "tension_amplitude": "N"}.items():
        ds[name].attrs["units"] = u
    ds.period.attrs["units"] = "s"
    ds.attrs.update(title="Wu & Yuan: severe sea, hinges locked (frequency domain)", wave_height_m=H,
                    wave_period_s=T, heading_deg=0.0, made_by="mfm.studies.wu_yuan.severe_study")
    return ds
