"""The mean wave drift of a model's own motions, from the Kochin functions of its database.

A database made with ``[hydro.bem] drift = "kochin"`` (``hydro.bem.solve``) holds the far-field
amplitudes of the diffraction, H_D(θ; ω, β), and of each hydro dof's radiation, H_j(θ; ω), of the
whole layout. The far field of the bodies moving with the model's RAOs ξ̂(ω, β) = H₀ x̂(ω, β)
(x̂ the coordinates' RAOs about q₀, :func:`mfm.frequency_response`; H₀ the hydro Jacobian: every
joint, PTO, mooring and coupling of the model in them) is H_D + Σ_j ξ̂_j H_j, and Maruo's and
Newman's far-field momentum balance gives the mean horizontal force and yaw moment on the whole
layout per unit wave amplitude squared (:func:`hydro.drift.far_field_drift`).

The far field sees the layout as one: the total (F_x, F_y, M_z), not each body's share. It is
put on the hydro body nearest the tree's root (the platform of a hybrid, the first float of an
M4 chain) at its reference point, M_z moved there from the Kochin functions' origin:

    D_root = (F_x, F_y, 0, 0, 0, M_z − (x_r F_y − y_r F_x)),   every other body's row 0.

So the generalised forces along the coordinates that move the whole layout rigidly (the root's
surge, sway and yaw: a moored platform's offset) are the far field's, exact; those along the
joints between bodies (each body's own share of the drift: a float's mean hinge moment) are not
known from the far field and are 0 here (that needs the near-field pressure integration capytaine
3.0 lacks); heave, roll and pitch drift likewise 0. The RAOs are those at q₀ (the still-water
equilibrium by default), with the database's radiation; the drift then moves the mean position,
whose RAOs are taken to be the same (no wave-drift damping, no iteration).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..mechanics.model import Model
from ..mechanics.points import h_matrix_at
from ..validation import check_model
from .response import _amplitudes
from .rest import linear_hydro, linear_system

KOCHIN_VARIABLES = ("kochin_diffraction", "kochin_radiation")


class MeanDrift(NamedTuple):
    """The drift of a model's own motions (:func:`model_mean_drift`): ``D`` (n_ω, n_β, 6K) per
    unit wave amplitude squared (N/m², N m/m²) on ``omega`` (rad/s) and ``wave_direction`` (rad),
    for the hydro ``dofs`` (6K labels), and ``attrs`` (units, method, motions, the dofs it is on);
    as a database's ``mean_drift`` (:meth:`table`; a dataset: :func:`mfm.mean_drift`)."""
    omega: np.ndarray
    wave_direction: np.ndarray
    D: np.ndarray
    dofs: tuple
    attrs: dict

    def table(self):
        """The :class:`hydro.drift.DriftTable` of D: the interpolation every drift reads."""
        from hydro.drift import DriftTable

        return DriftTable.of_arrays(self.omega, self.wave_direction, self.D, self.dofs,
                                    self.attrs)


def has_kochin(model: Model) -> bool:
    """Whether the model's database carries the Kochin functions (``drift = "kochin"``)."""
    return model.hydro is not None and all(v in model.hydro.database() for v in KOCHIN_VARIABLES)


def root_hydro_body(model: Model, body_index) -> int:
    """The hydro body (an index into ``body_index``, the model index of each hydro body) nearest
    the tree's root: the fewest joints from the inertial frame, the first of equals."""
    def depth(i):
        d = 0
        while model.parents[i] >= 0:
            i, d = model.parents[i], d + 1
        return d

    return min(range(len(body_index)), key=lambda k: (depth(int(body_index[k])), k))


def model_mean_drift(model: Model, *, q0=None, loads=None) -> MeanDrift:
    """D(ω, β) of the module docstring as a :class:`MeanDrift` (omega, wave_direction, hydro
    dofs): the far-field mean drift force of the model's own motions per unit wave amplitude
    squared (N/m², N m/m²), on the database's finite frequencies and headings, at the hydro
    bodies' reference points (inertial axes), as a database's ``mean_drift`` is (the same table
    and interpolation serve it: :meth:`MeanDrift.table`, :meth:`mfm.loads.water.Water.in_mean_drift`;
    as a labelled DataArray: :func:`mfm.mean_drift`).

    model: a Model whose database has the Kochin functions (``[hydro.bem] drift = "kochin"``);
    q0, loads: the linearisation point (default the still-water equilibrium) and extra loads, as
    :func:`mfm.frequency_response`. Raises ValueError naming the database and how to make the
    functions where they are missing."""
    from hydro.drift import far_field_drift
    from hydro.waves import wavenumber

    model = check_model(model)
    spec = model.hydro
    if spec is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: the mean drift of its "
                         "motions needs a [hydro] table")
    db = spec.database()
    missing = [v for v in KOCHIN_VARIABLES if v not in db]
    if missing:
        raise ValueError(f"the hydro database {spec.source!r} has no {missing[0]!r}: the drift of "
                         "the model's own motions needs the layout's Kochin functions; make the "
                         "database with `mfm hydro` and [hydro.bem] drift = \"kochin\"")
    sys = linear_system(model, q0, loads=loads)
    water = linear_hydro(sys.loads)
    H0 = np.asarray(h_matrix_at(water.geometry, sys.kin0))                # (6K, n_q)
    labels = list(spec.dofs)
    om = np.asarray(db["omega"].values, dtype=float)
    fin = np.flatnonzero(np.isfinite(om) & (om > 0))
    om = om[fin]
    betas = np.asarray(db["wave_direction"].values, dtype=float)
    Hd = db["kochin_diffraction"].transpose("omega", "wave_direction", "theta").values[fin]
    Hr = db["kochin_radiation"].sel(radiating_dof=labels).transpose(
        "omega", "radiating_dof", "theta").values[fin]
    # the depth each frequency was solved at (hydro.bem's deep_water_kh split: deep above)
    deep_from = db.attrs.get("deep_water_omega_min", "none")
    deep_from = math.inf if deep_from in ("none", None) else float(deep_from)
    depth = np.where(om >= deep_from, math.inf, spec.water_depth)
    k = np.array([float(wavenumber(w, h, spec.g)) for w, h in zip(om, depth)])
    K = len(labels) // 6
    root = root_hydro_body(model, water.geometry.body_index)
    x_r, y_r = np.asarray(spec.ref0, dtype=float)[root, :2]
    D = np.zeros((om.size, betas.size, 6 * K))
    options = {"radiation": "database", "state_space_options": None}
    for ib, beta in enumerate(betas):
        x = _amplitudes(model, sys, om, float(beta), options)             # (n_ω, n_q)
        xi = x @ H0.T                                                     # (n_ω, 6K)
        F = np.empty((om.size, 3))
        for h in np.unique(depth):
            sel = depth == h
            F[sel] = far_field_drift(Hd[sel, ib], Hr[sel], xi[sel], om[sel], k[sel],
                                     np.full(sel.sum(), beta), water_depth=float(h),
                                     rho=spec.rho, g=spec.g)
        D[:, ib, 6 * root] = F[:, 0]
        D[:, ib, 6 * root + 1] = F[:, 1]
        D[:, ib, 6 * root + 5] = F[:, 2] - (x_r * F[:, 1] - y_r * F[:, 0])
    root_name = labels[6 * root].rsplit("__", 1)[0]
    return MeanDrift(om, betas, D, tuple(labels), {
        "units": "N/m^2 (forces), N m/m^2 (moments): mean force per unit wave amplitude squared, "
                 "at the bodies' reference points",
        "method": "far field of the model's own motions (mfm.frequency.drift.model_mean_drift: "
                  "hydro.drift.far_field_drift, Maruo and Newman, on the database's Kochin "
                  f"functions on {db.sizes['theta']} directions)",
        "motions": f"model {model.name!r} linearised at q0 = {np.round(sys.q0, 9).tolist()} (its "
                   "joints, PTOs and moorings)",
        "dofs": ", ".join(f"{root_name}__{m}" for m in ("Surge", "Sway", "Yaw")),
        "applied_on": f"{root_name}: the layout's total (the far field gives no body's share)"})


def run_mean_drift(model: Model):
    """The drift table a run of ``model`` takes for ``[hydro] drift``: the drift of its own
    motions (:func:`model_mean_drift`, about the still-water equilibrium) where its database has
    the Kochin functions, else None (the database's ``mean_drift``)."""
    from ..loads.water import wave_drift

    if model.hydro is None or not wave_drift(model.hydro) or not has_kochin(model):
        return None
    return model_mean_drift(model)
