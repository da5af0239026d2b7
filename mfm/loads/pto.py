"""Power take-offs, one concept at every level: a linear damper c on a rate ẇ.

A PTO absorbs P = c ẇ² (W), and over a period of a harmonic motion of complex amplitude ŵ at ω
on average ½ c ω² |ŵ|². Two kinds carry one:

- the **joint dampers** of the model (``damping`` of a joint in the config: the Model's term
  −c q̇ of :func:`mfm.mechanics.dynamics.joint_loads`): ẇ = q̇_k on each damped coordinate;
- a load that is a PTO (the hydraulic pistons, :class:`~mfm.loads.HydraulicPTO`): ẇ = g(q) q̇
  along its stroke, recorded per sample in the time domain (:meth:`Load.pto_records`) and
  linearised about q₀ for the linear levels (:meth:`Load.linear_dampers`).

Which coordinates are damped (:func:`damped_coordinates`), the joint dampers as a
:class:`~mfm.loads.base.LinearDampers` (:func:`joint_dampers`), every PTO of a model and its loads
at q₀ in the time domain's order (:func:`linear_ptos`) and the power (:func:`absorbed_power`,
:func:`mean_absorbed_power`) are written here once; :mod:`mfm.results` (every dataset) and the
spectral and linear levels read them from here.
"""
from __future__ import annotations

import numpy as np

from .base import LinearDampers


def absorbed_power(c, rate):
    """The power a linear damper absorbs, P = c v² (W): joint dampers (c q̇²) and hydraulic
    pistons (β ẇ²) alike."""
    return c * rate**2


def mean_absorbed_power(c, omega, amplitude):
    """Its mean over a period for a harmonic motion of complex amplitude x̂ at ω: ½ c ω² |x̂|²."""
    return 0.5 * c * omega**2 * np.abs(amplitude) ** 2


def damped_coordinates(damping) -> list[int]:
    """The coordinates with a joint damper: c > 0 (in any case, for a batch's (case, n_q))."""
    return [int(k) for k in np.flatnonzero(np.any(np.atleast_2d(np.asarray(damping)) > 0, axis=0))]


def joint_dampers(model) -> LinearDampers:
    """The model's joint dampers as PTOs: names the damped coordinates, c their damping, rows the
    identity's (ẇ = q̇_k), offset 0 (the displacement is the coordinate itself)."""
    damped = damped_coordinates(model.damping)
    return LinearDampers(tuple(model.coordinates[k] for k in damped),
                         np.asarray(model.damping, dtype=float)[damped],
                         np.eye(model.n_coordinates)[damped], np.zeros(len(damped)))


def load_dampers(loads, kin0) -> list[LinearDampers]:
    """The loads' PTOs linearised at ``kin0`` (:meth:`mfm.loads.base.Load.linear_dampers`): the
    hydraulic pistons the linear levels report beside the joint dampers."""
    return [d for d in (ld.linear_dampers(kin0) for ld in loads) if d is not None]


def linear_ptos(model, loads, kin0) -> LinearDampers:
    """Every PTO about q₀ as one damper set, in the time domain's ``pto`` order (the joint dampers,
    then the loads' pistons): names (P,), c (P,), rows G (P, n_q), offset (P,)."""
    parts = [joint_dampers(model)] + load_dampers(loads, kin0)
    return LinearDampers(tuple(n for d in parts for n in d.names),
                         np.concatenate([np.asarray(d.damping, dtype=float) for d in parts]),
                         np.concatenate([np.asarray(d.rows, dtype=float).reshape(-1, model.n_coordinates)
                                         for d in parts]),
                         np.concatenate([np.asarray(d.offset, dtype=float) for d in parts]))
