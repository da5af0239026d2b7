"""Mean and slow wave drift forces from a database's ``mean_drift`` (hydro.database), and the
far-field mean drift of given motions from a layout's Kochin functions (:func:`far_field_drift`).

The database gives D_i(ω, β), the mean force on dof i per unit wave amplitude squared (N/m²,
N m/m²) at the body's reference point, inertial axes. For the wave components (a_j, ω_j, φ_j,
β_j) of a sea (:class:`hydro.waves.WaveComponents`), with D_j = D(ω_j, β_j) interpolated linearly
in ω and then in β (a real table: no phase to wind):

``mode="mean"``: the constant mean drift  F = r(t) Σ_j D_j a_j²  (a regular wave: D a² exactly).

``mode="newman"``: Newman's (1974) approximation of the slowly varying drift force:

    F(t) = r(t) Re[ S₊(t) conj(S(t)) ],   S(t) = Σ_j s_j √|D_j| c_j e^{−iω_j t},
    S₊(t) = Σ_j sgn(D_j) s_j √|D_j| c_j e^{−iω_j t}

with c_j = a_j e^{iφ_j} and s_j = e^{i k_j (x_r cos β_j + y_r sin β_j)} the wave's phase at
the body's reference point (x_r, y_r). It keeps the difference-frequency terms ω_j − ω_l only
(Re[e^{−i(ω_j − ω_l)t}]), with the full quadratic transfer function T_jl replaced by
sgn(D_j) √(|D_j| |D_l|) (Newman: T_jl ≈ ½(T_jj + T_ll) ≈ √(T_jj T_ll) near the diagonal). Its
time average is Σ_j D_j a_j², the mean drift of the spectrum (cross terms average out over the
record: to the sampling error of a finite record).

Limits (say them where the force is used): valid for the slow drift of soft-moored bodies whose
natural periods (surge, sway, yaw on the moorings) are long against the wave periods, so that
only the QTF near its diagonal (small ω_j − ω_l) matters; no sum-frequency terms (springing,
ringing of stiff systems); D is that of the body at rest at its mean heading (its offset and yaw
do not change the coefficients: no wave-drift damping) and of the motions the database's drift
was computed with (``mean_drift.attrs["motions"]``: fixed, or freely floating with a given
inertia), not the model's own motions; with directional spreading, pairs of components of
different headings take the same sgn(D_j) √(|D_j| |D_l|) (the bidirectional QTF is not known);
no current.

r(t) is the start-up ramp of :func:`hydro.waves.ramp`, applied to the force as the excitation's
is applied to the excitation (so a ramped regular wave's drift rises over the ramp to D a²).
"""
from __future__ import annotations


import numpy as np
import xarray as xr

from .excitation import GRID_RTOL, _bracket, _heading_table, _map_headings
from .waves import WaveComponents, _harmonic_sum, ramp

MODES = ("mean", "newman")


class DriftTable:
    """D(ω, β) (n_ω, n_β, n_dof) of a database sorted for interpolation, the heading grid closed
    around the circle where the database covers it (as :class:`hydro.excitation.ExcitationTable`)."""

    @classmethod
    def of_arrays(cls, omega, wave_direction, D, labels, attrs=None) -> "DriftTable":
        """The table of D (n_ω, n_β, n_dof) on ``omega`` (rad/s) and ``wave_direction`` (rad)
        for the dofs ``labels``, without a dataset (the drift of a model's own motions,
        mfm.frequency.drift)."""
        da = xr.DataArray(np.asarray(D, float), dims=("omega", "wave_direction", "influenced_dof"),
                          coords={"omega": np.asarray(omega, float),
                                  "wave_direction": np.asarray(wave_direction, float),
                                  "influenced_dof": [str(d) for d in labels]},
                          attrs=dict(attrs or {}))
        return cls(xr.Dataset({"mean_drift": da}))

    def __init__(self, db: xr.Dataset, dofs=None):
        if "mean_drift" not in db:
            raise KeyError(
                "the hydro database has no 'mean_drift' (the mean drift force per unit wave "
                "amplitude squared); make it with `mfm hydro` and [hydro.bem] drift = \"free\" or "
                "\"fixed\" (one wet body), or read WAMIT output with its .8/.9 beside the .out; "
                "a database with the layout's Kochin functions ([hydro.bem] drift = \"kochin\") "
                "gives the drift of the model's own motions to mfm.simulate, simulate_batch and "
                "mfm.equilibrium; or leave [hydro] drift unset")
        da = db["mean_drift"].transpose("omega", "wave_direction", "influenced_dof")
        da = da.sortby("omega").sortby("wave_direction")
        if dofs is not None:
            da = da.sel(influenced_dof=list(dofs))
        self.labels = [str(d) for d in da["influenced_dof"].values]
        self.omega = np.asarray(da["omega"].values, float)
        beta = np.asarray(da["wave_direction"].values, float)
        self.beta, self.D, self.periodic = _heading_table(beta, np.asarray(da.values, float), None)
        self.attrs = dict(da.attrs)

    def at(self, comps: WaveComponents) -> np.ndarray:
        """D_j (n_comp, n_dof) at the components; 0 for a component outside the ω grid (those the
        excitation has already dropped as carrying a negligible part of the energy, or refused:
        :func:`hydro.excitation.excitation_time_series` runs first)."""
        w = np.asarray(comps.omega, float)
        lo, hi = self.omega[0], self.omega[-1]
        inside = (w >= lo * (1 - GRID_RTOL)) & (w <= hi * (1 + GRID_RTOL))
        b = _map_headings(self.beta, self.periodic, np.asarray(comps.heading, float), inside)
        i0, i1, sw = _bracket(self.omega, np.clip(w, lo, hi))
        k0, k1, sb = _bracket(self.beta, b)
        sw, sb = sw[:, None], sb[:, None]
        at_k = lambda k: (1 - sw) * self.D[i0, k] + sw * self.D[i1, k]   # noqa: E731
        D = (1 - sb) * at_k(k0) + sb * at_k(k1)
        return np.where(inside[:, None], D, 0.0)


def drift_time_series(db: xr.Dataset, comps: WaveComponents, t, *, mode: str,
                      reference_points=None, ramp_duration: float = 0.0, dofs=None) -> np.ndarray:
    """The drift force (len(t), n_dof) of the module docstring on the database's dofs (``db``: a
    database, or a :class:`DriftTable` made already).

    reference_points: (n_body, 3) the bodies' reference points (the wave's phase there, Newman's
    envelope; default the database's ``reference_point``), one per 6 dofs in order.
    """
    if mode not in MODES:
        raise ValueError(f"drift mode {mode!r}; accepted: {list(MODES)} (mean: the constant mean "
                         "drift; newman: Newman's slow drift)")
    t = np.asarray(t, float)
    table = db if isinstance(db, DriftTable) else DriftTable(db, dofs)
    n_dof = len(table.labels)
    if comps is None or len(comps.omega) == 0:
        return np.zeros((t.shape[0], n_dof))
    D = table.at(comps)                                                    # (J, n_dof)
    a = np.asarray(comps.amplitude, float)
    if mode == "mean":
        out = np.broadcast_to((D * (a * a)[:, None]).sum(0), (t.shape[0], n_dof)).copy()
    else:
        if reference_points is None:
            if isinstance(db, DriftTable):
                raise ValueError("drift_time_series: newman on a DriftTable needs "
                                 "reference_points (the table has no bodies' positions)")
            reference_points = np.asarray(db["reference_point"].values, float)
        ref = np.repeat(np.asarray(reference_points, float)[:, :2], 6, axis=0)[:n_dof]  # per dof
        k, beta = np.asarray(comps.wavenumber, float), np.asarray(comps.heading, float)
        s = np.exp(1j * (np.multiply.outer(k * np.cos(beta), ref[:, 0])
                         + np.multiply.outer(k * np.sin(beta), ref[:, 1])))        # (J, n_dof)
        c = comps.complex_amplitude[:, None] * s * np.sqrt(np.abs(D))
        w = np.asarray(comps.omega, float)
        # S = Re + i Im, with Im Σ c e^{−iωt} = Re Σ (−i c) e^{−iωt}
        S_re, S_im = _harmonic_sum(w, c, t), _harmonic_sum(w, -1j * c, t)
        cp = np.sign(D) * c
        P_re, P_im = _harmonic_sum(w, cp, t), _harmonic_sum(w, -1j * cp, t)
        out = P_re * S_re + P_im * S_im                                    # Re[S₊ conj(S)]
    return out * ramp(t, ramp_duration)[:, None] if ramp_duration else out


def mean_drift_of(db: xr.Dataset, comps: WaveComponents, dofs=None) -> np.ndarray:
    """Σ_j D(ω_j, β_j) a_j² (n_dof,): the mean drift force of the components (N, N m). ``db``:
    a database, or a :class:`DriftTable` made already."""
    D = (db if isinstance(db, DriftTable) else DriftTable(db, dofs)).at(comps)
    return (D * np.asarray(comps.amplitude, float)[:, None] ** 2).sum(0)


# ----------------------------------------------------------------- the far field of given motions
def _fourier(H):
    """The periodic trapezoid grid's Fourier coefficients c_n (…, N) of H (…, N) on θ_i = 2π i/N,
    H(θ) = Σ_n c_n e^{inθ}, and their integer wavenumbers n (N,) (the Nyquist one's derivative
    dropped: it is not resolved)."""
    N = H.shape[-1]
    c = np.fft.fft(H, axis=-1) / N
    n = np.fft.fftfreq(N, 1.0 / N)
    return c, n


def far_field_drift(kochin_diffraction, kochin_radiation, motions, omega, wavenumber, heading, *,
                    water_depth: float, rho: float, g: float) -> np.ndarray:
    """The far-field mean drift force per unit wave amplitude squared of bodies in regular waves,
    given their first-order motions: (n, 3) [F_x (N/m²), F_y (N/m²), M_z (N m/m², about the
    Kochin functions' origin)] for n (ω, β) pairs.

    kochin_diffraction (n, N), kochin_radiation (n, n_dof, N): the Kochin functions (capytaine
    3.0's normalisation, ``hydro.bem.solve(drift="kochin")``) on θ_i = 2π i/N; motions (n, n_dof)
    the complex motion amplitudes ξ per unit wave amplitude (e^{−iωt}); omega, wavenumber, heading
    (n,). With the total far field H(θ) = i [H_D(θ) + Σ_j ξ_j H_j(θ)] (Maruo 1960 for the force,
    Newman 1967 for the yaw moment; the form of Delhommeau's thesis eq. 2.170 that capytaine's
    ``far_field_mean_drift_force`` takes):

        F_x = −2πρω cos β Im H(β) − c₂ ∫₀^{2π} |H(θ)|² cos θ dθ,
        F_y = −2πρω sin β Im H(β) − c₂ ∫₀^{2π} |H(θ)|² sin θ dθ,
        M_z = (2πρω/k) Re H′(β) − (c₂/k) ∫₀^{2π} Im[H̄(θ) H′(θ)] dθ,

    c₂ = 2πρk² in deep water, 2πρ k (k₀h)² / (h [(kh)² − (k₀h)² + k₀h]) at depth h (k₀ = ω²/g).
    The integrals are the periodic trapezoid sums (exact for the grid's harmonics), H(β) and H′
    the grid's Fourier series (trigonometric interpolation, spectral derivative): no finite
    difference in θ. The first terms are the interference of the scattered wave with the incident
    one (the drift's sign), the integrals the energy radiated away."""
    Hd = np.asarray(kochin_diffraction, complex)
    Hr = np.asarray(kochin_radiation, complex)
    xi = np.asarray(motions, complex)
    w = np.asarray(omega, float)
    k = np.asarray(wavenumber, float)
    beta = np.asarray(heading, float)
    H = 1j * (Hd + np.einsum("nj,njt->nt", xi, Hr))                       # (n, N)
    N = H.shape[-1]
    theta = 2 * np.pi * np.arange(N) / N
    c, m = _fourier(H)
    dm = np.where(np.abs(m) == N / 2, 0.0, m)                             # Nyquist: not resolved
    dH = np.fft.ifft(c * (1j * dm) * N, axis=-1)                           # H′ on the grid
    phase = np.exp(1j * np.multiply.outer(beta, m))                       # (n, N): e^{inβ}
    H_b = np.sum(c * phase, axis=-1)
    dH_b = np.sum(c * (1j * dm) * phase, axis=-1)
    dth = 2 * np.pi / N
    c1 = 2 * np.pi * rho * w
    if np.isinf(water_depth):
        c2 = 2 * np.pi * rho * k**2
    else:
        h = float(water_depth)
        k0h = w**2 / g * h
        c2 = 2 * np.pi * rho * k * k0h**2 / (h * ((k * h) ** 2 - k0h**2 + k0h))
    H2 = np.abs(H) ** 2
    fx = -c1 * np.cos(beta) * H_b.imag - c2 * dth * (H2 @ np.cos(theta))
    fy = -c1 * np.sin(beta) * H_b.imag - c2 * dth * (H2 @ np.sin(theta))
    mz = c1 / k * dH_b.real - c2 / k * dth * np.sum(np.imag(np.conj(H) * dH), axis=-1)
    return np.stack([fx, fy, mz], axis=-1)
