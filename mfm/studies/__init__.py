"""Studies built on the time and frequency domains: sweeps (:mod:`.sweep`), the fidelity ladder
(:mod:`.fidelity`), stability of the integrators (:mod:`.stability`), wave energy measures
(:mod:`.wec`), each method's error against its wall time (:mod:`.speed_accuracy`), and the
Wu & Yuan (2025) platform (:mod:`.wu_yuan`, its layout and configs :mod:`.wu_yuan_layout`).
The front door (``mfm``) imports none of the last three: ``from mfm.studies import wu_yuan``."""
