"""The front door of the time domain: :func:`simulate` checks its inputs, makes the runner's
choices (:mod:`.choices`), builds the run's loads, compiles and runs the pure rollout
(:mod:`mfm.timedomain.rollout`, through :mod:`.pipeline`), stops with a clear error if the state
went non-finite (:mod:`.checks`), and returns an :class:`xarray.Dataset` (:mod:`mfm.results`).
Many runs at once are :func:`~.batch.simulate_batch`.
"""
from __future__ import annotations


import numpy as np
import xarray as xr
from hydro import phases

from .. import results
from ..errors import SimulationError
from ..frequency import rest
from ..frequency.drift import run_mean_drift
from ..loads.assembly import as_loads
from ..mechanics.model import Model
from ..radiation import resolve as resolve_radiation
from ..timedomain import integrators as _integrators
from ..timedomain.record import OUTPUTS
from ..timedomain.setup import model_loads, stage_offsets
from ..validation import check_model, finite_number, initial_vector, whole_number
from .checks import (check_sea_read, nonfinite_message, refuse_convolution, refuse_impossible, warn_accuracy, warn_stability,
                     warn_verlet_drift)
from .choices import convolution_or_state_space, judge_radiation, judged_choice, state_space_update
from .pipeline import prepare_run
from .progress import phase, progress_bar, progress_options
from .threads import background, keeping_interrupts, result


def simulate(model: Model, sea=None, *, duration: float, dt: float, integrator="rk4",
             q0=None, qd0=None, loads=None, save_every: int = 1, t0: float = 0.0,
             ramp: float = 0.0, radiation: str = "auto", memory: float | None = None,
             state_space_options: dict | None = None, check_stability: bool = True,
             added_mass: str = "lhs", progress: bool | dict = False,
             compile: str = "default") -> xr.Dataset:
    """Simulate a model in the time domain.

    Parameters
    ----------
    model: a compiled :class:`~mfm.mechanics.model.Model` (with its water if the config has ``[hydro]``).
    sea: a sea state from :mod:`hydro.waves` (``Regular``, ``Jonswap``, …), or None (still water,
        or no water at all for a mechanics-only model).
    duration, dt: s. The run has ``round(duration / dt)`` steps.
    integrator: ``"rk4"`` (default), ``"beeman"`` (Lande-Sudall et al. eq. 52), ``"semi_implicit"``,
        ``"newmark"``, ``"verlet"`` (one evaluation per step, second order: the fast one, with
        ``radiation="state_space_exact"``), or an instance from :mod:`mfm.integrators`.
    q0, qd0: initial coordinates and rates, arrays (n_q,) or dicts by coordinate name (others 0).
    loads: an :class:`mfm.loads.Load` or a sequence of them (external loads), added to the
        model's own (its water and its config's loads).
    save_every: keep every k-th step in the output.
    ramp: s, the start-up ramp of the excitation (½(1 − cos πt/ramp)).
    radiation: ``"auto"`` (default: the cheaper of the convolution and the state space for this
        run, the state space's states integrated by the integrator where it does that as well as
        exactly (RK4 at the usual steps), else advanced exactly, and the fit judged on the
        model's own modes and its response to the sea against the database
        (:mod:`mfm.frequency.fitcheck`): past its tolerances the convolution. :func:`choose_radiation`;
        the choice and why are in the attribute ``radiation_choice``, the judgement's errors in
        ``fit_mode_error`` and ``fit_sea_error``),
        ``"convolution"`` (direct, window T_K from the decay of K; ``memory`` overrides it,
        s), ``"state_space"`` (the passive fit of :mod:`hydro.statespace`, options in
        ``state_space_options``, its states integrated by the integrator),
        ``"state_space_exact"`` (the same fit, its states advanced exactly over each step: stable
        at any dt, what ``integrator="verlet"`` needs) or ``"none"`` (A∞ only).
    added_mass: ``"lhs"`` (A∞ in M*, the default) or ``"rhs"``: the scheme of Lande-Sudall et al. §5, A∞ ξ̈
        on the right-hand side with the acceleration iterated in Beeman's corrector (needs
        ``integrator="beeman"``; converges only where A∞ is smaller than the structural mass; the
        iteration counts are in ``iterations``).
    check_stability: warn (:class:`StabilityWarning`) before running when dt exceeds the
        integrator's stability limit at the shortest natural period of the model linearised at q0,
        and (:class:`AccuracyWarning`) when Verlet integrates coordinates without restoring.
    progress: False (default), True for a progress bar (tqdm, on stderr), or a dict of tqdm
        options (e.g. ``{"delay": 5}``: shown only once the run has taken 5 s). The run is then
        made in 20 to 100 chunks of one compiled function, with the bar updated between them;
        the results are the same to the last bit.
    compile: ``"default"`` (XLA's optimised programs) or ``"fast"``: every program of the run
        compiled at XLA's lowest optimisation level, as the checks' linearisation is
        (:func:`mfm.runner.xla.once_options`), for a first look at a short run: its compilation
        about a third of the CPU (RM3's README run, caches empty: 11–16 → 5.4 CPU s on 2 cores;
        benchmarks/RESULTS.md, issue 55), its steps up to ~3× slower once compiled, and its
        numbers not the default's to the last bit (XLA's default fuses a·b + c into one rounded
        operation, the lowest level does not: ~1e-16 relative per operation, grown by the
        dynamics over a run). Recorded in the result's attribute ``compile``. Where ``XLA_FLAGS``
        sets XLA's level, or with ``MFM_FAST_COMPILE=off``, the programs are compiled as
        those settings say.

    Returns an :class:`xarray.Dataset` with ``q``, ``qd``, ``qdd`` (time, coordinate),
    ``body_position`` (time, body, axis) CoM in inertial axes, ``body_rotation`` (time, body, angle)
    roll/pitch/yaw (R = R_z(yaw) R_y(pitch) R_x(roll)), ``joint_force`` and ``joint_moment``
    (time, body, axis): the load each body's joint transmits from the parent (inertial axes, moment
    about the joint point), ``kinetic_energy`` and ``potential_energy`` (time), ``iterations``
    (corrector iterations of the step), ``pto_power`` and ``pto_displacement`` (time, pto) for each
    joint damper and hydraulic PTO; with water also ``eta`` (time), ``xi`` (time, hydro_dof) and
    ``hydro_force`` (time, component, hydro_dof); each load's own outputs (e.g. ``point_position``
    of named body points). Units and provenance (config, database, sea state, settings, versions)
    are in the attributes (:mod:`mfm.results`).

    Raises :class:`SimulationError` when the state goes non-finite; its ``dataset`` holds the run
    up to the last finite sample.
    """
    with keeping_interrupts():
        model = check_model(model)
        check_sea_read(model, as_loads(loads), [sea])
        # a strategy object or its string alias, with the string API's side options
        radiation, memory, state_space_options = resolve_radiation(radiation, memory,
                                                                   state_space_options)
        dt = finite_number(dt, "dt", positive=True)
        duration = finite_number(duration, "duration", positive=True)
        t0 = finite_number(t0, "t0")
        ramp = finite_number(ramp, "ramp", nonnegative=True)
        memory = finite_number(memory, "memory", positive=True, allow_none=True)
        progress = progress_options(progress)
        if compile not in ("default", "fast"):
            raise ValueError(f"compile={compile!r}; accepted: 'default' (XLA's optimised programs) or "
                             "'fast' (its lowest optimisation level: a cheaper first compilation, "
                             "slower steps, other last bits)")
        fast = compile == "fast"
        n_steps = int(round(duration / dt))
        if n_steps < 1:
            raise ValueError(f"duration = {duration} s is shorter than one step dt = {dt} s")
        if not whole_number(save_every) or n_steps % save_every:
            raise ValueError(f"save_every: {save_every!r} must be a positive divisor of the {n_steps} "
                             "steps")
        extra = as_loads(loads)
        refuse_impossible(model, extra + tuple(model.loads), n_steps, save_every)
        integ = _integrators.get(integrator)
        if added_mass not in ("lhs", "rhs"):
            raise ValueError(f"added_mass={added_mass!r}; accepted: 'lhs' (A∞ in M*), 'rhs' (Lande-Sudall et al.)")
        if added_mass == "rhs" and integ.name != "beeman":
            raise ValueError(f"added_mass='rhs' (the scheme of Lande-Sudall et al.) iterates the acceleration in "
                             f"Beeman's corrector; integrator={integ.name!r} has none: use "
                             "integrator='beeman' or added_mass='lhs'")
        choice = "given"
        auto = radiation == "auto"
        if auto:
            # the convolution or the state space now; how the state space's states advance once its
            # fit is made (below, beside the jet's compilation): choose_radiation in two halves
            radiation, choice = convolution_or_state_space(model, dt=dt, n_steps=n_steps,
                                                           integrator=integ, memory=memory)
            if model.hydro is None:
                radiation = "convolution"          # no water: nothing to choose
        if radiation == "convolution":
            refuse_convolution(model, dt=dt, memory=memory, n_offsets=len(stage_offsets(integ)),
                               why=choice if auto else "")
        q0 = initial_vector(model, q0, "q0")
        qd0 = initial_vector(model, qd0, "qd0")
        free = []
        judged = {}
        # The checks' linearisation at q0 (the model's jet at rest, ~6 s to compile for M4 134)
        # compiles on a second thread while this one builds the run's water (its radiation fit, in
        # numpy) and compiles the run. An error here returns at once: that compilation finishes on
        # its own.
        # the bar from the start, so that a long preparation shows its phase: the radiation fit
        # (seconds to a minute for 90 dofs) used to run under a bar that said "compiling"
        bar = progress_bar(progress, n_steps, model.name)
        fit = model.hydro is not None and radiation.startswith("state_space")
        phase(bar, "preparing the loads" + (" (the radiation's state-space fit: up to a minute)"
                                            if fit else ""))
        try:
            if check_stability:
                # still water's loads at rest have the structure of the run's, so the jet compiles
                # while this thread builds the run's water (its radiation fit) and is then evaluated
                # with the run's own loads; on a daemon thread, which a Ctrl-C does not wait for
                # (mfm.runner.threads)
                ahead = background(rest.compile_jet, model, rest.still_water_loads(
                    model, extra, added_mass=added_mass, stage_offsets=stage_offsets(integ)), q0)
            # the fit says how far it is (its orders, its passivity iterations) on the bar
            with phases.reporting(None if bar is None else
                                  (lambda what: phase(bar, f"preparing the loads: {what}"))):
                if auto and radiation == "state_space_exact":
                    radiation, how = state_space_update(model, dt=dt, integrator=integ,
                                                        state_space_options=state_space_options)
                    choice = f"{choice}; {how}"
                # [hydro] drift on a database with the layout's Kochin functions: the drift of the
                # model's own motions (mfm.frequency.drift), made once for the run
                drift_table = run_mean_drift(model) if sea is not None else None
                loads = model_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                                    radiation=radiation, memory=memory,
                                    state_space_options=state_space_options, added_mass=added_mass,
                                    integrator=integ, extra=extra, mean_drift=drift_table)
            # the recorded run (its programs: the whole run, or its start and chunks), compiled here:
            # beside the jet's compilation where the water builds faster than that (no fit), and
            # before the checks' warnings
            phase(bar, "compiling")
            run = prepare_run(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integ, loads=loads,
                              save_every=save_every, t0=t0, recording=OUTPUTS,
                              chunked=bar is not None, fast=fast)
            if check_stability:
                phase(bar, "linearising at q0 for the checks")
                result(ahead)
                # one linearisation at q0 gives the shortest period and the coordinates that nothing
                # pulls back (those of no_restoring(model, q0, loads=<the extra loads>), `mfm info`'s)
                J, K = rest.linearised_at_rest(model, q0, loads)
                free = rest.free_coordinates(model, K)
            if auto and radiation.startswith("state_space"):
                # the fit judged on the model's own modes and its response to the sea
                # (mfm.frequency.fitcheck), from the checks' compiled linearisation; past its
                # tolerances the run is remade with the convolution, which has no fit to be wrong
                phase(bar, "judging the radiation fit on the model's modes")
                verdict = judge_radiation(model, loads=extra, sea=sea, duration=duration,
                                          state_space_options=state_space_options,
                                          added_mass=added_mass, stage_offsets=stage_offsets(integ),
                                          q0=q0)
                judged = verdict.attrs()
                radiation, choice = judged_choice(radiation, choice, verdict)
                if not verdict.ok:
                    refuse_convolution(model, dt=dt, memory=memory,
                                       n_offsets=len(stage_offsets(integ)),
                                       why=f"'auto': {verdict.summary}, and the convolution that "
                                           "replaces a fit judged off is too large")
                    phase(bar, "preparing the loads (the convolution)")
                    loads = model_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                                        radiation=radiation, memory=memory, added_mass=added_mass,
                                        integrator=integ, extra=extra, mean_drift=drift_table)
                    phase(bar, "compiling")
                    run = prepare_run(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integ,
                                      loads=loads, save_every=save_every, t0=t0, recording=OUTPUTS,
                                      chunked=bar is not None, fast=fast)
        except BaseException:
            if bar is not None:
                bar.close()
            raise
        if check_stability:
            warn_stability(integ, dt, rest.period_from_jacobian(J))
        if sea is not None:
            warn_accuracy(model, sea, dt, integ)
        warn_verlet_drift(integ, free)
        out = run(bar)
        t, q, qd, qdd, z, iters = (np.asarray(a) for a in out[:6])
        rec = {k: np.asarray(v) for k, v in out[6].items()}
        settings = dict(duration=duration, n_steps=n_steps, save_every=int(save_every), t0=t0,
                        complete="true", ramp_s=ramp, memory_s=memory,
                        sea="still water" if sea is None else repr(sea),
                        sea_label="still water" if sea is None else str(sea), radiation_choice=choice,
                        compile=compile,
                        no_restoring=", ".join(free) if check_stability else "not checked",
                        **judged)
        finite = np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1)
        if not finite.all():
            k = int(np.argmax(~finite))
            message = nonfinite_message(model, integ, t, q, qd, dt, loads, k)
            partial = None
            if k > 0:
                keep = slice(0, k)
                settings.update(complete="false", stopped=message)
                partial = results.time_series(model, loads, integ, dt, t[keep], q[keep], qd[keep],
                                              rec["qdd"][keep], iters[keep],
                                              {n: v[keep] for n, v in rec.items()}, settings)
            raise SimulationError(message + (f" The run up to t = {t[k - 1]:.6g} s is in this error's "
                                             "`dataset`." if partial is not None else ""), partial)
        return results.time_series(model, loads, integ, dt, t, q, qd, rec["qdd"], iters, rec, settings)
