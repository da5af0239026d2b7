"""Outputs at named body points (a turbine hub, a fairlead): no load, only what they record.

Config table ``[[points]]``: ``name``, ``body``, ``point`` [x, y, z] m at q = 0. In the time
domain each records its position, velocity and acceleration in inertial axes,

    v = H_p q̇,   a = H_p q̈ + Ḣ_p q̇   (translational rows of the point's B-like matrix),

and in the frequency domain its displacement and acceleration RAOs (−ω² × displacement).
"""
from __future__ import annotations

import equinox as eqx
import numpy as np

from ..validation import body_ref, tables, vector
from ..mechanics.points import BodyPoints, h_matrix_at
from ..errors import ConfigError
from .base import Load, LoadOutput


class BodyPointOutputs(Load):
    """Recorded outputs at body points ``points`` (BodyPoints) named ``names``."""
    points: BodyPoints
    names: tuple[str, ...] = eqx.field(static=True)

    def evaluate(self, ctx):
        return LoadOutput()

    def static_load(self):
        return None

    def diagnostics(self, ctx, out):
        P = len(self.names)
        H, _, _ = self.points.h_matrix(ctx.kin)
        v, bias = self.points.velocity_and_bias(ctx.kin)
        acc = (H @ ctx.qdd + bias).reshape(P, 6)[:, :3]
        return {"point_position": self.points.positions(ctx.kin),
                "point_velocity": v.reshape(P, 6)[:, :3], "point_acceleration": acc}

    def outputs(self):
        return {"coords": {"point": list(self.names), "axis": ["x", "y", "z"]},
                "point_position": (("point", "axis"), {"long_name": "position of each named body "
                                                       "point, inertial axes", "units": "m"}),
                "point_velocity": (("point", "axis"), {"long_name": "velocity of each named body "
                                                       "point, inertial axes", "units": "m/s"}),
                "point_acceleration": (("point", "axis"), {"long_name": "acceleration of each "
                                                           "named body point, inertial axes",
                                                           "units": "m/s2"})}

    def frequency_outputs(self, model, kin0, x, omega):
        H = np.asarray(h_matrix_at(self.points, kin0)).reshape(len(self.names), 6, -1)[:, :3]
        disp = np.einsum("pai,wi->wpa", H, x)
        return {"point_rao": (("point", "axis"), disp,
                              {"long_name": "displacement of each named body point per metre of "
                               "wave amplitude, inertial axes", "units": "m/m"}),
                "point_acceleration_rao": (("point", "axis"), -omega[:, None, None] ** 2 * disp,
                                           {"long_name": "acceleration of each named body point "
                                            "per metre of wave amplitude", "units": "m/s2/m"}),
                "coords": {"point": list(self.names), "axis": ["x", "y", "z"]}}

    @classmethod
    def create(cls, model, points: dict) -> "BodyPointOutputs":
        """From Python: ``points`` {name: (body, [x, y, z] at q = 0)}."""
        entries = [{"name": n, "body": b, "point": list(np.asarray(p, dtype=float))}
                   for n, (b, p) in points.items()]
        return cls.from_parsed(cls.parse_table(entries, list(model.body_names)), model)

    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, t) in enumerate(tables(raw, "points", {"name", "body", "point", "notes"})):
            body = body_ref(t, "body", where, names)
            if "point" not in t:
                raise ConfigError(f"{where}.point: missing; the point [x, y, z] (m, inertial at q = 0)")
            out.append({"name": str(t.get("name", f"point{i}")), "body": body,
                        "point": vector(t["point"], 3, f"{where}.point")})
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        return cls(points=BodyPoints.on_bodies(model.com, [model.body_index(t["body"]) for t in parsed],
                                               [t["point"] for t in parsed]),
                   names=tuple(t["name"] for t in parsed))
