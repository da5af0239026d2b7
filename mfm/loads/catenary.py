"""Quasi-static catenary mooring lines, solved by MoorPy once and interpolated inside jax.

Config table ``[[catenary_lines]]``, one entry per line:

- ``body``: the body the fairlead is on; ``fairlead`` [x, y, z] m at q = 0 (inertial);
  ``anchor`` [x, y, z] m (fixed, on the seabed, below the fairlead);
- ``length`` unstretched length, m; ``weight`` N/m in water, or ``mass_per_length`` kg/m in water
  (weight = mass_per_length × the model's gravity); ``EA`` axial stiffness, N;
  ``seabed_friction`` MoorPy's seabed friction coefficient CB (default 0: no friction);
- ``line_type``: a table ``{name = "chain", length = …, weight = …, EA = …}`` holding any of the
  line keys above, or the name of a type given as a table in another entry; the line's own keys
  win over its type's;
- ``table_extent`` [Δx, Δz] m, the half-widths of the table about the rest spans (default
  [40, 15]); ``table_step`` [hx, hz] m, its spacing (default [1, 1]);
- optional ``name`` and ``notes``.

Physics: each line is quasi-static (MoorPy's ``Catenary.catenary``: elastic, with seabed contact
and friction). Its fairlead force depends only on the fairlead's position relative to its anchor,
through the horizontal span x = |r_F,h − r_A,h| and the height z = z_F − z_A:

    f = −H(x, z) ê_h − V(x, z) ẑ,    ê_h = (r_F,h − r_A,h)/x,

H the horizontal and V the vertical fairlead tension (the line pulls the fairlead towards its
anchor and down), applied at the fairlead (so it gives a moment about the CoM too).

Inside jax. The compiled time loop cannot call MoorPy, so H and V are tabulated once on the host
on a grid of (x, z) about the rest spans and interpolated by the tensor-product cubic spline of
the table (not-a-knot; evaluated as bicubic Hermite patches from the spline's nodal values and
derivatives: continuous second derivatives, so the stiffness −∂f/∂r that the equilibrium and
the frequency domain take from jax is smooth; the tables themselves are made and kept by
:mod:`mfm.loads.catenary_tables`). Default table: ±40 m × ±15 m at 1 m; on the Wu &
Yuan line its error is at most 3.2e-4 of the local tension anywhere in it (at the slack corner,
where H → 0) and 1.8e-5 of the rest tension within ±20 m × ±10 m, and its derivative (the
stiffness) agrees with a finite difference of MoorPy within 6e-5 there, 4e-6 at rest
(``tests/test_catenary.py``); refine ``table_step`` for more. Each table is asked of the host
(:meth:`mfm.host.Host.mooring_table`): lines of one geometry share one table, and the runner's
host keeps tables in the process, in the config's database file (where ``mfm fits`` stores them)
and on disk (:mod:`mfm.runner.tables`), the same to the last bit as a table made anew.

Outside the table nothing is clipped or extrapolated: the force is NaN, so a run that takes a
fairlead out stops as non-finite and :meth:`CatenaryLines.describe_nonfinite` names the line, its
span and the table's bounds (widen ``table_extent``); the equilibrium and the linearisation fail
likewise. :meth:`CatenaryLines.table_margin` tells how close a configuration is to an edge.

Linearised lines. :meth:`CatenaryLines.linearised` (or :func:`mfm.frequency.linearise_lines` for every line of
a model) gives the same lines with the fairlead force and the tensions replaced by their first-order
expansion in the fairlead positions about a configuration q₀ (the static equilibrium by default):

    f(r_F) = f(r_F,0) + ∂f/∂r_F (r_F − r_F,0),   (H, V)(r_F) = (H, V)₀ + ∂(H, V)/∂r_F (r_F − r_F,0),

the derivatives those of the table at r_F,0 (so the equilibrium, the stiffness and the tension RAO
of the frequency domain are the nonlinear lines' own), the fairleads still moving with their bodies
exactly. The time domain with linearised lines is the model the frequency domain solves, as far as
the lines go: the check of one against the other, and the measure of what the lines' nonlinearity
does in a given sea. Linearised lines have no table, so they never leave it.

Outputs: ``fairlead_tension``, ``fairlead_horizontal_tension`` and ``fairlead_vertical_tension``
(N, per ``mooring_line``) in the time domain; ``fairlead_tension_rao`` (N/m, complex) in the
frequency domain, the tension's own linearisation ∂T/∂r_F · r̂_F.
"""
from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..validation import body_ref, number, tables, unknown, vector
from ..mechanics.points import BodyPoints
from ..errors import ConfigError
from .base import Load, LoadOutput
from .. import host
from ..backend import device_array
from .catenary_tables import make_table, moorpy_version, table_centre

LINE_KEYS = {"length", "weight", "mass_per_length", "EA", "seabed_friction"}
KEYS = {"name", "body", "fairlead", "anchor", "line_type", "table_extent", "table_step",
        "notes"} | LINE_KEYS
TYPE_KEYS = {"name", "notes"} | LINE_KEYS
DEFAULT_EXTENT = (40.0, 15.0)
DEFAULT_STEP = (1.0, 1.0)


def _hermite(t):
    t2, t3 = t * t, t * t * t
    return (jnp.stack([2 * t3 - 3 * t2 + 1, -2 * t3 + 3 * t2]),      # values at 0, 1
            jnp.stack([t3 - 2 * t2 + t, t3 - t2]))                   # slopes at 0, 1


def interpolate(coef, n, lo, step, x, z):
    """The spline of one table at (x, z): (H, V) and whether (x, z) lies in the table (outside:
    NaN, nothing is extrapolated). ``coef`` (NX, NZ, 4, 2) of which the first ``n`` = (nx, nz)
    nodes are the table (the rest pads tables of several lines to one array)."""
    u, w = (x - lo[0]) / step[0], (z - lo[1]) / step[1]
    inside = (u >= 0) & (u <= n[0] - 1) & (w >= 0) & (w <= n[1] - 1)
    i = jnp.clip(jnp.floor(u), 0, n[0] - 2).astype(int)
    j = jnp.clip(jnp.floor(w), 0, n[1] - 2).astype(int)
    t, s = u - i, w - j
    c = jax.lax.dynamic_slice(coef, (i, j, 0, 0), (2, 2, 4, 2))      # corners (a, b, data, HV)
    h0t, h1t = _hermite(t)
    h0s, h1s = _hermite(s)
    basis = jnp.stack([jnp.outer(h0t, h0s), jnp.outer(h1t, h0s), jnp.outer(h0t, h1s),
                       jnp.outer(h1t, h1s)], axis=2)                 # (a, b, data)
    val = jnp.einsum("abd,abdk->k", basis, c)
    return jnp.where(inside, val, jnp.nan), inside


class CatenaryLines(Load):
    """Quasi-static catenary lines from fairleads on bodies to fixed anchors (module docstring).
    ``fairleads`` (BodyPoints), ``anchors`` (P, 3); the lines' tables ``coef`` (P, NX, NZ, 4, 2)
    (line k's own nx × nz nodes first, ``n`` (P, 2), the rest NaN) with origin ``lo`` (P, 2) and
    spacing ``step`` (P, 2) in (x, z); ``names`` and ``lines`` (the line parameters, for provenance
    and checks) static."""
    fairleads: BodyPoints
    anchors: jnp.ndarray
    coef: jnp.ndarray
    n: jnp.ndarray
    lo: jnp.ndarray
    step: jnp.ndarray
    names: tuple[str, ...] = eqx.field(static=True)
    lines: tuple = eqx.field(static=True)     # per line: dict items (length, EA, weight, …, hi)
    # linearised lines (:meth:`linearised`): the fairleads r_F,0 (P, 3) about which, the force
    # f₀ (P, 3) and its derivative ∂f/∂r_F (P, 3, 3), the tensions (H, V)₀ (P, 2) and theirs (P, 2, 3)
    linear: bool = eqx.field(static=True, default=False)
    lin_p0: jnp.ndarray | None = None
    lin_f0: jnp.ndarray | None = None
    lin_df: jnp.ndarray | None = None
    lin_hv0: jnp.ndarray | None = None
    lin_dhv: jnp.ndarray | None = None

    # -- the physics
    def spans(self, p):
        """Horizontal spans x (P,), heights z (P,) and horizontal unit vectors ê_h (P, 2) of the
        fairleads p (P, 3) from their anchors."""
        d = p[:, :2] - self.anchors[:, :2]
        x = jnp.sqrt(jnp.sum(d * d, axis=1))
        return x, p[:, 2] - self.anchors[:, 2], d / x[:, None]

    def tensions(self, p):
        """(H, V, inside) per line at fairlead positions p (P, 3): horizontal and vertical
        fairlead tensions (N; NaN outside the table) and whether each is in its table."""
        if self.linear:
            HV = self.lin_hv0 + jnp.einsum("kca,ka->kc", self.lin_dhv, p - self.lin_p0)
            return HV[:, 0], HV[:, 1], jnp.ones(HV.shape[0], dtype=bool)
        x, z, _ = self.spans(p)
        HV, inside = jax.vmap(interpolate)(self.coef, self.n, self.lo, self.step, x, z)
        return HV[:, 0], HV[:, 1], inside

    def fairlead_forces(self, p):
        """Forces on the fairleads (P, 3), inertial axes, N."""
        if self.linear:
            return self.lin_f0 + jnp.einsum("kab,kb->ka", self.lin_df, p - self.lin_p0)
        H, V, _ = self.tensions(p)
        _, _, e = self.spans(p)
        return jnp.concatenate([-H[:, None] * e, -V[:, None]], axis=1)

    def linearised(self, model, q0) -> "CatenaryLines":
        """These lines linearised in their fairlead positions about the configuration ``q0``
        (n_q,) of ``model`` (module docstring): f = f₀ + ∂f/∂r_F (r_F − r_F,0), and likewise H and
        V, each line's derivatives taken from its table at r_F,0 (jax). The fairleads move with
        their bodies as before; :func:`mfm.equilibrium` and :func:`mfm.frequency_response` give the
        same results with either (the same force and derivative at q₀)."""
        from ..mechanics.kinematics import kinematics

        if self.linear:
            raise ValueError("linearised: these catenary lines are linearised already")
        q0 = jnp.asarray(q0, jnp.float64)
        if q0.shape != (model.n_coordinates,):
            raise ValueError(f"q0: shape {tuple(q0.shape)}; expected ({model.n_coordinates},), "
                             "the model's coordinates")
        p0 = self.fairleads.positions(kinematics(model, q0))
        f0, df, hv0, dhv = _expansion(self, p0)
        _, _, inside = self.tensions(p0)
        if not bool(jnp.all(inside)) or not bool(jnp.all(jnp.isfinite(df))):
            bad = [n for n, ok in zip(self.names, np.asarray(inside)) if not ok]
            raise ValueError(f"q0: the fairleads of catenary lines {bad} lie outside their tables "
                             "there; linearise about a configuration inside them")
        return dataclasses.replace(self, linear=True, lin_p0=p0, lin_f0=f0, lin_df=df,
                                   lin_hv0=hv0, lin_dhv=dhv)

    def evaluate(self, ctx):
        f = self.fairlead_forces(self.fairleads.positions(ctx.kin))
        F = jnp.concatenate([f, jnp.zeros_like(f)], axis=1).reshape(-1)
        return LoadOutput(body=self.fairleads.to_body_wrench(F, ctx.kin, ctx.model.n_bodies))

    # -- outputs
    def diagnostics(self, ctx, out):
        H, V, _ = self.tensions(self.fairleads.positions(ctx.kin))
        return {"fairlead_tension": jnp.sqrt(H * H + V * V), "fairlead_horizontal_tension": H,
                "fairlead_vertical_tension": V}

    def outputs(self):
        line = ("mooring_line",)
        return {"coords": {"mooring_line": list(self.names)},
                "fairlead_tension": (line, {"long_name": "tension at the fairlead of each "
                                            "catenary line (quasi-static, MoorPy table)",
                                            "units": "N"}),
                "fairlead_horizontal_tension": (line, {"long_name": "horizontal fairlead tension "
                                                       "H (the line pulls towards its anchor)",
                                                       "units": "N"}),
                "fairlead_vertical_tension": (line, {"long_name": "vertical fairlead tension V "
                                                     "(the line pulls down)", "units": "N"})}

    def linear_outputs(self, model, kin0):
        """The fairlead tension T = √(H² + V²) to first order about q₀: T₀ at the fairleads of
        ``kin0`` and L = ∂T/∂r_F ∂r_F/∂q (the line's own linearisation, the one the stiffness
        uses)."""
        T0, dT, Hp = (np.asarray(a) for a in _tension_gradient(self, kin0))
        return {"fairlead_tension": (("mooring_line",), T0, np.einsum("ka,kai->ki", dT, Hp),
                                     {"long_name": "tension at the fairlead of each catenary line, "
                                      "linearised about the equilibrium", "units": "N"}),
                "coords": {"mooring_line": list(self.names)}}

    def frequency_outputs(self, model, kin0, x, omega):
        """Tension amplitude per metre of wave amplitude: L x̂ with L of :meth:`linear_outputs`."""
        _, _, L, _ = self.linear_outputs(model, kin0)["fairlead_tension"]
        return {"fairlead_tension_rao": (("mooring_line",), np.asarray(x) @ L.T,
                                         {"long_name": "fairlead tension amplitude per metre of "
                                          "wave amplitude (linearised at the equilibrium)",
                                          "units": "N/m"}),
                "coords": {"mooring_line": list(self.names)}}

    def provenance(self):
        parts = []
        for k, name in enumerate(self.names):
            ln = dict(self.lines[k])
            nx, nz = (int(a) for a in np.asarray(self.n)[k])
            parts.append(f"{name}: x {ln['x_lo']:.6g}..{ln['x_hi']:.6g} m ({nx}), "
                         f"z {ln['z_lo']:.6g}..{ln['z_hi']:.6g} m ({nz})")
        lin = {}
        if self.linear:
            lin = {"catenary_linearised": "fairlead forces and tensions linearised in the fairlead "
                                          "positions about " + "; ".join(
                f"{n}: r_F ({', '.join(f'{v:.6g}' for v in np.asarray(p))}) m"
                for n, p in zip(self.names, self.lin_p0))}
        return {**lin, "catenary_moorpy_version": moorpy_version(),
                "catenary_tables": "; ".join(parts),
                "catenary_interpolation": "tensor-product not-a-knot cubic spline of MoorPy's "
                                          "(H, V) over (span, height); NaN outside the table"}

    # -- the table's edges
    def table_margin(self, model, q):
        """Per line the smallest distance (m) from the fairlead's (x, z) at q to its table's
        edge, negative outside."""
        from ..mechanics.kinematics import kinematics

        x, z, _ = (np.asarray(a) for a in self.spans(self.fairleads.positions(
            kinematics(model, jnp.asarray(q, jnp.float64)))))
        out = []
        for k in range(len(self.names)):
            ln = dict(self.lines[k])
            out.append(min(x[k] - ln["x_lo"], ln["x_hi"] - x[k], z[k] - ln["z_lo"], ln["z_hi"] - z[k]))
        return np.array(out)

    def describe_nonfinite(self, model, q, qd):
        from ..mechanics.kinematics import kinematics

        q = np.asarray(q, dtype=float)
        if self.linear or not np.isfinite(q).all():      # linearised lines have no table to leave
            return None
        margin = self.table_margin(model, q)
        x, z, _ = (np.asarray(a) for a in self.spans(self.fairleads.positions(
            kinematics(model, jnp.asarray(q)))))
        v = np.abs(np.asarray(self.fairleads.h_matrix(kinematics(model, jnp.asarray(q)))[0])
                   .reshape(len(self.names), 6, -1)[:, :3] @ np.asarray(qd, dtype=float)).max(axis=1)
        k = int(np.argmin(margin))
        ln = dict(self.lines[k])
        # the last finite saved state may precede the exit by a save interval: a fairlead within
        # 10 % of the table's half-width of an edge, or 2 s of its speed, is named too
        near = max(0.1 * min(ln["ext"]), 2.0 * float(v[k]))
        if margin[k] >= max(near, 0.0):
            return None
        where = "left" if margin[k] < 0 else f"was {margin[k]:.3g} m from the edge of"
        return (f"Likely cause: the fairlead of catenary line {self.names[k]!r} {where} its table "
                f"(span x = {x[k]:.6g} m, height z = {z[k]:.6g} m; table x ∈ [{ln['x_lo']:.6g}, "
                f"{ln['x_hi']:.6g}], z ∈ [{ln['z_lo']:.6g}, {ln['z_hi']:.6g}] m). Outside its table "
                "a line's force is NaN, never extrapolated: widen table_extent.")

    # -- config
    @classmethod
    def create(cls, model, lines: list[dict]) -> "CatenaryLines":
        """From Python: ``lines`` a list of ``[[catenary_lines]]`` entries (dicts)."""
        return cls.from_parsed(cls.parse_table(list(lines), list(model.body_names)), model)

    @staticmethod
    def parse_table(raw, names):
        entries = list(tables(raw, "catenary_lines", KEYS))
        types = {}
        for where, t in entries:                       # line types given as tables, by name
            lt = t.get("line_type")
            if isinstance(lt, dict):
                unknown(lt, TYPE_KEYS, f"{where}.line_type")
                if not isinstance(lt.get("name"), str) or not lt["name"]:
                    raise ConfigError(f"{where}.line_type.name: {lt.get('name')!r}; a line type "
                                      "given as a table needs a name (a string) to be reused by")
                if lt["name"] in types and types[lt["name"]][1] != lt:
                    raise ConfigError(f"{where}.line_type: {lt['name']!r} is defined twice, "
                                      f"differently ({types[lt['name']][0]}.line_type)")
                for key in LINE_KEYS & set(lt):
                    number(lt[key], f"{where}.line_type.{key}")
                types[lt["name"]] = (where, lt)
        out = []
        for i, (where, t) in enumerate(entries):
            body = body_ref(t, "body", where, names)
            props, src = {}, {}
            lt = t.get("line_type")
            if isinstance(lt, str):
                if lt not in types:
                    raise ConfigError(f"{where}.line_type: {lt!r} is not a line type; defined "
                                      f"(as tables in other entries): {sorted(types)}")
                lt = types[lt][1]
            elif lt is not None and not isinstance(lt, dict):
                raise ConfigError(f"{where}.line_type: {lt!r}; give a table {{name = …, length = …, "
                                  "weight = …, EA = …}} or the name of one")
            if lt is not None:
                for key in LINE_KEYS & set(lt):
                    props[key], src[key] = lt[key], f"{where}.line_type.{key}"
            for key in LINE_KEYS & set(t):
                props[key], src[key] = t[key], f"{where}.{key}"
            if "weight" in props and "mass_per_length" in props:
                if "weight" in t and "mass_per_length" in t:
                    raise ConfigError(f"{where}: give weight (N/m in water) or mass_per_length "
                                      "(kg/m in water), not both")
                props.pop("mass_per_length" if "weight" in t else "weight")
            for key, what in (("length", "the unstretched length (m)"),
                              ("EA", "the axial stiffness EA (N)")):
                if key not in props:
                    raise ConfigError(f"{where}.{key}: missing; {what}, on the line or its line_type")
            if "weight" not in props and "mass_per_length" not in props:
                raise ConfigError(f"{where}.weight: missing; the weight in water (N/m), or "
                                  "mass_per_length (kg/m in water), on the line or its line_type")
            item = {"name": str(t.get("name", f"line{i}")), "body": body}
            for key in sorted(props):
                v = number(props[key], src[key])
                if key == "seabed_friction":
                    if v < 0:
                        raise ConfigError(f"{src[key]}: {v}; give a friction coefficient ≥ 0 "
                                          "(0: none)")
                elif v <= 0:
                    raise ConfigError(f"{src[key]}: {v}; give a positive number "
                                      "(length m, weight N/m, mass_per_length kg/m, EA N)")
                item[key] = v
            item.setdefault("seabed_friction", 0.0)
            for key in ("fairlead", "anchor"):
                if key not in t:
                    raise ConfigError(f"{where}.{key}: missing; [x, y, z] m (inertial"
                                      + (", at q = 0)" if key == "fairlead" else ", fixed)"))
                item[key] = vector(t[key], 3, f"{where}.{key}")
            z0 = item["fairlead"][2] - item["anchor"][2]
            x0 = float(np.hypot(*(item["fairlead"][:2] - item["anchor"][:2])))
            if z0 <= 0:
                raise ConfigError(f"{where}.anchor: {list(item['anchor'])}; the anchor must lie "
                                  f"below the fairlead {list(item['fairlead'])} (it sits on the seabed)")
            for key, default, what in (("table_extent", DEFAULT_EXTENT, "half-widths"),
                                       ("table_step", DEFAULT_STEP, "spacings")):
                v = vector(t.get(key, list(default)), 2, f"{where}.{key}")
                if np.any(v <= 0):
                    raise ConfigError(f"{where}.{key}: {t.get(key)!r}; give positive [horizontal, "
                                      f"vertical] {what} in m")
                item[key] = tuple(float(a) for a in v)
            ext = item["table_extent"]
            if x0 - ext[0] <= 0 or z0 - ext[1] <= 0:
                raise ConfigError(f"{where}.table_extent: {list(ext)}; the table about the rest "
                                  f"span {x0:.6g} m and height {z0:.6g} m would reach the anchor "
                                  f"(x or z ≤ 0): give half-widths below [{x0:.6g}, {z0:.6g}]")
            if any(e / s > 2000 for e, s in zip(ext, item["table_step"])):
                raise ConfigError(f"{where}.table_step: {list(item['table_step'])}; more than 4000 "
                                  f"points per axis for table_extent {list(ext)}")
            item["x0"], item["z0"] = x0, z0
            out.append(item)
        seen = [it["name"] for it in out]
        dup = sorted({n for n in seen if seen.count(n) > 1})
        if dup:
            raise ConfigError(f"catenary_lines: names {dup} used more than once; give each line "
                              "its own name")
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        coef, lo, step, lines = [], [], [], []
        for t in parsed:
            w = t["weight"] if "weight" in t else t["mass_per_length"] * float(model.gravity)
            try:
                # a table stored in the config's database file (`mfm fits`) is read from there
                x0, z0 = table_centre(t["x0"], t["z0"])
                xs, zs, c = host.current().mooring_table(
                    make_table, x0, z0, t["table_extent"], t["table_step"], t["length"], t["EA"],
                    w, t["seabed_friction"],
                    stored=None if model.hydro is None else model.hydro.stored_in)
            except ValueError as e:
                raise ConfigError(f"catenary_lines {t['name']!r}: {e}; narrow table_extent") from None
            coef.append(c)
            lo.append([xs[0], zs[0]])
            step.append([xs[1] - xs[0], zs[1] - zs[0]])
            lines.append(tuple({"length": t["length"], "EA": t["EA"], "weight": w,
                                "seabed_friction": t["seabed_friction"], "x_lo": float(xs[0]),
                                "x_hi": float(xs[-1]), "z_lo": float(zs[0]),
                                "z_hi": float(zs[-1]), "ext": t["table_extent"]}.items()))
        n = np.array([c.shape[:2] for c in coef])
        padded = np.full((len(coef), *n.max(axis=0), 4, 2), np.nan)
        for k, c in enumerate(coef):
            padded[k, :c.shape[0], :c.shape[1]] = c
        return cls(fairleads=BodyPoints.on_bodies(model.com, [model.body_index(t["body"]) for t in parsed],
                                                  [t["fairlead"] for t in parsed]),
                   anchors=device_array(np.stack([t["anchor"] for t in parsed])),
                   coef=device_array(padded), n=device_array(n), lo=device_array(np.array(lo)),
                   step=device_array(np.array(step)),
                   names=tuple(t["name"] for t in parsed), lines=tuple(lines))


@eqx.filter_jit
def _tension_gradient(lines: CatenaryLines, kin0):
    """Each line's fairlead tension T = √(H² + V²) (P,) and ∂T/∂r_F (P, 3) at the fairleads of
    ``kin0``, and the fairleads' velocity maps ∂ṙ_F/∂q̇ (P, 3, n_q) there (compiled: op by op,
    the first frequency response of Wu & Yuan spent 6 s compiling its primitives one by one)."""
    P = len(lines.names)

    def tension(p):
        H, V, _ = lines.tensions(p)
        return jnp.sqrt(H * H + V * V)

    p0 = lines.fairleads.positions(kin0)
    k = jnp.arange(P)
    dT = jax.jacfwd(tension)(p0)[k, k]                                      # line k's own
    return tension(p0), dT, lines.fairleads.h_matrix(kin0)[0].reshape(P, 6, -1)[:, :3]


@eqx.filter_jit
def _expansion(lines: CatenaryLines, p0):
    """f₀ (P, 3), ∂f/∂r_F (P, 3, 3), (H, V)₀ (P, 2) and ∂(H, V)/∂r_F (P, 2, 3) of each line at its
    fairlead p0 (P, 3) (compiled: the eager jacobian of the tables took ~20 s)."""
    k = jnp.arange(p0.shape[0])

    def hv(p):
        H, V, _ = lines.tensions(p)
        return jnp.stack([H, V], axis=1)

    out = []
    for fn in (lines.fairlead_forces, hv):
        J = jax.jacfwd(fn)(p0)                                  # (P, c, P, 3)
        out += [fn(p0), J[k, :, k, :]]                         # line k's own: (P, c, 3)
    return tuple(out)
