"""Studies built on the time and frequency domains: sweeps (:mod:`.sweep`), the fidelity ladder
(:mod:`.fidelity`), stability of the integrators (:mod:`.stability`), wave energy measures
(:mod:`.wec`)."""
