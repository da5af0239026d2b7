"""Wave excitation forces in the time domain from a hydro database and a set of wave components.

    F(t) = r(t) Re Σ_j a_j e^{iφ_j} X(ω_j, β_j) e^{−iω_j t}          (N or N m; e^{−iωt} convention)

with X = db["excitation"] (per metre of wave amplitude, dims omega, wave_direction, influenced_dof)
and r the start-up ramp of `hydro.waves.ramp` (the same one the elevation uses).

Interpolation of X between database points: amplitude |X| and phase arg X, each linear (the phase
increment taken along the shorter arc), first in ω at the two neighbouring headings, then in β.
Why not real and imaginary parts: the phase of X winds with frequency and heading (a body at a
distance d from the origin sees e^{ik d cos β}, k ∝ ω²), and a straight chord between two points of
a rotating phasor shortens it — by 1 − cos(Δθ/2), 3 % for a 0.5 rad step — whereas |X| and arg X
vary slowly. Where |X| passes through zero the two methods differ only by an amount of the order
of the (small) amplitude.

Range rules: a frequency outside the database's ω grid is an error naming it and the grid, unless
all such components together carry at most `drop_energy_fraction` of Σ a_j² — then they are given
zero force and a warning says how much energy was dropped. A heading is first mapped by multiples
of 2π into the database's range; if the database covers the full circle (auto-detected, or
`periodic_heading=True`) interpolation wraps around, otherwise a heading outside the range is an
error naming it and the range.

Cost: X at the components is a small (n_comp, n_dof) precompute; the time series is two real matrix
products per chunk of time steps (cos ωt and sin ωt against Re/Im of the coefficients), with at
most 2²⁰ phases in memory at once.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import xarray as xr

from hydro.waves import WaveComponents, _check_components, _harmonic_sum, ramp

__all__ = ["ExcitationTable", "polar_interpolation", "excitation_coefficients", "excitation_time_series", "excitation_dataarray"]

# relative slack on the ω grid's ends: a frequency this close beyond an end is that end (configs list
# their BEM frequencies with six decimals, so 2π/5 s is stored as 0.523599, 4e-7 from 2π/5 itself)
GRID_RTOL = 1e-6
_HEADING_TOL = 1e-9  # rad


def _excitation_table(db: xr.Dataset, dofs):
    """X as complex128 (n_ω, n_β, n_dof) sorted by ω and β, with the ω and β grids and dof labels."""
    if "excitation" not in db:
        raise KeyError(f"db has no 'excitation' variable (has {sorted(db.data_vars)}); "
                       "the hydro database schema requires excitation(omega, wave_direction, influenced_dof)")
    da = db["excitation"]
    if "complex" in da.dims:  # split storage as written to NetCDF: merge re/im back
        da = da.sel(complex="re") + 1j * da.sel(complex="im")
    missing = {"omega", "wave_direction", "influenced_dof"} - set(da.dims)
    if missing:
        raise ValueError(f"db['excitation'] must have dims (omega, wave_direction, influenced_dof); missing {sorted(missing)}")
    da = da.transpose("omega", "wave_direction", "influenced_dof").sortby("omega").sortby("wave_direction")
    labels = [str(v) for v in da["influenced_dof"].values]
    if dofs is not None:
        dofs = [dofs] if isinstance(dofs, str) else list(dofs)
        unknown = [d for d in dofs if d not in labels]
        if unknown:
            raise ValueError(f"dofs {unknown} are not in the database's influenced_dof {labels}")
        da = da.sel(influenced_dof=dofs)
        labels = dofs
    omega = np.asarray(da["omega"].values, dtype=np.float64)
    beta = np.asarray(da["wave_direction"].values, dtype=np.float64)
    X = np.asarray(da.values, dtype=np.complex128)
    if not np.all(np.isfinite(omega)) or np.any(omega <= 0.0) or np.any(np.diff(omega) <= 0.0):
        raise ValueError("db omega must be finite, > 0 and without duplicates (rad/s)")
    if not np.all(np.isfinite(X)):
        bad = np.argwhere(~np.isfinite(X))[0]
        raise ValueError(f"db excitation is not finite at omega={omega[bad[0]]!r} rad/s, "
                         f"wave_direction={beta[bad[1]]!r} rad, dof {labels[bad[2]]!r} (an ω = ∞ row?)")
    return X, omega, beta, labels


def _interp_polar(x0: np.ndarray, x1: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Complex interpolation with |X| and arg X linear in s ∈ [0, 1] (shorter-arc phase step).

    x0, x1: complex (n, m); s: (n, 1). A zero end takes the phase of the other end.
    """
    a0, a1 = np.abs(x0), np.abs(x1)
    p0, p1 = np.angle(x0), np.angle(x1)
    p0 = np.where(a0 > 0.0, p0, p1)
    p1 = np.where(a1 > 0.0, p1, p0)
    dp = np.angle(np.exp(1j * (p1 - p0)))
    return ((1.0 - s) * a0 + s * a1) * np.exp(1j * (p0 + s * dp))


def _bracket(grid: np.ndarray, v: np.ndarray):
    """Lower index i and fraction s of v between grid[i] and grid[i+1] (i+1 clipped for 1 point)."""
    n = grid.shape[0]
    if n == 1:
        return np.zeros(v.shape, dtype=np.int64), np.zeros(v.shape, dtype=np.int64), np.zeros(v.shape)
    i = np.clip(np.searchsorted(grid, v, side="right") - 1, 0, n - 2)
    s = np.clip((v - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0)
    return i, i + 1, s


def _heading_table(beta: np.ndarray, X: np.ndarray, periodic):
    """Heading grid (and X) to interpolate on, made periodic when the database covers the circle."""
    # a duplicate end point (e.g. −π and π) is the same direction: keep the first
    keep = beta < beta[0] + 2.0 * math.pi - _HEADING_TOL
    beta, X = beta[keep], X[:, keep]
    n = beta.shape[0]
    wrap_gap = beta[0] + 2.0 * math.pi - beta[-1]
    covers = n >= 3 and wrap_gap <= np.max(np.diff(beta)) * (1.0 + 1e-6) + _HEADING_TOL
    if periodic is None:
        periodic = covers
    elif periodic and n < 2:
        raise ValueError("periodic_heading=True needs a database with at least 2 wave directions")
    if periodic:
        beta = np.append(beta, beta[0] + 2.0 * math.pi)
        X = np.concatenate([X, X[:, :1]], axis=1)
    return beta, X, bool(periodic)


def _map_headings(grid: np.ndarray, periodic: bool, heading: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Headings moved by multiples of 2π into [grid[0], grid[0] + 2π); error if outside the grid."""
    lo, hi = grid[0], grid[-1]
    b = lo - _HEADING_TOL + np.mod(heading - lo + _HEADING_TOL, 2.0 * math.pi)
    if periodic:
        return np.clip(b, lo, hi)
    outside = active & (b > hi + _HEADING_TOL)
    if np.any(outside):
        j = int(np.flatnonzero(outside)[0])
        raise ValueError(
            f"wave heading {heading[j]:.6g} rad ({math.degrees(heading[j]):.4g}°) of component {j} "
            f"({int(outside.sum())} component(s) in all) is outside the database's wave_direction range "
            f"[{lo:.6g}, {hi:.6g}] rad ([{math.degrees(lo):.4g}°, {math.degrees(hi):.4g}°], modulo 360°): "
            "compute the database for that heading (a full circle allows any heading), or use a "
            "narrower directional spreading"
        )
    return np.clip(b, lo, hi)


def polar_interpolation(xp, polar, i0, k0, k1, sw, sb, *, one_heading: bool):
    """X(ω_j, β_j) from a table's polar form (:attr:`ExcitationTable.polar`: per ω interval and
    heading |X| at both ends, arg X at the lower end and the shorter-arc phase step) and the
    components' brackets (:meth:`ExcitationTable.brackets`): |X| and arg X linear in ω at the
    headings k0 and k1, then in β (a zero end taking the other's phase, the shorter arc), as
    :func:`_interp_polar` does in two steps. ``xp``: numpy or jax.numpy (the same numbers on the
    host and on a device, to round-off). Returns complex (n, n_dof)."""
    a0, a1, p0, dp = polar
    sw, sb = sw[:, None], sb[:, None]

    def in_omega(k):
        return (1.0 - sw) * a0[i0, k] + sw * a1[i0, k], p0[i0, k] + sw * dp[i0, k]

    A0, P0 = in_omega(k0)                               # at the lower heading
    if one_heading:
        return A0 * xp.exp(1j * P0)
    A1, P1 = in_omega(k1)                               # at the upper heading
    P0 = xp.where(A0 > 0.0, P0, P1)
    P1 = xp.where(A1 > 0.0, P1, P0)
    dP = xp.remainder(P1 - P0 + math.pi, 2.0 * math.pi) - math.pi
    return ((1.0 - sb) * A0 + sb * A1) * xp.exp(1j * (P0 + sb * dP))


class ExcitationTable:
    """X(ω, β) of a database made ready for interpolation at wave components: complex128
    (n_ω, n_β, n_dof) sorted by ω and β, the heading grid closed around the circle where the
    database covers it (see the module docstring). Made once per database and reused for every
    sea state (a batch of thousands of cases interpolates its components in one call,
    :meth:`brackets_many`, instead of sorting the dataset again per case)."""

    def __init__(self, db: xr.Dataset, dofs=None, periodic_heading: bool | None = None):
        X, omega, beta, labels = _excitation_table(db, dofs)
        self.omega, self.labels = omega, labels
        self.beta, self.X, self.periodic = _heading_table(beta, X, periodic_heading)
        self.water_depth = db.attrs.get("water_depth")
        # the polar form of each ω interval, made once (the numbers _interp_polar makes of its two
        # ends: |X|, arg X, a zero end taking the other's phase, the shorter-arc step), so that a
        # component costs one complex exponential in ω instead of two abs, two angles and two
        # exponentials; a one-frequency grid is one interval of zero length
        Xb = self.X
        x0, x1 = (Xb[:-1], Xb[1:]) if Xb.shape[0] > 1 else (Xb, Xb)
        a0, a1 = np.abs(x0), np.abs(x1)
        p0, p1 = np.angle(x0), np.angle(x1)
        p0 = np.where(a0 > 0.0, p0, p1)
        p1 = np.where(a1 > 0.0, p1, p0)
        self.polar = (a0, a1, p0, np.angle(np.exp(1j * (p1 - p0))))

    def _check(self, c: WaveComponents, drop_energy_fraction: float) -> np.ndarray:
        """The components' ω outside the grid (bool, (n,)): an error where they carry more than
        ``drop_energy_fraction`` of Σa², else a warning; and a warning where the components were
        discretised for another water depth."""
        if not 0.0 <= drop_energy_fraction < 1.0:
            raise ValueError(f"drop_energy_fraction must lie in [0, 1), got {drop_energy_fraction!r}")
        h_db = float(self.water_depth if self.water_depth is not None else c.water_depth)
        if not (h_db == c.water_depth or abs(h_db - c.water_depth) <= 1e-9 * abs(h_db)):
            warnings.warn(f"components were discretised for water_depth={c.water_depth} m but the database "
                          f"has water_depth={h_db} m: wavenumbers (elevation away from the origin) disagree "
                          "with the excitation", stacklevel=3)
        w = c.omega
        lo, hi = self.omega[0], self.omega[-1]
        outside = (w < lo * (1.0 - GRID_RTOL)) | (w > hi * (1.0 + GRID_RTOL))
        if np.any(outside):
            energy = c.amplitude**2
            total = float(energy.sum())
            frac = float(energy[outside].sum()) / total if total > 0.0 else 1.0
            j = int(np.flatnonzero(outside)[0])
            if frac > drop_energy_fraction:
                raise ValueError(
                    f"wave frequency {w[j]:.6g} rad/s (component {j}; {int(outside.sum())} component(s), "
                    f"a fraction {frac:.3g} of the wave energy, outside in all) lies outside the database's omega grid "
                    f"[{lo:.6g}, {hi:.6g}] rad/s: pass omega_range inside the grid to the sea state, use "
                    "components.band(...), or extend the database"
                )
            warnings.warn(
                f"dropped {int(outside.sum())} wave component(s) outside the database's omega grid "
                f"[{lo:.6g}, {hi:.6g}] rad/s, carrying a fraction {frac:.3g} of the wave energy (Σa²); their "
                "excitation is set to zero", stacklevel=3)
        return outside

    def brackets(self, w, heading, outside):
        """Where the components (ω_j, β_j) fall on the table: the lower ω point i0 and fraction
        sω, the headings k0, k1 around β_j and fraction sβ, each (n,) (a heading outside a
        database that does not cover the circle raises, naming it)."""
        b = _map_headings(self.beta, self.periodic, heading, ~outside)
        wi = np.clip(w, self.omega[0], self.omega[-1])
        i0, _, sw = _bracket(self.omega, wi)
        k0, k1, sb = _bracket(self.beta, b)
        return i0, k0, k1, sw, sb

    def _interpolate(self, w, heading, outside):
        """X at (ω_j, β_j), the rows ``outside`` zero: the polar interpolation of the module
        docstring, elementwise over the components (:func:`polar_interpolation`)."""
        out = polar_interpolation(np, self.polar, *self.brackets(w, heading, outside),
                                  one_heading=self.beta.shape[0] == 1)
        out[outside] = 0.0
        return out

    def coefficients(self, components: WaveComponents, *, drop_energy_fraction: float = 1e-3) -> np.ndarray:
        """X(ω_j, β_j) at each component: complex128 (n_comp, n_dof) (:func:`excitation_coefficients`)."""
        c = _check_components(components)
        outside = self._check(c, drop_energy_fraction)
        return self._interpolate(c.omega, c.heading, outside)

    def brackets_many(self, components, *, drop_energy_fraction: float = 1e-3):
        """The checks and :meth:`brackets` of each of a sequence of components (a batch's sea
        states) at once: ``(outside, (i0, k0, k1, sω, sβ))``, each a list of (n_comp_i,) arrays
        (``outside``: the components given zero force, see the module docstring)."""
        cs = [_check_components(c) for c in components]
        if not cs:
            return [], ([], [], [], [], [])
        outside = np.concatenate([self._check(c, drop_energy_fraction) for c in cs])
        w = np.concatenate([c.omega for c in cs])
        heading = np.concatenate([c.heading for c in cs])
        try:
            br = self.brackets(w, heading, outside)
        except ValueError:
            # a heading outside the grid: the case's own call names its component
            for c in cs:
                self.coefficients(c, drop_energy_fraction=drop_energy_fraction)
            raise
        cut = np.cumsum([len(c) for c in cs])[:-1]
        return np.split(outside, cut), tuple(np.split(a, cut) for a in br)


def excitation_coefficients(db: xr.Dataset, components: WaveComponents, *, dofs=None,
                            drop_energy_fraction: float = 1e-3, periodic_heading: bool | None = None) -> np.ndarray:
    """X(ω_j, β_j) interpolated at each wave component: complex128 (n_comp, n_dof), N/m or N m/m.

    Per metre of wave amplitude (multiply by `components.complex_amplitude[:, None]` for the force
    amplitudes). dofs: influenced_dof labels to keep (default all, in database order). Rows of
    components dropped for lying outside the ω grid (see the module docstring) are zero.
    """
    c = _check_components(components)
    table = ExcitationTable(db, dofs, periodic_heading)
    return table.coefficients(c, drop_energy_fraction=drop_energy_fraction)


def _time(t) -> np.ndarray:
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise ValueError(f"t must be a finite 1-D array of times (s), got shape {t.shape}")
    return t


def excitation_time_series(db: xr.Dataset, components: WaveComponents, t, *, ramp_duration: float = 0.0,
                           dofs=None, drop_energy_fraction: float = 1e-3,
                           periodic_heading: bool | None = None) -> np.ndarray:
    """F(t) = ramp(t) Re Σ_j a_j e^{iφ_j} X(ω_j, β_j) e^{−iω_j t}: float64 (n_t, n_dof), N or N m.

    t: s, (n_t,). dofs: influenced_dof labels (default all). ramp_duration: s, the
    ½(1 − cos(πt/T)) start-up ramp of `hydro.waves.ramp` (0 = none).
    """
    t = _time(t)
    X = excitation_coefficients(db, components, dofs=dofs, drop_energy_fraction=drop_energy_fraction,
                                periodic_heading=periodic_heading)
    F = _harmonic_sum(components.omega, components.complex_amplitude[:, None] * X, t)
    if ramp_duration:
        F *= ramp(t, ramp_duration)[:, None]
    return F


def excitation_dataarray(db: xr.Dataset, components: WaveComponents, t, *, ramp_duration: float = 0.0,
                         dofs=None, drop_energy_fraction: float = 1e-3,
                         periodic_heading: bool | None = None) -> xr.DataArray:
    """`excitation_time_series` as an xarray.DataArray with dims (time, influenced_dof)."""
    t = _time(t)
    labels = _excitation_table(db, dofs)[3]
    F = excitation_time_series(db, components, t, ramp_duration=ramp_duration, dofs=dofs,
                               drop_energy_fraction=drop_energy_fraction, periodic_heading=periodic_heading)
    return xr.DataArray(
        F, dims=("time", "influenced_dof"), coords={"time": t, "influenced_dof": labels},
        name="excitation_force",
        attrs={"units": "N (translations), N m (rotations)", "convention": "exp(-i omega t)",
               "ramp_duration": float(ramp_duration),
               "description": "F(t) = ramp(t) Re sum_j a_j exp(i phi_j) X(omega_j, beta_j) exp(-i omega_j t)"},
    )
