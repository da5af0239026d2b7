"""Linear stiffness and damping matrices on a body point: extra damping, a linearised mooring.

Config table ``[[body_matrices]]``: ``body``; ``point`` [x, y, z] m at q = 0 (default: the body's
hydro reference point if it is wet, else its centre of mass); ``stiffness`` and ``damping``, each
a 6×6 matrix or 6 diagonal values, in inertial axes about the point (N/m, N/rad, N m/m, N m/rad;
N s/m …); ``damping_ratio`` a table of fractions of critical damping per mode, e.g.
``{heave = 0.2, pitch = 0.4}``, set from the model's own linearisation when the model is built
(:func:`mfm.frequency.resolve_damping_ratios`, which :func:`mfm.load` calls: the linearisation
is not this module's to make); optional ``name``. The load on the point is

    F = −K ξ − D ξ̇,   ξ = (displacement of the point, rotation vector of the body),

so it linearises to Hᵀ K H and Hᵀ D H (H the point's B-like rows).
"""
from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..validation import body_ref, number, tables
from ..backend import device_array
from ..mechanics.points import BodyPoints
from ..errors import ConfigError
from .base import MODES, Load, LoadOutput

KEYS = {"name", "body", "point", "stiffness", "damping", "damping_ratio", "notes"}

# What sets a damping ratio's damping: the model's linearisation, which sits above the loads
# (mfm.frequency.modes registers resolve_damping_ratios here when it is imported, as every
# `import mfm` does): the inversion that keeps this module from importing upward.
_RESOLVERS: list = []


def register_resolver(resolve):
    """Give :meth:`LinearBodyMatrix.create` the function ``resolve(model, load) -> load`` that sets
    the damping of the ratios it asks for (:func:`mfm.frequency.resolve_damping_ratios`)."""
    _RESOLVERS[:] = [resolve]


class LinearBodyMatrix(Load):
    """F = −K ξ − D ξ̇ at body points. ``points`` (BodyPoints, one per matrix), ``stiffness`` and
    ``damping`` (P, 6, 6) inertial axes about the points; ``names`` static. ``damping_ratios``:
    the fractions of critical damping asked for and not yet added to ``damping``, each
    (matrix index, body, mode, ratio, point): a load with any cannot be evaluated until
    :func:`mfm.frequency.resolve_damping_ratios` has set them from the model's linearisation."""
    points: BodyPoints
    stiffness: jnp.ndarray
    damping: jnp.ndarray
    names: tuple[str, ...] = eqx.field(static=True, default=())
    damping_ratios: tuple = eqx.field(static=True, default=())

    def evaluate(self, ctx):
        if self.damping_ratios:
            raise ValueError(
                f"body matrices {list(self.names)}: damping_ratio {self.damping_ratios} is not set "
                "yet: it is a fraction of critical damping from the model's linearisation; give the "
                "load to mfm.frequency.resolve_damping_ratios(model, load) first (mfm.load does so "
                "for [[body_matrices]] tables)")
        xi = self.points.xi(ctx.kin).reshape(-1, 6)
        v, _ = self.points.velocity_and_bias(ctx.kin)
        F = -(jnp.einsum("pab,pb->pa", self.stiffness, xi)
              + jnp.einsum("pab,pb->pa", self.damping, v.reshape(-1, 6)))
        return LoadOutput(body=self.points.to_body_wrench(F.reshape(-1), ctx.kin, ctx.model.n_bodies))

    @classmethod
    def create(cls, model, body: str, *, point=None, stiffness=None, damping=None,
               damping_ratio: dict | None = None, name: str | None = None) -> "LinearBodyMatrix":
        """One matrix on ``body`` from Python, as a ``[[body_matrices]]`` entry would give it
        (stiffness/damping 6×6 or 6 diagonal values; damping_ratio e.g. {"heave": 0.2}, set from
        the linearisation of ``model`` with this load, :func:`mfm.frequency.resolve_damping_ratios`)."""
        entry = {"body": body}
        if point is not None:
            entry["point"] = list(np.asarray(point, dtype=float))
        for key, v in (("stiffness", stiffness), ("damping", damping)):
            if v is not None:
                entry[key] = np.asarray(v, dtype=float).tolist()
        if damping_ratio:
            entry["damping_ratio"] = dict(damping_ratio)
        if name is not None:
            entry["name"] = name
        load = cls.from_parsed(cls.parse_table([entry], list(model.body_names)), model)
        if load.damping_ratios:
            if not _RESOLVERS:      # only where mfm.frequency was never imported: not via `mfm`
                raise RuntimeError("LinearBodyMatrix.create(damping_ratio=...) needs the model's "
                                   "linearisation: import mfm (or mfm.frequency) first")
            load = _RESOLVERS[0](model, load)
        return load

    # -- config
    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, t) in enumerate(tables(raw, "body_matrices", KEYS)):
            body = body_ref(t, "body", where, names)
            item = {"name": str(t.get("name", f"{body}_matrix{i}")), "body": body,
                    "point": None, "ratios": {}}
            if "point" in t:
                item["point"] = _vec3(t["point"], f"{where}.point")
            for key in ("stiffness", "damping"):
                item[key] = _matrix6(t.get(key, [0.0] * 6), f"{where}.{key}")
            ratios = t.get("damping_ratio", {})
            if not isinstance(ratios, dict):
                raise ConfigError(f"{where}.damping_ratio: {ratios!r}; give a table such as "
                                  "{heave = 0.2, pitch = 0.4} (fractions of critical damping)")
            for mode, r in ratios.items():
                if mode not in MODES:
                    raise ConfigError(f"{where}.damping_ratio.{mode}: not a mode; accepted: {list(MODES)}")
                r = number(r, f"{where}.damping_ratio.{mode}")
                if not 0 <= r < 10:
                    raise ConfigError(f"{where}.damping_ratio.{mode}: {r}; give a fraction of "
                                      "critical damping ≥ 0 (0.2 = 20 %)")
                item["ratios"][mode] = r
            out.append(item)
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        idx = [model.body_index(t["body"]) for t in parsed]
        pts = []
        for t, i in zip(parsed, idx):
            if t["point"] is not None:
                pts.append(t["point"])
            elif model.hydro is not None and i in model.hydro.body_index:
                pts.append(np.asarray(model.hydro.ref0)[model.hydro.body_index.index(i)])
            else:
                pts.append(np.asarray(model.com[i]))
        ratios = tuple((p, t["body"], mode, float(ratio), tuple(float(x) for x in pts[p]))
                       for p, t in enumerate(parsed) for mode, ratio in t["ratios"].items())
        return cls(points=BodyPoints.on_bodies(model.com, idx, pts),
                   stiffness=device_array(np.stack([t["stiffness"] for t in parsed])),
                   damping=device_array(np.stack([t["damping"] for t in parsed])),
                   names=tuple(t["name"] for t in parsed), damping_ratios=ratios)

    def with_damping(self, p: int, mode: str, c: float) -> "LinearBodyMatrix":
        """This load with ``c`` (N s/m or N m s/rad) added on the diagonal of matrix ``p`` for
        ``mode``, and that mode's ratio no longer pending."""
        j = MODES.index(mode)
        D = np.asarray(self.damping).copy()
        D[p, j, j] += c
        rest = tuple(r for r in self.damping_ratios if not (r[0] == p and r[2] == mode))
        out = eqx.tree_at(lambda ld: ld.damping, self, jnp.asarray(D))
        return dataclasses.replace(out, damping_ratios=rest)


def _vec3(v, where):
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (3,) or not np.isfinite(a).all():
        raise ConfigError(f"{where}: {v!r} is not a list of 3 finite numbers (m)")
    return a


def _matrix6(v, where):
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is not None and a.shape == (6,):
        a = np.diag(a)
    if a is None or a.shape != (6, 6) or not np.isfinite(a).all():
        raise ConfigError(f"{where}: {v!r}; give 6 diagonal values or a 6×6 matrix (inertial axes "
                          "about the point: surge, sway, heave, roll, pitch, yaw)")
    return a
