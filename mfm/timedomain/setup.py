"""The loads of a run: the model's own (its water prepared for the integrator's stage times, its
config's loads). Which radiation strategy ``radiation="auto"`` takes is the runner's choice
(:mod:`mfm.runner.choices`)."""
from __future__ import annotations

from ..loads.assembly import carried_loads
from ..loads.base import Load
from ..mechanics.model import Model
from . import integrators as _integrators
from ..radiation import resolve as resolve_radiation
from ..validation import check_model


def model_loads(model: Model, sea=None, *, dt, duration, t0=0.0, ramp=0.0,
                radiation="convolution", memory=None, state_space_options=None,
                added_mass="lhs", integrator="rk4", extra=(), mean_drift=None) -> tuple[Load, ...]:
    """The loads of a run, ready for :func:`~mfm.timedomain.rollout.rollout`: with a [hydro]
    config the model's water for this sea and time grid (:func:`mfm.loads.water.build_water`,
    prepared for the stage times of ``integrator``), then the config's loads (``model.loads``:
    moorings, PTOs, …) and the ``extra`` loads of a front door, each laid on the run
    (:meth:`~mfm.loads.base.Load.for_run`): :func:`mfm.loads.assembly.carried_loads` for this
    integrator (``mean_drift``: the water's drift table in place of its database's)."""
    model = check_model(model)
    radiation, memory, state_space_options = resolve_radiation(radiation, memory,
                                                               state_space_options)
    stages = stage_offsets(integrator) if model.hydro is not None \
        else declared_stage_offsets(integrator)
    return carried_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                         radiation=radiation, memory=memory,
                         state_space_options=state_space_options, added_mass=added_mass,
                         stage_offsets=stages, extra=extra, mean_drift=mean_drift)


def declared_stage_offsets(integrator) -> tuple:
    """The integrator's ``stage_offsets``, or () where it declares none (a user's integrator that
    follows the protocol without them: only a load laid on the stage times needs them)."""
    offs = getattr(_integrators.get(integrator), "stage_offsets", None)
    return () if offs is None else tuple(float(o) for o in offs)


def stage_offsets(integrator):
    integ = _integrators.get(integrator)
    offs = getattr(integ, "stage_offsets", None)
    if offs is None:
        raise TypeError(f"integrator {integ!r} declares no stage_offsets (the fractions of dt at "
                        "which it evaluates the dynamics in a step, e.g. (0.0, 0.5, 1.0) for RK4); "
                        "loads with memory need them")
    return tuple(float(o) for o in offs)
