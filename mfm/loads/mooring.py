"""Linear moorings: springs from points on bodies to where those points sit at q = 0.

Config table ``[[moorings]]``: ``body``, ``point`` [x, y, z] m at q = 0 (inertial), ``stiffness``
[kx, ky, kz] N/m (inertial axes), optional ``name``. The force at the point is
F = −diag(k) (p − p₀); off the centre of mass it also gives the moment ρ × F, so a mooring on a
fairlead couples surge and pitch (K = k [[1, ℓ], [ℓ, ℓ²]] for a lever ℓ below the CoM).
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..mechanics.points import BodyPoints
from ..errors import ConfigError
from .base import Load, LoadOutput
from ..validation import body_ref, tables, vector


class PointSprings(Load):
    """Linear springs at body points (e.g. a linear mooring), N. ``points`` the attachment points
    (:class:`~mfm.mechanics.points.BodyPoints`, p₀ = their positions at q = 0); ``stiffness`` (m, 3) N/m."""
    points: BodyPoints
    stiffness: jnp.ndarray
    # the config's names of the springs (what mfm.optimize calls "<name>.kx"); static, read by
    # the host only
    names: tuple[str, ...] = eqx.field(static=True, default=())

    def evaluate(self, ctx):
        f = -self.stiffness * (self.points.positions(ctx.kin) - self.points.ref0)
        F = jnp.concatenate([f, jnp.zeros_like(f)], axis=1).reshape(-1)
        return LoadOutput(body=self.points.to_body_wrench(F, ctx.kin, ctx.model.n_bodies))

    # -- config
    @staticmethod
    def parse_table(raw, body_names):
        out = []
        for i, (where, m) in enumerate(tables(raw, "moorings", {"name", "body", "point",
                                                                 "stiffness", "notes"})):
            body = body_ref(m, "body", where, body_names)
            k = vector(m.get("stiffness"), 3, f"{where}.stiffness") if "stiffness" in m else None
            if k is None or np.any(k < 0):
                raise ConfigError(f"{where}.stiffness: {m.get('stiffness')!r}; give [kx, ky, kz] ≥ 0 "
                                  "in N/m (inertial axes)")
            if "point" not in m:
                raise ConfigError(f"{where}.point: missing; the attachment point [x, y, z] (m, q = 0)")
            out.append({"name": str(m.get("name", f"mooring{i}")), "body": body,
                        "point": vector(m["point"], 3, f"{where}.point"), "stiffness": k})
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        return cls(points=BodyPoints.on_bodies(model.com, [model.body_index(m["body"]) for m in parsed],
                                               [m["point"] for m in parsed]),
                   stiffness=jnp.asarray(np.stack([m["stiffness"] for m in parsed])),
                   names=tuple(m["name"] for m in parsed))
