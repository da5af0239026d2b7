"""hydro: the water. Hydrodynamic databases, radiation memory, waves, excitation.

This package never imports the mechanics core (`mfm`): it takes poses and velocities as arrays and
returns forces, databases and time series.
"""
import jax

jax.config.update("jax_enable_x64", True)

# sea states, spectra and excitation time series
from hydro.waves import (  # noqa: E402,F401
    Jonswap, MeasuredElevation, PiersonMoskowitz, Regular, SeaStateWarning, Spreading, UserSpectrum,
    WaveComponents,
    elevation, ramp, wavenumber,
)
# many seas discretised at once (a study's), the same components as each sea's own
from hydro.seabatch import components_many  # noqa: E402,F401
from hydro.excitation import (  # noqa: E402,F401
    excitation_coefficients, excitation_dataarray, excitation_time_series,
)
# second order: the mean and Newman's slow wave drift force from a database's mean_drift
from hydro import drift  # noqa: E402,F401
from hydro.drift import drift_time_series, mean_drift_of  # noqa: E402,F401

# BEM databases from capytaine (capytaine itself is imported lazily inside them).
from hydro import bem, geometry  # noqa: E402,F401

# database schema, WAMIT reader, radiation memory (K(t), Ogilvie), state space.
from hydro import database, radiation, statespace, wamit  # noqa: E402,F401
from hydro.database import (  # noqa: E402,F401
    from_capytaine, open_database, read_netcdf, select_bodies, to_netcdf, validate,
    write_netcdf,
)
from hydro.wamit import read_wamit  # noqa: E402,F401
# BEMIO HDF5 (WEC-Sim's and SEA-Stack's files): read and written (netCDF4 imported when used)
from hydro import bemio  # noqa: E402,F401
from hydro.bemio import read_bemio, write_bemio  # noqa: E402,F401
from hydro.radiation import (  # noqa: E402,F401
    added_mass_from_irf, check_grid, damping_from_irf, impulse_response, memory_length,
)
from hydro.statespace import StateSpaceRadiation, fit_state_space, fitted_impedance  # noqa: E402,F401

# a database made ready for both domains (symmetry, A∞, K(t), fits, convolution weights), and one
# function that opens any database file by its type
from hydro import prepare  # noqa: E402,F401
from hydro.prepare import HydroSpec, open_any_database  # noqa: E402,F401
