"""mfm: floating multi-body systems by the Moving Frame Method (MFM) in jax.

Importing mfm switches jax to float64 (every physical quantity here is float64) and starts jax's
backend with the XLA option that compiles mfm's time loops as one function
(:mod:`mfm.backend`); it changes no environment variable, no garbage-collector setting and no
cache folder: ``mfm.load`` (or the runner's first program) turns jax's compilation cache on
(:mod:`mfm.runner.door`).

Data flows one way: config (TOML) → float tree → :class:`Model` → :func:`simulate` →
:class:`xarray.Dataset` → plots. The package is three layers (docs/ARCHITECTURE.md):

- **the pure core**, jax and numpy functions of (model, loads, state): ``mechanics`` (frames,
  the tree, the model, kinematics and dynamics), ``loads`` (the load protocol and every load),
  ``timedomain`` (integrators, the rollout, what it records), ``frequency`` (the linearisation
  at rest, equilibrium, RAOs, natural frequencies);
- **the runner** (``runner``), what a front door does around the core: checks and ``auto``
  choices, compilation and its caches, threads, pipelining and progress; with ``results``, every
  dataset;
- **the front doors**, the names below; ``studies`` (sweeps, fidelity, stability, design) and
  ``io`` (configs, building a model, plots, the command line, BEM databases) use them.
"""
from . import backend  # noqa: I001  (first: XLA's option must reach jax's backend as it starts)
from .backend import PerformanceWarning  # noqa: E402
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from . import frequency, loads, radiation, results  # noqa: E402
from .errors import (AccuracyWarning, ConfigError, SeaStateError, SimulationError,  # noqa: E402
                     StabilityWarning, SweepError)
from .io.build import compile_tree, load  # noqa: E402
from .mechanics.dynamics import (coriolis_matrix, energies, evaluate, forward_dynamics,  # noqa: E402
                                 mass_matrix, reaction_loads)
from .mechanics.kinematics import b_matrix, b_matrix_dot, body_poses, kinematics  # noqa: E402
from .mechanics.model import Model  # noqa: E402
from .runner.batch import simulate_batch  # noqa: E402
from .runner import door as _door  # noqa: E402
from .runner.frequency import (equilibrium, frequency_response, mean_drift,  # noqa: E402
                               natural_frequencies)
from .runner.linear import linear_response  # noqa: E402
from .runner.simulation import simulate  # noqa: E402
from .runner.spectral import spectral_response  # noqa: E402
from .studies import stability as _stability  # noqa: E402
from .studies.fidelity import reduce  # noqa: E402
from .studies.floquet import floquet  # noqa: E402
from .studies.optimize import optimize  # noqa: E402
from .studies.sweep import sweep  # noqa: E402
from . import integrators  # noqa: E402
from .timedomain import rollout as _rollout, setup as _setup  # noqa: E402

# the core's calls get the runner's host (programs kept on disk, tables kept) unless a caller
# hands another (mfm.host.using): mfm's own state, no setting of the user's
_door.install()
rollout = _rollout.rollout
model_loads = _setup.model_loads
amplification_matrix = _stability.amplification_matrix
largest_stable_dt = _stability.largest_stable_dt

__all__ = ["AccuracyWarning", "ConfigError", "Model", "PerformanceWarning", "SeaStateError",
           "SimulationError", "StabilityWarning", "SweepError", "amplification_matrix",
           "b_matrix", "b_matrix_dot", "body_poses", "compile_tree", "coriolis_matrix",
           "energies", "equilibrium", "evaluate", "floquet", "forward_dynamics", "frequency",
           "frequency_response", "integrators", "kinematics", "largest_stable_dt",
           "linear_response", "load", "loads", "mass_matrix", "mean_drift", "model_loads",
           "natural_frequencies", "optimize", "radiation", "reaction_loads", "reduce", "results",
           "rollout", "simulate", "simulate_batch", "spectral_response", "sweep"]
