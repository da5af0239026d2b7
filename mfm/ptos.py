"""Power take-offs that are not a joint's own spring–damper.

Hydraulic PTO of seed 000 (Hallak et al.): a piston between an attachment point on one body and
one on another body (or a fixed anchor), with stroke w = |p_a − p_b| − L₀ (L₀ the length at q = 0)
and force f = μ ẅ + β ẇ + κ w resisting the extension: supplementary (oil column) mass μ, damping
β and stiffness κ. Its stroke rate is one more B-like row, ẇ = g(q) q̇ with g = uᵀ(H_a − H_b) (u the
unit vector from b to a): the element contributes μ g gᵀ to M* and −g (μ ġq̇ + β ẇ + κ w) to the
generalised loads, and the articulated arm stays a tree (DESIGN §2).
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .loads import Load, LoadOutput
from .points import BodyPoints


class HydraulicPTO(Load):
    """Hydraulic PTOs (seed 000): arrays ``mu`` (P,) kg, ``beta`` (P,) N s/m, ``kappa`` (P,) N/m,
    ``length0`` (P,) m; ``a`` the attachment points (BodyPoints, one per PTO); ``b`` the other
    ends (BodyPoints): a point on a body, or, where ``b_fixed[p]`` (static) is True, a point fixed
    in the inertial frame at ``b.ref0``. ``names`` static.
    Absorbed power β ẇ²."""
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

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        w, wd, g, gdot_qd, _ = self._kinematics(kin)
        f = self.mu * gdot_qd + self.beta * wd + self.kappa * w
        return LoadOutput(tau=-(g.T @ f), mass=jnp.einsum("p,pi,pj->ij", self.mu, g, g))

    def reaction_loads(self, model, t, q, qd, qdd, z, kin, memory, out):
        """The piston force on the two bodies, μ ẅ included (at the attachment points, along u)."""
        w, wd, g, gdot_qd, u = self._kinematics(kin)
        f = self.mu * (g @ qdd + gdot_qd) + self.beta * wd + self.kappa * w
        P = len(self.names)
        Fa = jnp.concatenate([-f[:, None] * u, jnp.zeros((P, 3))], axis=1).reshape(-1)
        Wa = self.a.to_body_wrench(Fa, kin, model.n_bodies)
        fixed = jnp.asarray(np.array(self.b_fixed, dtype=float))[:, None]
        Wb = self.b.to_body_wrench((-Fa.reshape(P, 6) * (1.0 - fixed)).reshape(-1), kin, model.n_bodies)
        body = Wa + Wb
        return body if out.body is None else out.body + body

    def diagnostics(self, model, t, q, qd, qdd, z, kin, memory, out):
        w, wd, g, gdot_qd, _ = self._kinematics(kin)
        force = self.mu * (g @ qdd + gdot_qd) + self.beta * wd + self.kappa * w
        return {"hydraulic_stroke": w, "hydraulic_force": force,
                "hydraulic_power": self.beta * wd**2}

    def annotate(self, ds, rec):
        import xarray as xr

        names = list(self.names)
        power = xr.DataArray(rec["hydraulic_power"], dims=("time", "pto"), coords={"pto": names})
        stroke = xr.DataArray(rec["hydraulic_stroke"], dims=("time", "pto"), coords={"pto": names})
        if "pto" in ds.dims:
            power = xr.concat([ds.pto_power, power], dim="pto")
            stroke = xr.concat([ds.pto_displacement, stroke], dim="pto")
            ds = ds.drop_vars(["pto_power", "pto_displacement", "pto"])
        ds = ds.assign(pto_power=power, pto_displacement=stroke)
        ds["pto_power"].attrs = {"long_name": "absorbed power: c q̇² (joint dampers), β ẇ² (hydraulic)",
                                 "units": "W"}
        ds["pto_displacement"].attrs = {"long_name": "joint coordinate or piston stroke", "units": "rad or m"}
        ds["pto_force"] = (("time", "hydraulic_pto"), rec["hydraulic_force"],
                           {"long_name": "hydraulic piston force μẅ + βẇ + κw", "units": "N"})
        return ds.assign_coords(hydraulic_pto=names)
