"""The choices of ``radiation="auto"``: the convolution or a state space, how a state space's
states advance, and whether the fit is good enough for the model (judged on its own modes and
its response to the sea, :mod:`mfm.frequency.fitcheck`); each choice with its reason, recorded in
the result (``radiation_choice``)."""
from __future__ import annotations

import math

import numpy as np

from ..mechanics.model import Model
from ..timedomain import integrators as _integrators
from ..timedomain.setup import stage_offsets


# convolution work per run above which radiation="auto" takes the state space: ≈ 10 s of
# multiply–adds at the ~2e9/s one core does on these small matrix–vector products, the order of
# a state-space fit (benchmarks/fit_speed.py: 1–3 s for M4, Stansby & Li, Hallak; 22 s for Wu &
# Yuan's 90 dofs), so short runs keep the fit-free convolution
AUTO_CONVOLUTION_LIMIT = 2e10


# the largest relative error of a fitted radiation mode's response that radiation="auto" accepts
# from integrating its states with the run's integrator instead of advancing them exactly
# (:func:`integrated_state_error`); the fits themselves are further from their databases (band
# errors of 1e-2 and more)
STATE_SPACE_TOLERANCE = 1e-3


def choose_radiation(model: Model, *, dt, n_steps, integrator="rk4", memory=None,
                     state_space_options=None, sea=None, loads=None):
    """The radiation strategy ``radiation="auto"`` takes, and why: ``(name, reason)``.

    First the convolution or the state space (:func:`convolution_or_state_space`: the
    convolution's work against :data:`AUTO_CONVOLUTION_LIMIT`, no fit needed); then, for the
    state space, how its states advance (:func:`state_space_update`, from the fit: integrated by
    the integrator where that is as good as exact and cheaper, else advanced exactly); then the
    fit judged on the model's own modes and its response to ``sea`` over the run
    (:func:`judge_radiation`, ``loads`` the run's extra loads): past its tolerances, the
    convolution. The reason is recorded in the result (``radiation_choice``)."""
    name, why = convolution_or_state_space(model, dt=dt, n_steps=n_steps, integrator=integrator,
                                           memory=memory)
    if name != "state_space_exact":
        return name, why
    name, how = state_space_update(model, dt=dt, integrator=integrator,
                                   state_space_options=state_space_options)
    verdict = judge_radiation(model, loads=loads, sea=sea, duration=n_steps * float(dt),
                              state_space_options=state_space_options,
                              stage_offsets=stage_offsets(integrator))
    return judged_choice(name, f"{why}; {how}", verdict)


def judge_radiation(model: Model, *, loads=None, sea=None, duration=None,
                    state_space_options=None, added_mass="lhs", stage_offsets=(0.0, 0.5, 1.0),
                    q0=None):
    """The verdict of :func:`mfm.frequency.fitcheck.judge_fit` on the model's state-space fit
    (``state_space_options``): its modes about the static equilibrium over ``duration`` seconds
    and its response to ``sea``'s components, against the database's A(ω), B(ω), for the model
    with its extra ``loads`` in still water (the loads of the run's checks: the same compiled
    linearisation, :func:`mfm.frequency.rest.still_water_loads`). Where no equilibrium is found
    (a body that sinks alone), about ``q0`` (default zeros)."""
    from ..frequency import fitcheck, rest

    lds = rest.still_water_loads(model, loads, added_mass=added_mass,
                                 stage_offsets=stage_offsets)
    try:
        sys = rest._linear_system(model, lds)
    except ValueError:
        start = np.zeros(model.n_coordinates) if q0 is None else np.asarray(q0, float)
        sys = rest._linear_system(model, lds, start)
    spec = model.hydro
    components = None if sea is None else sea.components(spec.water_depth, spec.g)
    return fitcheck.judge_fit(model, sys, state_space_options=state_space_options,
                              components=components, horizon=duration)


def judged_choice(name, why, verdict):
    """(name, why) of a state-space choice after its fit's ``verdict``: kept where it passed,
    else ``"convolution"`` (the Cummins integral evaluated directly: no fit to be wrong), with
    the verdict's summary in the reason either way."""
    if verdict.ok:
        return name, f"{why}; {verdict.summary}"
    return "convolution", f"{why}; but {verdict.summary}: the convolution instead"


def convolution_or_state_space(model: Model, *, dt, n_steps, integrator="rk4", memory=None):
    """The first half of :func:`choose_radiation`, without the fit: ``("convolution", why)``,
    ``("state_space_exact", why)`` (some state space: :func:`state_space_update` says which) or
    ``("none", "no water")``.

    The convolution costs n_steps × S × n_lags × n² multiply–adds (S the stage offsets of the
    integrator, for each of which the history sum is formed once per step,
    :class:`mfm.loads.radiation.Convolution`; n the moved hydro dofs; n_lags = T_K/dt with T_K the
    memory from the decay of K, or ``memory``); the state space a fit once (seconds to a minute) and
    then O(n · poles) per evaluation. Above :data:`AUTO_CONVOLUTION_LIMIT` multiply–adds the state
    space is taken; below it the convolution, the direct evaluation of the Cummins integral with
    no fit."""
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


def integrated_state_error(amplification, z):
    """The largest relative error, over every input frequency, of the response of modes
    ẋ = p x + u integrated with one step's amplification factor R (z = p dt, Re z < 0) instead of
    advanced exactly (eᶻ): the response to an input at frequency ω is Σₙ aⁿ e^{−iωn dt} =
    1/(1 − a e^{−iω dt}), whose relative change from a = eᶻ to R(z) is at most
    |R(z) − eᶻ| / (1 − |eᶻ|) (at resonance, ω dt = Im z), to first order. Returns the maximum over
    ``z``; inf where a mode does not decay (Re z ≥ 0)."""
    z = np.asarray(z, complex).ravel()
    if not z.size:
        return 0.0
    decay = -np.expm1(z.real)                         # 1 − |eᶻ| > 0 for a decaying mode
    if not (decay > 0).all():
        return math.inf
    return float(np.max(np.abs(amplification(z) - np.exp(z)) / decay))


def state_space_update(model: Model, *, dt, integrator="rk4", state_space_options=None):
    """How the fitted radiation states of ``radiation="auto"`` advance, and why:
    ``("state_space", why)`` (integrated by the integrator, as its other states) or
    ``("state_space_exact", why)`` (advanced exactly over each step, for a velocity linear within
    it: stable at every dt, but each stage offset of the step needs its own product with the
    states).

    Integrated where the integrator declares its amplification factor R(z) (RK4's) and the
    largest relative error it makes in a fitted mode's response (:func:`integrated_state_error`,
    z = p dt for every pole p of the fit) is at most :data:`STATE_SPACE_TOLERANCE` (M4 134 at
    T_p/200: poles to |p| dt = 0.09, an error of 1.8e-5): the run then keeps the integrator's
    order, where the exact update's velocity, linear within each step, makes the radiation
    second order (notebooks/speed_accuracy.ipynb). Integrating costs one product with the states
    per evaluation (RK4: four a step) against the exact update's one per stage offset after the
    step's start (RK4: two): M4 134 over 100 T_p, the loop 0.70 against 0.47 s
    (benchmarks/RESULTS.md). Else exact."""
    from ..loads.radiation import StateSpace

    integ = _integrators.get(integrator)
    amplification = getattr(integ, "amplification", None)
    if amplification is None:
        return "state_space_exact", (f"its states advanced exactly ({integ.name} declares no "
                                     "amplification factor to integrate them with)")
    ss = StateSpace.build(model.hydro, state_space_options)
    pr = np.asarray(ss.p)            # on the host: eager slices compile a program each
    p = pr[:, 0] + 1j * pr[:, 1]
    err = integrated_state_error(amplification, p * float(dt))
    biggest = float(np.max(np.abs(p))) * float(dt) if p.size else 0.0
    what = (f"{p.size} fitted poles, largest |p| dt {biggest:.3g}: {integ.name} integrates them "
            f"with a relative error of the modes' response up to {err:.2g}")
    if err <= STATE_SPACE_TOLERANCE:
        return "state_space", f"{what} ≤ {STATE_SPACE_TOLERANCE:g}: its states integrated"
    return "state_space_exact", f"{what} > {STATE_SPACE_TOLERANCE:g}: its states advanced exactly"
