"""The frequency domain: the model at rest and its one linearisation (:mod:`.rest`: equilibrium,
the linear system, a run's checks), RAOs and joint reactions (:mod:`.response`), natural
frequencies (:mod:`.modes`), the spectral response (:mod:`.spectral`) and the linear time-domain
response (:mod:`.linear`)."""
from .modes import (critical_damping, cubic_natural_frequencies, natural_frequencies,  # noqa: F401
                    resolve_damping_ratios)
from .response import frequency_response, joint_reactions  # noqa: F401
from .rest import (LinearSystem, equilibrium, linear_system, linearise,  # noqa: F401
                   linearise_lines, no_restoring, system_loads)
