"""Rotor thrust of a wind turbine on a floating body (Stansby & Li 2024, eq. 33).

Config table ``[[wind_thrust]]``: ``body``; ``hub`` [x, y, z] m, inertial at q = 0 (the point moves
with the body); ``rotor_radius`` R m (> 0); ``wind_speed`` U m/s (≥ 0, the mean wind at the hub);
``thrust_coefficient`` a number, or the path of a CSV table (columns ``wind_speed_mps`` and ``Ct``,
``#`` comment lines; a relative path is relative to the config file), or left out for the bundled
NREL 5 MW table (``mfm/data/nrel5mw_ct.csv``); ``rho_air`` kg/m³ (default 1.2); ``direction_deg``
the direction the wind blows towards in the horizontal plane, degrees from +x towards +y
(default 0: along +x); optional ``name``, ``notes``. The load is a horizontal force at the hub,

    H = ½ ρ_air A C_T(U) (U − u_hub) |U − u_hub|,   A = π R²,   F = H d,  d = (cos φ, sin φ, 0),

with u_hub = d · v_hub the hub's inertial velocity along the wind. C_T is taken at the mean wind U,
not at the relative speed (Stansby & Li 2024), and is a linear interpolation of the table, 0 outside it (a
U above the turbine's cut-out is allowed, with a warning: no thrust). (U − u)|U − u| keeps the sign
right if the hub ever overtakes the wind.

Nothing here is special to the frequency domain: the load is smooth in (q, q̇), so the
equilibrium feels the mean thrust ½ ρ A C_T U² at the hub and the linearisation takes the
aerodynamic damping −∂H/∂u_hub = ρ A C_T U at the hub from jax.

Outputs (dim ``wind_load``, and ``axis`` x, y, z shared with the other results): ``wind_thrust``
H (N); ``hub_acceleration`` the kinematic acceleration of the hub, inertial axes (m/s²);
``hub_gravity_acceleration`` what gravity adds to the reading of an accelerometer fixed to the
nacelle, in body axes: the specific force −g⃗ expressed in the body frame, g Rᵀ e_z = g (R₂₀, R₂₁,
R₂₂), so a pitch θ about +y (the body x axis tipped down) reads −g sin θ ≈ −g θ along x. A nacelle
accelerometer reads Rᵀ hub_acceleration + hub_gravity_acceleration; the two are kept apart. In the
frequency domain, ``wind_thrust_rao``: the thrust fluctuation −ρ A C_T U u_hub per metre of wave
amplitude.

Every parameter (U, C_T(U), ρ_air, A, d) is an array leaf; :meth:`WindThrust.with_wind_speed`
re-evaluates C_T by ``jnp.interp`` (traceable), so a sweep over wind speed is a ``jax.vmap`` over
loads with no recompilation.
"""
from __future__ import annotations

import math
import warnings
from importlib import resources
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..validation import (body_ref, element_name, number, tables, unique_names,
                          vector)
from ..backend import device_array
from ..mechanics.points import BodyPoints, h_matrix_at
from ..errors import ConfigError
from .base import Load, LoadOutput

KEYS = {"name", "body", "hub", "rotor_radius", "wind_speed", "thrust_coefficient", "rho_air",
        "direction_deg", "notes"}
CT_MAX = 2.0    # beyond momentum theory's turbulent-wake state: a typo (a percentage?), not a rotor


class WindWarning(UserWarning):
    """A wind load that is legal but likely not what was meant (a wind above cut-out)."""


def bundled_ct_table() -> Path:
    """The bundled NREL 5 MW C_T(U) table (``mfm/data/nrel5mw_ct.csv``, source in its header)."""
    return Path(str(resources.files("mfm").joinpath("data", "nrel5mw_ct.csv")))


def read_ct_table(path, where: str = "thrust_coefficient"):
    """(U m/s, C_T) arrays from a CSV with columns ``wind_speed_mps`` and ``Ct`` (others ignored,
    ``#`` lines are comments). Raises ConfigError naming ``where``, the file and the problem."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"{where}: {str(path)!r} cannot be read ({type(e).__name__}); give a "
                          "number, or a CSV with columns wind_speed_mps, Ct (a relative path is "
                          "relative to the config file)") from None
    rows = [ln.split(",") for ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    header = [h.strip() for h in rows[0]] if rows else []
    if "wind_speed_mps" not in header or "Ct" not in header:
        raise ConfigError(f"{where}: {str(path)!r} has header {header}; a C_T table needs columns "
                          "wind_speed_mps and Ct")
    iu, ic = header.index("wind_speed_mps"), header.index("Ct")
    try:
        data = np.array([[float(r[iu]), float(r[ic])] for r in rows[1:]])
    except (ValueError, IndexError):
        raise ConfigError(f"{where}: {str(path)!r} has a row that is not numbers in columns "
                          "wind_speed_mps, Ct") from None
    if len(data) < 2 or not np.isfinite(data).all():
        raise ConfigError(f"{where}: {str(path)!r} needs at least 2 rows of finite numbers")
    u, ct = data[:, 0], data[:, 1]
    if np.any(np.diff(u) <= 0):
        raise ConfigError(f"{where}: {str(path)!r}: wind_speed_mps must increase row by row")
    if np.any(ct < 0) or np.any(ct > CT_MAX):
        raise ConfigError(f"{where}: {str(path)!r}: Ct must lie in [0, {CT_MAX}]")
    return u, ct


def _cut_out(table):
    """The largest wind speed with C_T > 0 in a table (None: a constant C_T, no cut-out)."""
    if table is None:
        return None
    u, ct = np.asarray(table[0]), np.asarray(table[1])
    return float(u[ct > 0].max()) if np.any(ct > 0) else -math.inf


class WindThrust(Load):
    """H = ½ ρ_air A C_T (U − u_hub)|U − u_hub| along ``direction`` at the hub ``points``.

    Arrays, one entry per turbine P: ``wind_speed`` U (P,) m/s, ``thrust_coefficient`` C_T(U)
    (P,), ``rho_air`` (P,) kg/m³, ``area`` πR² (P,) m², ``direction`` (P, 3) unit horizontal vector
    the wind blows towards (inertial). Static: ``ct_tables`` per turbine (U, C_T) tuples or None
    (a constant C_T), ``ct_sources`` where each C_T came from, ``names``.
    """
    points: BodyPoints
    wind_speed: jnp.ndarray
    thrust_coefficient: jnp.ndarray
    rho_air: jnp.ndarray
    area: jnp.ndarray
    direction: jnp.ndarray
    ct_tables: tuple = eqx.field(static=True, default=())
    ct_sources: tuple[str, ...] = eqx.field(static=True, default=())
    names: tuple[str, ...] = eqx.field(static=True, default=())

    # -- physics
    def hub_velocity(self, kin):
        """u_hub (P,): the hub's inertial velocity along the wind direction."""
        v, _ = self.points.velocity_and_bias(kin)
        return jnp.einsum("pa,pa->p", v.reshape(-1, 6)[:, :3], self.direction)

    def thrust(self, kin):
        """H (P,) N along the wind direction (negative if the hub outruns the wind)."""
        rel = self.wind_speed - self.hub_velocity(kin)
        return 0.5 * self.rho_air * self.area * self.thrust_coefficient * rel * jnp.abs(rel)

    def evaluate(self, ctx):
        H = self.thrust(ctx.kin)
        # a force at the hub, no moment about it; to_body_wrench adds the lever arm to the CoM
        F = jnp.concatenate([H[:, None] * self.direction, jnp.zeros_like(self.direction)], axis=1)
        return LoadOutput(body=self.points.to_body_wrench(F.reshape(-1), ctx.kin, ctx.model.n_bodies))

    def with_wind_speed(self, U) -> "WindThrust":
        """The same load at mean wind U (scalar or (P,)), C_T re-read from each table by
        ``jnp.interp`` (0 outside it); a constant C_T stays. Traceable: ``jax.vmap`` over U gives a
        batch of loads."""
        U = jnp.broadcast_to(jnp.asarray(U, dtype=jnp.float64), self.wind_speed.shape)
        tabs = self.ct_tables or (None,) * U.shape[-1]     # built by hand: constant C_T
        try:
            _warn_cut_out(np.asarray(U), tabs, self.names)
        except jax.errors.TracerArrayConversionError:
            pass                # traced (a vmap over U): nothing to check on the host
        ct = jnp.stack([self.thrust_coefficient[p] if tab is None else
                        jnp.interp(U[p], jnp.asarray(tab[0]), jnp.asarray(tab[1]), left=0.0, right=0.0)
                        for p, tab in enumerate(tabs)])
        return eqx.tree_at(lambda ld: (ld.wind_speed, ld.thrust_coefficient), self, (U, ct))

    # -- outputs
    def diagnostics(self, ctx, out):
        P = len(self.names)
        H, _, _ = self.points.h_matrix(ctx.kin)
        _, bias = self.points.velocity_and_bias(ctx.kin)
        acc = (H @ ctx.qdd + bias).reshape(P, 6)[:, :3]
        R = ctx.kin.E[np.asarray(self.points.body_index), :3, :3]
        # accelerometer reads a − g⃗ in body axes; gravity's part −Rᵀ(0, 0, −g) = g Rᵀ e_z
        grav = ctx.model.gravity * R[:, 2, :]
        return {"wind_thrust": self.thrust(ctx.kin), "hub_acceleration": acc,
                "hub_gravity_acceleration": grav}

    def outputs(self):
        return {"coords": {"wind_load": list(self.names), "axis": ["x", "y", "z"]},
                "wind_thrust": (("wind_load",), {
                    "long_name": "rotor thrust ½ ρ_air A C_T(U) (U − u_hub)|U − u_hub| along the "
                                 "wind direction", "units": "N"}),
                "hub_acceleration": (("wind_load", "axis"), {
                    "long_name": "kinematic acceleration of the hub, inertial axes (gravity not "
                                 "included)", "units": "m/s2"}),
                "hub_gravity_acceleration": (("wind_load", "axis"), {
                    "long_name": "gravity's part of a nacelle accelerometer's reading, body axes: "
                                 "g Rᵀ e_z (x: −g sin θ for a pitch θ about +y)", "units": "m/s2"})}

    def frequency_outputs(self, model, kin0, x, omega):
        """Thrust fluctuation −ρ A C_T U û_hub per metre of wave amplitude, û_hub = −iω d·H x̂."""
        Hm = np.asarray(h_matrix_at(self.points, kin0)).reshape(len(self.names), 6, -1)[:, :3]
        d = np.asarray(self.direction)
        u = -1j * omega[:, None] * np.einsum("pa,pai,wi->wp", d, Hm, x)
        slope = -np.asarray(self.rho_air * self.area * self.thrust_coefficient * self.wind_speed)
        return {"wind_thrust_rao": (("wind_load",), slope * u, {
                    "long_name": "rotor thrust fluctuation −ρ_air A C_T U u_hub per metre of wave "
                                 "amplitude", "units": "N/m"}),
                "coords": {"wind_load": list(self.names)}}

    def provenance(self):
        out = {}
        arr = lambda a, p: np.asarray(a)[..., p].tolist()  # noqa: E731  (a batch keeps its lists)
        for p, n in enumerate(self.names):
            out.update({f"wind_{n}_speed_mps": arr(self.wind_speed, p),
                        f"wind_{n}_thrust_coefficient": arr(self.thrust_coefficient, p),
                        f"wind_{n}_rotor_radius_m": np.sqrt(np.asarray(self.area)[..., p] / np.pi).tolist(),
                        f"wind_{n}_rho_air": arr(self.rho_air, p),
                        f"wind_{n}_direction_deg": float(np.degrees(np.arctan2(
                            *np.asarray(self.direction)[..., p, :].reshape(-1, 3)[0, [1, 0]]))),
                        f"wind_{n}_ct_source": self.ct_sources[p]})
        return out

    # -- construction
    @classmethod
    def create(cls, model, body: str, hub, *, rotor_radius: float, wind_speed: float,
               thrust_coefficient=None, rho_air: float = 1.2, direction_deg: float = 0.0,
               name: str | None = None) -> "WindThrust":
        """One turbine on ``body`` from Python, as a ``[[wind_thrust]]`` entry would give it
        (a table path is relative to the working directory)."""
        entry = {"body": body, "hub": list(np.asarray(hub, dtype=float)),
                 "rotor_radius": rotor_radius, "wind_speed": wind_speed, "rho_air": rho_air,
                 "direction_deg": direction_deg}
        if thrust_coefficient is not None:
            entry["thrust_coefficient"] = (str(Path(thrust_coefficient).resolve())
                                           if isinstance(thrust_coefficient, (str, Path))
                                           else thrust_coefficient)
        if name is not None:
            entry["name"] = name
        return cls.from_parsed(cls.parse_table([entry], list(model.body_names)), model)

    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, t) in enumerate(tables(raw, "wind_thrust", KEYS)):
            body = body_ref(t, "body", where, names)
            item = {"where": where, "body": body, "name": element_name(t, where, f"{body}_wind{i}")}
            for key, what in (("hub", "the hub [x, y, z] (m, inertial at q = 0)"),
                              ("rotor_radius", "the rotor radius (m, > 0), e.g. 63 for the NREL 5 MW"),
                              ("wind_speed", "the mean wind speed at the hub (m/s, ≥ 0)")):
                if key not in t:
                    raise ConfigError(f"{where}.{key}: missing; {what}")
            item["hub"] = vector(t["hub"], 3, f"{where}.hub")
            for key, ok, accepted in (
                    ("rotor_radius", lambda v: v > 0, "a radius > 0 (m)"),
                    ("wind_speed", lambda v: v >= 0, "a mean wind speed ≥ 0 (m/s)"),
                    ("rho_air", lambda v: v > 0, "an air density > 0 (kg/m³), e.g. 1.2"),
                    ("direction_deg", lambda v: True, "degrees")):
                v = number(t.get(key, {"rho_air": 1.2, "direction_deg": 0.0}.get(key)), f"{where}.{key}")
                if not ok(v):
                    raise ConfigError(f"{where}.{key}: {t[key]!r}; give {accepted}")
                item[key] = v
            ct = t.get("thrust_coefficient")
            if ct is None or isinstance(ct, str):
                if isinstance(ct, str) and not ct.strip():
                    raise ConfigError(f"{where}.thrust_coefficient: an empty path; give a number, "
                                      "a CSV path, or leave the key out (bundled NREL 5 MW table)")
                item["ct"] = ct
            else:
                if isinstance(ct, bool) or not isinstance(ct, (int, float)) or not math.isfinite(ct):
                    v = -1.0    # not a number: the message below says what is accepted
                else:
                    v = float(ct)
                if not 0 <= v <= CT_MAX:
                    raise ConfigError(f"{where}.thrust_coefficient: {ct!r}; give a number in "
                                      f"[0, {CT_MAX}], a CSV path (columns wind_speed_mps, Ct), or "
                                      "leave the key out (bundled NREL 5 MW table)")
                item["ct"] = v
            out.append(item)
        unique_names(out, "wind_thrust")
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        # a relative table path is relative to the config file (the model's source), like
        # hydro.database; a model built without a file resolves it from the working directory
        base = Path(model.source).parent if model.source else Path.cwd()
        tabs, sources, cts = [], [], []
        for t in parsed:
            if isinstance(t["ct"], float):
                tabs.append(None)
                sources.append("constant")
                cts.append(t["ct"])
                continue
            path = bundled_ct_table() if t["ct"] is None else Path(t["ct"])
            if not path.is_absolute():
                path = base / path
            u, ct = read_ct_table(path, f"{t['where']}.thrust_coefficient")
            tabs.append((tuple(u.tolist()), tuple(ct.tolist())))
            sources.append(("bundled NREL 5 MW: " if t["ct"] is None else "") + str(path))
            cts.append(float(np.interp(t["wind_speed"], u, ct, left=0.0, right=0.0)))
        names = tuple(t["name"] for t in parsed)
        _warn_cut_out(np.array([t["wind_speed"] for t in parsed]), tabs, names)
        phi = np.radians([t["direction_deg"] for t in parsed])
        return cls(points=BodyPoints.on_bodies(model.com, [model.body_index(t["body"]) for t in parsed],
                                               [t["hub"] for t in parsed]),
                   wind_speed=device_array([t["wind_speed"] for t in parsed], np.float64),
                   thrust_coefficient=device_array(cts, np.float64),
                   rho_air=device_array([t["rho_air"] for t in parsed], np.float64),
                   area=device_array([math.pi * t["rotor_radius"] ** 2 for t in parsed]),
                   direction=device_array(np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)],
                                                   1)),
                   ct_tables=tuple(tabs), ct_sources=tuple(sources), names=names)


def _warn_cut_out(U, tabs, names):
    for p, tab in enumerate(tabs):
        top = _cut_out(tab)
        u = float(U.reshape(-1, len(tabs))[..., p].max()) if U.size else 0.0
        if top is not None and u > top:
            warnings.warn(f"wind_thrust {names[p]!r}: wind_speed {u:g} m/s is above the turbine's "
                          f"cut-out ({top:g} m/s, the last C_T > 0 of its table): no thrust",
                          WindWarning, stacklevel=3)
