"""Kept for code that imports :class:`HydraulicPTO` from here; it lives in
:mod:`mfm.loads.hydraulic_pto`."""
from .loads.hydraulic_pto import HydraulicPTO  # noqa: F401
