"""Kept for code that imports the water from here. The water load lives in
:mod:`mfm.loads.water` (with its radiation strategies in :mod:`mfm.loads.radiation`); the hydro
preparation (:class:`HydroSpec`, :func:`modal_form`, :func:`open_any_database`) in
:mod:`hydro.prepare`, which needs nothing of the mechanics."""
from hydro.prepare import HydroSpec, modal_form, open_any_database  # noqa: F401

from .loads.water import (HYDRO_COMPONENTS, MODES, Water, build_water, load_hydro_spec,  # noqa: F401
                          moving_dofs)
