"""Config tables → loads. Adding a load is one module in ``mfm/loads/`` and one line here.

Each class named here provides ``parse_table(raw, body_names) -> parsed`` (checks the ``[[table]]``
entries, raising :class:`~mfm.ConfigError` with the key path, value and what is accepted) and
``from_parsed(parsed, model) -> Load`` (the load on the compiled model). Loads are added to a model
in this order; the water, when the config has ``[hydro]``, comes first.
"""
from __future__ import annotations

import importlib

TABLES = {
    "moorings": ("mfm.loads.mooring", "PointSprings"),
    "ptos": ("mfm.loads.hydraulic_pto", "HydraulicPTO"),
    "body_matrices": ("mfm.loads.body_matrix", "LinearBodyMatrix"),
    "joint_loads": ("mfm.loads.joint_load", "JointLoad"),
    "points": ("mfm.loads.probes", "BodyPointOutputs"),
    "wind_thrust": ("mfm.loads.wind", "WindThrust"),
    "catenary_lines": ("mfm.loads.catenary", "CatenaryLines"),
    "morison": ("mfm.loads.morison", "MorisonElements"),
}


def load_class(table: str):
    """The load class that reads config table ``table``."""
    module, name = TABLES[table]
    return getattr(importlib.import_module(module), name)
