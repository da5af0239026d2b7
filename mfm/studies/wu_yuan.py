"""Wu & Yuan (seed 004) study helpers: the power of each WEC operating alone, P_s of the
interaction factors (eqs. 31–33: q_s = P_m^i / P_s^i, q_r and q_a their sums over a row or the
array), from the lone-WEC model configs/wu_yuan_wec.toml (written from
:mod:`mfm.studies.wu_yuan_layout`). Needs a checkout (the configs in configs/)::

    from mfm.studies import wu_yuan
    Ps = wu_yuan.wec_alone_power(3.8)      # DataArray (wec: 12, period: 10), W, H = 3.8 m

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
"""
from __future__ import annotations

import functools
import math
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from ..frequency.response import frequency_response
from ..io.build import load
from . import wu_yuan_layout as layout

ROOT = Path(__file__).resolve().parents[2]      # the repository (configs/), in a checkout
WEC_CONFIG = ROOT / "configs" / "wu_yuan_wec.toml"


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
def platform_model(m: int, locked: bool = False):
    """Model ``m`` (1–5) of the platform: configs/wu_yuan_m<m>.toml, or with ``locked`` its
    severe-sea variant (every hinge locked: no PTO, no preload; 6 coordinates), written by
    :func:`mfm.studies.wu_yuan_layout.config_text` into a temporary file that reads the same
    database. Loaded once per process (a model keeps its compiled linearisation: a second study
    of it is cheap)."""
    if m not in (1, 2, 3, 4, 5):
        raise ValueError(f"m: {m!r}; the seed's models are 1, 2, 3, 4, 5")
    if not locked:
        return load(ROOT / "configs" / f"wu_yuan_m{m}.toml")
    text = layout.config_text(m, locked=True)
    rel = f'"../hydro/data/wu_yuan_m{m}.nc"'
    if rel not in text:
        raise RuntimeError(f"mfm.studies.wu_yuan_layout no longer names the database as {rel}")
    text = text.replace(rel, '"' + (ROOT / "hydro" / "data" / f"wu_yuan_m{m}.nc").as_posix() + '"')
    path = Path(tempfile.mkdtemp(prefix="wu_yuan_locked_")) / f"wu_yuan_m{m}_locked.toml"
    path.write_text(text)
    return load(path)


@functools.lru_cache(maxsize=1)
def wec_alone_model():
    """The lone WEC (configs/wu_yuan_wec.toml with its database), loaded once per process."""
    return load(WEC_CONFIG)


def wec_alone_power(H, periods=None, *, heading_deg: float = 0.0, model=None, q0=None,
                    radiation: str = "database") -> xr.DataArray:
    """P_s^i: the mean power (W) of each of the 12 WECs operating alone (module docstring), in a
    regular wave of height ``H`` (m) and heading ``heading_deg`` (deg; the seed's 0: waves
    travelling to +x) at the periods ``periods`` (s; default the seed's ten, those of the
    database).

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
        w = np.asarray(db["omega"].values, dtype=float)
        omega = np.sort(w[np.isfinite(w)])[::-1]             # ascending period
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
