"""mfm: floating multi-body systems by the Moving Frame Method (MFM) in jax.

Importing mfm switches jax to float64: every physical quantity here is float64.

Data flows one way: config (TOML) → float tree → :class:`Model` → :func:`simulate` →
:class:`xarray.Dataset` → plots.
"""
from . import _xla  # noqa: I001  (first: XLA options must be set before jax starts its backend)
from ._xla import PerformanceWarning  # noqa: E402
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from . import config, integrators, loads, results, se3, water, wec  # noqa: E402
from .build import compile_tree, load  # noqa: E402
from .frequency import equilibrium, frequency_response, natural_frequencies  # noqa: E402
from .dynamics import (coriolis_matrix, energies, evaluate, forward_dynamics,  # noqa: E402
                       mass_matrix, reaction_loads)
from .kinematics import b_matrix, b_matrix_dot, body_poses, kinematics  # noqa: E402
from .model import Model  # noqa: E402
from .simulate import AccuracyWarning, SimulationError, StabilityWarning, rollout, simulate, simulate_batch  # noqa: E402
from . import stability  # noqa: E402
from .stability import amplification_matrix, floquet, largest_stable_dt  # noqa: E402
from .spectral import spectral_response  # noqa: E402
from . import linear  # noqa: E402
from .linear import linear_response  # noqa: E402
from . import fidelity  # noqa: E402
from .fidelity import reduce  # noqa: E402
from .tree import ConfigError  # noqa: E402
from .sweep import SweepError, sweep  # noqa: E402

__all__ = ["AccuracyWarning", "PerformanceWarning", "amplification_matrix", "fidelity", "floquet", "largest_stable_dt",
           "reduce", "spectral_response", "linear", "linear_response", "stability", "ConfigError", "Model", "SimulationError", "b_matrix", "b_matrix_dot", "body_poses",
           "compile_tree", "config", "coriolis_matrix", "energies", "equilibrium", "evaluate",
           "forward_dynamics", "frequency_response", "natural_frequencies", "water",
           "integrators", "kinematics", "load", "loads", "mass_matrix", "reaction_loads",
           "results", "rollout", "se3", "simulate", "simulate_batch", "StabilityWarning", "sweep", "SweepError", "wec"]
