"""mfm: floating multi-body systems by the Moving Frame Method (MFM) in jax.

Importing mfm switches jax to float64: every physical quantity here is float64.
"""
import jax

jax.config.update("jax_enable_x64", True)
