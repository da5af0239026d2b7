"""The front doors of the frequency domain: the core's numbers (:mod:`mfm.frequency`) as
labelled datasets (:mod:`mfm.results`)."""
from __future__ import annotations

from .. import results
from ..frequency import drift, modes, response, rest


def frequency_response(model, omega, heading: float = 0.0, *, q0=None,
                       radiation: str = "database", state_space_options: dict | None = None,
                       loads=None, joint_reactions: bool = True):
    r = response.solve_raos(model, omega, heading, q0=q0, radiation=radiation,
                            state_space_options=state_space_options, loads=loads,
                            joint_reactions=joint_reactions)
    return results.frequency(model, r.loads, r.omega, r.x, r.q0, r.kin0, r.heading, r.settings,
                             r.extra, r.reactions)


def natural_frequencies(model, omega_grid=None, *, q0=None, iterations: int = 30, loads=None,
                        radiation: str = "database"):
    n = modes.natural_modes(model, omega_grid, q0=q0, iterations=iterations, loads=loads,
                            radiation=radiation)
    return results.natural(model, n.loads, n.eigen, n.modes, n.damping_ratio,
                           n.radiation_damping_ratio, n.min_det, n.settings,
                           min_det_damped=n.min_det_damped)


def equilibrium(model, q_guess=None, *, loads=None, sea=None, tol: float = 1e-10,
                max_iter: int = 50):
    """Static equilibrium q₀ of the model under its loads (:func:`mfm.frequency.rest.equilibrium`:
    Newton with the jax Jacobian), and with ``sea`` its mean position in that sea under the mean
    wave drift force F̄ = Σ_j D(ω_j, β_j) a_j²: D the drift of the model's own motions where its
    database has the layout's Kochin functions (``[hydro.bem] drift = "kochin"``:
    :func:`mfm.frequency.drift.model_mean_drift`, the RAOs about the still-water equilibrium, the
    far field's total on the hydro body nearest the root), else the database's ``mean_drift``
    (a body held or freely floating, as ``mean_drift.attrs["motions"]`` says).

    Returns (q₀, info): info = dict(residual, iterations, free: coordinates without stiffness)
    and, with ``sea``, ``mean_drift``: which drift was taken (its method and motions). Raises
    ValueError when no equilibrium is found (the residual named by coordinate), or when the sea's
    drift cannot be had (no Kochin functions and no mean_drift: how to make them)."""
    table = drift.model_mean_drift(model, loads=loads) \
        if sea is not None and drift.has_kochin(model) else None
    q0, info = rest.equilibrium(model, q_guess, loads=loads, sea=sea, mean_drift=table, tol=tol,
                                max_iter=max_iter)
    if sea is not None:
        attrs = table.attrs if table is not None else model.hydro.database()["mean_drift"].attrs
        info["mean_drift"] = f"{attrs.get('method', '?')}; motions: {attrs.get('motions', '?')}"
    return q0, info


def mean_drift(model, *, q0=None, loads=None):
    """The mean wave drift of the model's own motions per unit wave amplitude squared, as a
    labelled ``xarray.DataArray`` (omega, wave_direction, influenced_dof) in N/m² and N m/m²,
    the layout's far-field total on the hydro body nearest the root
    (:func:`mfm.frequency.drift.model_mean_drift`: the equations, the approximation, the errors).
    Needs a database with the layout's Kochin functions (``[hydro.bem] drift = "kochin"``)."""
    return results.mean_drift(drift.model_mean_drift(model, q0=q0, loads=loads))


# one text per idea: the equations and the dataset's variables are the core's docstrings
frequency_response.__doc__ = response.solve_raos.__doc__
natural_frequencies.__doc__ = modes.natural_modes.__doc__
