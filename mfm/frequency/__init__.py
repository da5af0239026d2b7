"""The frequency domain's core: the model at rest and its one linearisation (:mod:`.rest`:
equilibrium, the linear system, a run's checks), RAOs and joint reactions (:mod:`.response`),
natural frequencies (:mod:`.modes`) and the judgement of a radiation fit on the model's modes
(:mod:`.fitcheck`), each as numbers: the front doors that label them
(:func:`mfm.frequency_response`, :func:`mfm.natural_frequencies`) are the runner's. The spectral and linear time-domain levels of the fidelity ladder are the
runner's (:mod:`mfm.runner.spectral`, :mod:`mfm.runner.linear`)."""
from .modes import (NaturalModes, critical_damping, cubic_natural_frequencies,  # noqa: F401
                    natural_modes, resolve_damping_ratios)
from .response import Raos, joint_reactions, solve_raos  # noqa: F401
from .rest import (LinearSystem, equilibrium, linear_system, linearise,  # noqa: F401
                   linearise_lines, no_restoring, system_loads)
