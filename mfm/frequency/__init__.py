"""The frequency domain: the model linearised about its static equilibrium with the loads it
carries, RAOs and joint reactions, natural frequencies (:mod:`.response`), the spectral response
(:mod:`.spectral`) and the linear time-domain response (:mod:`.linear`)."""
from .response import (LinearSystem, critical_damping, cubic_natural_frequencies,  # noqa: F401
                       equilibrium, frequency_response, joint_reactions, linear_system, linearise,
                       natural_frequencies, system_loads)
