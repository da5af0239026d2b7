"""Mechanics by the Moving Frame Method: SE(3) frames (:mod:`.se3`), the float tree's specs
(:mod:`.tree`), the compiled :class:`~.model.Model` (:mod:`.compile`, :mod:`.model`), the B-matrix
and the body velocities (:mod:`.kinematics`), the equations of motion M* q̈ = Bᵀ F + Q − N* q̇ and
the joint reactions (:mod:`.dynamics`), and body points (:mod:`.points`). Imports nothing of mfm
but :mod:`mfm.runner.xla`; everything else builds on it."""
