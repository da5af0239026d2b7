"""mfm: floating multi-body systems by the Moving Frame Method (MFM) in jax.

Importing mfm switches jax to float64: every physical quantity here is float64.

Data flows one way: config (TOML) → float tree → :class:`Model` → :func:`simulate` →
:class:`xarray.Dataset` → plots. The package is laid out by concern (README, Architecture):
``mechanics`` (frames, the tree, the model, kinematics and dynamics), ``loads`` (the load
protocol and every load), ``frequency`` (the linearisation at rest, equilibrium, responses,
spectra, natural frequencies), ``timedomain`` (integrators, the rollout, recording, batches,
:func:`simulate`), ``studies`` (sweeps, fidelity, stability), ``io`` (configs, building a
model, plots, the command line, BEM databases), and ``results`` (every dataset). The names
below are the front doors; old module paths (``mfm.simulate``, ``mfm.stability``, …) keep
working through :mod:`mfm._compat`, with a warning naming the new place.
"""
from . import _xla  # noqa: I001  (first: XLA options must be set before jax starts its backend)
from ._xla import PerformanceWarning  # noqa: E402
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from . import frequency, loads, radiation, results  # noqa: E402
from .timedomain import integrators  # noqa: E402
from .io.build import compile_tree, load  # noqa: E402
from .frequency import equilibrium, frequency_response, natural_frequencies  # noqa: E402
from .mechanics.dynamics import (coriolis_matrix, energies, evaluate, forward_dynamics,  # noqa: E402
                                 mass_matrix, reaction_loads)
from .mechanics.kinematics import b_matrix, b_matrix_dot, body_poses, kinematics  # noqa: E402
from .mechanics.model import Model  # noqa: E402
from .errors import AccuracyWarning, SeaStateError, SimulationError, StabilityWarning  # noqa: E402
from .timedomain.batch import simulate_batch  # noqa: E402
from .timedomain.rollout import rollout  # noqa: E402
from .timedomain.setup import model_loads  # noqa: E402
from .timedomain.simulation import simulate  # noqa: E402
from .studies.floquet import floquet  # noqa: E402
from .studies.stability import amplification_matrix, largest_stable_dt  # noqa: E402
from .frequency.spectral import spectral_response  # noqa: E402
from .frequency.linear import linear_response  # noqa: E402
from .studies.fidelity import reduce  # noqa: E402
from .errors import ConfigError, SweepError  # noqa: E402
from .studies.sweep import sweep  # noqa: E402
from .studies.optimize import optimize  # noqa: E402
from . import _compat  # noqa: E402
from . import _gc  # noqa: E402

_compat.install()
# the libraries' objects, which live as long as the process, out of the collector's walks (and
# its exit's): see mfm/_gc.py
_gc.freeze()


def __getattr__(name):
    # a module that moved (mfm.stability, mfm.config, ...): its stand-in, warning with the new name
    return _compat.package_attribute(name)


__all__ = ["AccuracyWarning", "ConfigError", "Model", "PerformanceWarning", "SeaStateError",
           "SimulationError", "StabilityWarning", "SweepError", "amplification_matrix",
           "b_matrix", "b_matrix_dot", "body_poses", "compile_tree", "coriolis_matrix",
           "energies", "equilibrium", "evaluate", "floquet", "forward_dynamics", "frequency",
           "frequency_response", "integrators", "kinematics", "largest_stable_dt",
           "linear_response", "load", "loads", "mass_matrix", "model_loads",
           "natural_frequencies", "optimize", "radiation", "reaction_loads", "reduce", "results", "rollout", "simulate",
           "simulate_batch", "spectral_response", "sweep"]
