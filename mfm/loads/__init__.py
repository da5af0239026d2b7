"""Loads as plug-ins: one module per load, one base (:mod:`mfm.loads.base`), one registry of config
tables (:mod:`mfm.loads.registry`). Each load serves the time domain, the equilibrium and the
frequency domain from one definition.

- :class:`~mfm.loads.water.Water`: Cummins hydrodynamics (built per sea state by
  :func:`mfm.timedomain.setup.model_loads`), radiation as a strategy (:mod:`mfm.loads.radiation`);
- :class:`PointSprings` (``[[moorings]]``), :class:`HydraulicPTO` (``[[ptos]]``),
  :class:`LinearBodyMatrix` (``[[body_matrices]]``), :class:`JointLoad` (``[[joint_loads]]``),
  :class:`BodyPointOutputs` (``[[points]]``), :class:`WindThrust` (``[[wind_thrust]]``),
  :class:`CatenaryLines` (``[[catenary_lines]]``: quasi-static MoorPy lines, tabulated);
- :class:`BodyWrench`, :class:`CoordinateForceSeries`: loads given directly (``loads=``).
"""
from .base import Context, FrequencyTerms, LinearDampers, Load, LoadOutput
from .body_matrix import LinearBodyMatrix
from .catenary import CatenaryLines
from .generic import BodyWrench, CoordinateForceSeries
from .hydraulic_pto import HydraulicPTO
from .joint_load import JointLoad
from .mooring import PointSprings
from .probes import BodyPointOutputs
from .registry import TABLES, load_class
from .wind import WindThrust

__all__ = ["BodyPointOutputs", "BodyWrench", "CatenaryLines", "Context", "CoordinateForceSeries",
           "FrequencyTerms", "HydraulicPTO", "JointLoad", "LinearBodyMatrix", "LinearDampers", "Load",
           "LoadOutput", "PointSprings", "TABLES", "WindThrust", "load_class"]
