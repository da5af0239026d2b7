"""The loads of a run: the model's own (its water prepared for the integrator's stage times, its
config's loads) and the radiation strategy ``radiation="auto"`` takes."""
from __future__ import annotations

import math

from ..loads.assembly import carried_loads
from ..loads.base import Load
from ..mechanics.model import Model
from . import integrators as _integrators
from ..validation import check_model


def model_loads(model: Model, sea=None, *, dt, duration, t0=0.0, ramp=0.0,
                radiation="convolution", memory=None, state_space_options=None,
                added_mass="lhs", integrator="rk4") -> tuple[Load, ...]:
    """The loads a model carries itself, ready for :func:`~mfm.timedomain.rollout.rollout`: with a
    [hydro] config its water for this sea and time grid (:func:`mfm.loads.water.build_water`,
    prepared for the stage times of ``integrator``), then the config's loads (``model.loads``:
    moorings, PTOs, …): :func:`mfm.loads.assembly.carried_loads` for this integrator."""
    model = check_model(model)
    stages = stage_offsets(integrator) if model.hydro is not None else ()
    return carried_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                         radiation=radiation, memory=memory,
                         state_space_options=state_space_options, added_mass=added_mass,
                         stage_offsets=stages)


# convolution work per run above which radiation="auto" takes the state space: ≈ 10 s of
# multiply–adds at the ~2e9/s one core does on these small matrix–vector products, the order of
# a state-space fit (benchmarks/fit_speed.py: 1–3 s for M4, Stansby & Li, Hallak; 22 s for Wu &
# Yuan's 90 dofs), so short runs keep the fit-free convolution
AUTO_CONVOLUTION_LIMIT = 2e10


def choose_radiation(model: Model, *, dt, n_steps, integrator="rk4", memory=None):
    """The radiation strategy ``radiation="auto"`` takes, and why: ``(name, reason)``.

    The convolution costs n_steps × S × n_lags × n² multiply–adds (S the stage offsets of the
    integrator, for each of which the history sum is formed once per step,
    :class:`mfm.loads.radiation.Convolution`; n the moved hydro dofs; n_lags = T_K/dt with T_K the
    memory from the decay of K, or ``memory``); the state space a fit once (seconds to a minute) and
    then O(n · poles) per evaluation. Above :data:`AUTO_CONVOLUTION_LIMIT` multiply–adds the state
    space is taken, its states advanced exactly (``"state_space_exact"``, stable with every
    integrator); below it the convolution, the direct evaluation of the Cummins integral with no
    fit. The reason is recorded in the result (``radiation_choice``)."""
    if model.hydro is None:
        return "none", "no water"
    integ = _integrators.get(integrator)
    spec = model.hydro
    T_K = spec.memory() if memory is None else float(memory)
    n = len(spec.moving)
    lags = int(math.ceil(T_K / dt))
    # an integrator of the user's that declares no offsets: its evaluations per step
    offsets = getattr(integ, "stage_offsets", None)
    S = len(offsets) if offsets else getattr(integ, "evaluations", 2)
    macs = float(n_steps) * S * lags * n * n
    what = (f"convolution {n_steps} steps × {S} stage offsets × {lags} lags (T_K {T_K:.3g} s / "
            f"dt {dt:.3g} s) × {n}² moved dofs = {macs:.2g} multiply–adds")
    if macs > AUTO_CONVOLUTION_LIMIT:
        return "state_space_exact", f"auto: {what} > {AUTO_CONVOLUTION_LIMIT:.0e}: state space"
    return "convolution", f"auto: {what} ≤ {AUTO_CONVOLUTION_LIMIT:.0e}: convolution"


def stage_offsets(integrator):
    integ = _integrators.get(integrator)
    offs = getattr(integ, "stage_offsets", None)
    if offs is None:
        raise TypeError(f"integrator {integ!r} declares no stage_offsets (the fractions of dt at "
                        "which it evaluates the dynamics in a step, e.g. (0.0, 0.5, 1.0) for RK4); "
                        "loads with memory need them")
    return tuple(float(o) for o in offs)
