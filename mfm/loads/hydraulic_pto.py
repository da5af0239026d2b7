"""Hydraulic PTO of Hallak et al., a piston between two body points.

Config table ``[[ptos]]``: ``body`` and ``point`` (one end, m at q = 0), ``anchor_body`` (omitted:
the inertial frame) and ``anchor`` (the other end), ``mu`` kg, ``beta`` N s/m, ``kappa`` N/m,
optional ``name``. Stroke w = |p_a − p_b| − L₀ (L₀ the length at q = 0) and force
f = μ ẅ + β ẇ + κ w resisting the extension: supplementary (oil column) mass μ, damping β and
stiffness κ. Its stroke rate is one more B-like row, ẇ = g(q) q̇ with g = uᵀ(H_a − H_b) (u the
unit vector from b to a):

    M* += μ g gᵀ,   Q −= g (μ ġq̇ + β ẇ + κ w),   ġq̇ = uᵀ(a_a − a_b) + (|Δv|² − ẇ²)/L

(a the velocity-product accelerations of the points, Δv = v_a − v_b), so the articulated arm stays
a tree (DESIGN §2). Absorbed power β ẇ².
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..validation import body_ref, number, tables, vector
from ..mechanics.points import BodyPoints
from ..errors import ConfigError
from .base import LinearDampers, Load, LoadOutput, PTORecords
from .pto import absorbed_power, mean_absorbed_power

PTO_KEYS = {"name", "kind", "body", "point", "anchor_body", "anchor", "mu", "beta", "kappa", "notes"}


class HydraulicPTO(Load):
    """Hydraulic PTOs: arrays ``mu`` (P,) kg, ``beta`` (P,) N s/m, ``kappa`` (P,) N/m,
    ``length0`` (P,) m; ``a`` the attachment points (BodyPoints, one per PTO); ``b`` the other
    ends (BodyPoints): a point on a body, or, where ``b_fixed[p]`` (static) is True, a point fixed
    in the inertial frame at ``b.ref0``. ``names`` static."""
    a: BodyPoints
    b: BodyPoints
    mu: jnp.ndarray
    beta: jnp.ndarray
    kappa: jnp.ndarray
    length0: jnp.ndarray
    b_fixed: tuple[bool, ...] = eqx.field(static=True)
    names: tuple[str, ...] = eqx.field(static=True)

    def _kinematics(self, kin):
        """Stroke w, rate ẇ, rows g (P, n_q) and ġq̇ (P,)."""
        fixed = jnp.asarray(np.array(self.b_fixed, dtype=float))[:, None]
        pa, pb = self.a.positions(kin), self.b.positions(kin)
        pb = fixed * self.b.ref0 + (1.0 - fixed) * pb
        va, aa = (x.reshape(-1, 6)[:, :3] for x in self.a.velocity_and_bias(kin))
        vb, ab = (x.reshape(-1, 6)[:, :3] * (1.0 - fixed) for x in self.b.velocity_and_bias(kin))
        Ha = self.a.h_matrix(kin)[0].reshape(len(self.names), 6, -1)[:, :3]
        Hb = self.b.h_matrix(kin)[0].reshape(len(self.names), 6, -1)[:, :3] * (1.0 - fixed)[:, :, None]
        d = pa - pb
        L = jnp.linalg.norm(d, axis=1)
        u = d / L[:, None]
        dv = va - vb
        wd = jnp.sum(u * dv, axis=1)
        g = jnp.einsum("pa,paq->pq", u, Ha - Hb)
        gdot_qd = jnp.sum(u * (aa - ab), axis=1) + (jnp.sum(dv * dv, axis=1) - wd**2) / L
        return L - self.length0, wd, g, gdot_qd, u

    def evaluate(self, ctx):
        w, wd, g, gdot_qd, _ = self._kinematics(ctx.kin)
        f = self.mu * gdot_qd + self.beta * wd + self.kappa * w
        return LoadOutput(tau=-(g.T @ f), mass=jnp.einsum("p,pi,pj->ij", self.mu, g, g))

    def _force(self, ctx):
        w, wd, g, gdot_qd, u = self._kinematics(ctx.kin)
        return w, wd, self.mu * (g @ ctx.qdd + gdot_qd) + self.beta * wd + self.kappa * w, u

    def reaction_loads(self, ctx, out):
        """The piston force on the two bodies, μ ẅ included (at the attachment points, along u)."""
        _, _, f, u = self._force(ctx)
        P = len(self.names)
        n = ctx.model.n_bodies
        Fa = jnp.concatenate([-f[:, None] * u, jnp.zeros((P, 3))], axis=1).reshape(-1)
        Wa = self.a.to_body_wrench(Fa, ctx.kin, n)
        fixed = jnp.asarray(np.array(self.b_fixed, dtype=float))[:, None]
        Wb = self.b.to_body_wrench((-Fa.reshape(P, 6) * (1.0 - fixed)).reshape(-1), ctx.kin, n)
        body = Wa + Wb
        return body if out.body is None else out.body + body

    def diagnostics(self, ctx, out):
        w, wd, force, _ = self._force(ctx)
        return {"hydraulic_stroke": w, "hydraulic_force": force,
                "hydraulic_power": absorbed_power(self.beta, wd)}

    def pto_records(self, records):
        return PTORecords(tuple(self.names), records["hydraulic_power"],
                          records["hydraulic_stroke"], records["hydraulic_force"])

    def force_rao(self, omega, stroke):
        """Complex piston force per metre of wave amplitude from the stroke RAO ŵ (n_ω, P):

            f̂ = (κ − ω² μ − iω β) ŵ        (N/m, x(t) = Re[x̂ e^{−iωt}])

        the first-order part of f = μ ẅ + β ẇ + κ w. Its μ term is μ times the stroke
        acceleration: ẅ = g q̈ + ġ q̇ and ġ q̇ is quadratic in the motion (second order), so
        ẅ̂ = −ω² ŵ. Mean absorbed power ½ β ω² |ŵ|² = ½ Re[f̂ conj(−iω ŵ)] (only β works)."""
        omega = np.asarray(omega, dtype=float)
        stroke = np.asarray(stroke)
        if stroke.ndim != 2 or stroke.shape != (omega.size, len(self.names)):
            raise ValueError(f"stroke: shape {stroke.shape}; expected (n_omega, n_pto) = "
                             f"({omega.size}, {len(self.names)})")
        w = omega[:, None]
        return (np.asarray(self.kappa)[None] - w**2 * np.asarray(self.mu)[None]
                - 1j * w * np.asarray(self.beta)[None]) * stroke

    def frequency_outputs(self, model, kin0, x, omega):
        """Stroke amplitude ŵ = g x̂, force amplitude f̂ = (κ − ω²μ − iωβ) ŵ (:meth:`force_rao`)
        and mean power ½ β ω² |ŵ|² per unit wave amplitude squared."""
        _, _, g, _, _ = _kinematics_at(self, kin0)
        stroke = x @ np.asarray(g).T
        return {"hydraulic_pto_rao": (("hydraulic_pto",), stroke,
                                      {"long_name": "piston stroke per metre of wave amplitude",
                                       "units": "m/m"}),
                "hydraulic_pto_power": (("hydraulic_pto",),
                                        mean_absorbed_power(np.asarray(self.beta), omega[:, None], stroke),
                                        {"long_name": "mean absorbed power β ẇ² per unit wave "
                                         "amplitude squared", "units": "W/m2"}),
                "hydraulic_pto_force_rao": (("hydraulic_pto",), self.force_rao(omega, stroke),
                                            {"long_name": "piston force μẅ + βẇ + κw per metre of "
                                             "wave amplitude, (κ − ω²μ − iωβ) × stroke RAO",
                                             "units": "N/m"}),
                "coords": {"hydraulic_pto": list(self.names)}}

    def linear_dampers(self, kin0):
        """The pistons to first order about q₀: ẇ = g(q₀) q̇, power β ẇ² (the β term of
        :meth:`evaluate`; μ and κ absorb nothing)."""
        w, _, g, _, _ = _kinematics_at(self, kin0)
        return LinearDampers(tuple(self.names), np.asarray(self.beta, dtype=float),
                             np.asarray(g, dtype=float), np.asarray(w, dtype=float))

    # -- config
    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, p) in enumerate(tables(raw, "ptos", PTO_KEYS)):
            if p.get("kind", "hydraulic") != "hydraulic":
                raise ConfigError(f"{where}.kind: {p.get('kind')!r}; accepted: 'hydraulic' (joint "
                                  "spring–dampers are set on the joint itself: damping, stiffness)")
            body_ref(p, "body", where, names)
            anchor_body = p.get("anchor_body")
            if anchor_body is not None and anchor_body not in names:
                raise ConfigError(f"{where}.anchor_body: {anchor_body!r} is not a body; known bodies: "
                                  f"{names} (leave it out to anchor in the inertial frame)")
            for key in ("point", "anchor"):
                if key not in p:
                    raise ConfigError(f"{where}.{key}: missing; a point [x, y, z] in m at q = 0")
            vals = {}
            for key in ("mu", "beta", "kappa"):
                vals[key] = number(p.get(key, 0.0), f"{where}.{key}")
                if vals[key] < 0:
                    raise ConfigError(f"{where}.{key}: {vals[key]} is negative; give a value ≥ 0")
            point, anchor = vector(p["point"], 3, f"{where}.point"), vector(p["anchor"], 3, f"{where}.anchor")
            if np.linalg.norm(point - anchor) < 1e-9:
                raise ConfigError(f"{where}: point and anchor coincide; a piston needs a length")
            out.append({"name": str(p.get("name", f"pto{i}")), "body": p["body"], "point": point,
                        "anchor_body": anchor_body, "anchor": anchor, **vals})
        return out

    @classmethod
    def from_parsed(cls, P, model):
        ia = [model.body_index(p["body"]) for p in P]
        ib = [model.body_index(p["anchor_body"]) if p["anchor_body"] else 0 for p in P]
        return cls(a=BodyPoints.on_bodies(model.com, ia, [p["point"] for p in P]),
                   b=BodyPoints.on_bodies(model.com, ib, [p["anchor"] for p in P]),
                   mu=jnp.asarray([p["mu"] for p in P]), beta=jnp.asarray([p["beta"] for p in P]),
                   kappa=jnp.asarray([p["kappa"] for p in P]),
                   length0=jnp.asarray([np.linalg.norm(p["point"] - p["anchor"]) for p in P]),
                   b_fixed=tuple(p["anchor_body"] is None for p in P),
                   names=tuple(p["name"] for p in P))


@eqx.filter_jit
def _kinematics_at(ptos: HydraulicPTO, kin):
    """``ptos._kinematics(kin)`` compiled, for the host's calls at q₀ (the frequency domain's
    outputs and dampers): op by op, each primitive compiled on its own."""
    return ptos._kinematics(kin)
