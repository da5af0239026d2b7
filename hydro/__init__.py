"""hydro: the water. Hydrodynamic databases, radiation memory, waves, excitation.

This package never imports the mechanics core (`mfm`): it takes poses and velocities as arrays and
returns forces, databases and time series.
"""
import jax

jax.config.update("jax_enable_x64", True)
