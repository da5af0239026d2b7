"""The front doors of the frequency domain: the core's numbers (:mod:`mfm.frequency`) as
labelled datasets (:mod:`mfm.results`)."""
from __future__ import annotations

from .. import results
from ..frequency import modes, response


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


# one text per idea: the equations and the dataset's variables are the core's docstrings
frequency_response.__doc__ = response.solve_raos.__doc__
natural_frequencies.__doc__ = modes.natural_modes.__doc__
