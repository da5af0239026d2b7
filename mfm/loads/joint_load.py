"""Constant generalised loads on joint coordinates: a hinge preload, a constant thrust on a slider.

Config table ``[[joint_loads]]``: ``coordinate`` (a name of q, e.g. ``"wec1.angle"``), ``value``
(N m on a hinge angle, N on a stroke or a root translation), optional ``name``. It acts as
τ_k = value on that coordinate (virtual power τ q̇_k) in the time domain, the equilibrium and the
frequency domain alike (it moves q₀, and with it the linearisation).
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..backend import device_array
from ..validation import number, tables
from ..errors import ConfigError
from .base import Load, LoadOutput


class JointLoad(Load):
    """τ = ``values`` (n_q,) on the coordinates; ``names`` static (one per config entry)."""
    values: jnp.ndarray
    names: tuple[str, ...] = eqx.field(static=True, default=())

    def evaluate(self, ctx):
        return LoadOutput(tau=self.values)

    @classmethod
    def create(cls, model, values: dict) -> "JointLoad":
        """From Python: ``values`` {coordinate name: load (N m or N)}."""
        entries = [{"coordinate": c, "value": float(v)} for c, v in values.items()]
        return cls.from_parsed(cls.parse_table(entries, list(model.body_names)), model)

    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, t) in enumerate(tables(raw, "joint_loads", {"name", "coordinate", "value", "notes"})):
            c = t.get("coordinate")
            if not isinstance(c, str):
                raise ConfigError(f"{where}.coordinate: {c!r}; give a coordinate name such as "
                                  "\"float3.angle\" (see `mfm info CONFIG`)")
            if "value" not in t:
                raise ConfigError(f"{where}.value: missing; the load in N m (hinge) or N (slider)")
            out.append({"name": str(t.get("name", f"joint_load{i}")), "coordinate": c,
                        "value": number(t["value"], f"{where}.value"), "where": where})
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        tau = np.zeros(model.n_coordinates)
        for t in parsed:
            if t["coordinate"] not in model.coordinates:
                raise ConfigError(f"{t['where']}.coordinate: {t['coordinate']!r} is not a "
                                  f"coordinate of {model.name!r}; coordinates: {list(model.coordinates)}")
            tau[model.coordinate_index(t["coordinate"])] += t["value"]
        return cls(values=device_array(tau), names=tuple(t["name"] for t in parsed))
