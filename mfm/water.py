"""The model assembly: the one place where the mechanics (`mfm`) and the water (`hydro`) meet.

Hydro coordinates (DESIGN §3). The BEM data of hydro body k are 6 modes about its reference point
r_k (inertial axes). Its small-motion vector ξ_k = (displacement of r_k, rotation vector) has the
velocity ``ξ̇ = H(q) q̇`` with ``H_k = T_k B_i``,

    T_k = [[I, −ρ̂ R], [0, R]],   ρ = R d_k,   d_k = r_k(0) − c_i(0),

which moves the CoM velocity of body i to the reference point and turns its body-axis angular
velocity into inertial axes. A hydro load F (force at r_k and moment about r_k, inertial axes)
does the virtual power Fᵀ ξ̇ = (Hᵀ F)ᵀ q̇; it is applied as the equivalent body wrench (force, and
moment about the CoM in body axes Rᵀ(m + ρ × f)), so Bᵀ of it is exactly Hᵀ F and the joint
reactions see it.

Cummins equation for all hydro bodies together:

    F_hyd = F_exc(t) − A∞ ξ̈ − ∫₀^{T_K} K(τ) ξ̇(t − τ) dτ − C_wp ξ + ρ g V ẑ (at the CoB) − F_drag

- A∞ is acceleration-proportional: ``M* += Hᵀ A∞ H`` and its velocity part ``−Hᵀ A∞ Ḣ q̇`` is a
  load (Ḣ q̇ from the tree walk's velocity-product accelerations).
- Buoyancy is the constant force ρgV ẑ at the centre of buoyancy (a point fixed in the body), plus
  the linear water-plane stiffness C_wp about r_k (the database's ``waterplane_stiffness``: no
  ρgV z_B, no m g z_G, so gravity and buoyancy are not counted twice). Weights act exactly (mfm).
- Radiation memory by direct convolution (trapezoidal, second order, the velocity history kept
  as the load's memory) or by a state-space realisation (its states are integrated with q).
- Quadratic drag −½ ρ C_D A |u| u per axis on the velocity of r_k (no current, no wave velocity).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from .loads import Load, LoadOutput
from .model import Model
from .points import BodyPoints

MODES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")


class Water(Load):
    """The hydrodynamic load of a model (Cummins through Bᵀ F). Build with :func:`build_water`.

    Arrays (float64): ``A_inf`` (6K, 6K); ``C_wp`` (6K, 6K); ``buoyancy`` (K,) = ρ g V, N;
    ``d_cob`` (K, 3) CoB − CoM at q = 0; ``drag`` (K, 3) = ½ ρ C_D A per inertial axis;
    ``ss_p``, ``ss_C`` the radiation state space in modal form: one complex state per pole and
    input dof j (shared by the entries (i, j) fitted with the same poles; conjugate pairs folded),
    ż = p z + ξ̇_j, F_i = −Σ_k Re(C_ik z_k) (no dense A: O(n_x) per evaluation for the states); ``W_current``
    (3, n, n) and ``W_lag`` (3, N, n, n) the convolution weights per stage offset 0, dt/2, dt over
    the n dofs ``conv_dofs`` (:meth:`HydroSpec.kernel`); the excitation
    ``exc_values`` (n, 6K) on the grid ``exc_t0 + j·exc_step`` and the wave elevation at the
    origin ``eta_values`` (n,) on the same grid.
    Static: ``radiation`` ("convolution" | "state_space" | "none"), ``n_lags``, ``conv_dofs``
    (the hydro dofs the mechanics can move, :attr:`HydroSpec.moving`: the convolution runs on
    those only; the velocities of the others are always 0 and their loads do no work).
    """
    geometry: BodyPoints
    A_inf: jnp.ndarray
    C_wp: jnp.ndarray
    buoyancy: jnp.ndarray
    d_cob: jnp.ndarray
    drag: jnp.ndarray
    ss_p: jnp.ndarray       # (n_x, 2) complex poles (modal form) as (re, im)
    ss_C: jnp.ndarray       # (len(ss_out), n_x, 2) output residues (re, im), conjugate pairs folded (×2)
    W_current: jnp.ndarray
    W_lag: jnp.ndarray
    dt: jnp.ndarray
    exc_t0: jnp.ndarray
    exc_step: jnp.ndarray
    exc_values: jnp.ndarray
    eta_values: jnp.ndarray
    radiation: str = eqx.field(static=True)
    n_lags: int = eqx.field(static=True)
    dofs: tuple[str, ...] = eqx.field(static=True)
    added_mass: str = eqx.field(static=True, default="lhs")
    ss_in: tuple[int, ...] = eqx.field(static=True, default=())    # input dof j of each state
    ss_out: tuple[int, ...] = eqx.field(static=True, default=())   # the output dofs: rows of ss_C
    conv_dofs: tuple[int, ...] = eqx.field(static=True, default=())  # dofs of W_current, W_lag

    @property
    def n_states(self) -> int:
        return 2 * len(self.ss_in) if self.radiation == "state_space" else 0

    # -- convolution memory: ξ̇ at the step times t_n, t_{n−1}, … (newest first)
    def init_memory(self, model, t0, q0, qd0, dt):
        if self.radiation != "convolution":
            return ()
        from .kinematics import kinematics
        kin = kinematics(model, q0, qd0)
        v, _ = self.geometry.velocity_and_bias(kin)
        v = v[np.asarray(self.conv_dofs)]
        hist = jnp.zeros((self.n_lags, v.shape[0])).at[0].set(v)
        return (jnp.asarray(t0, jnp.float64), hist)

    def update_memory(self, model, t, q, qd, kin, memory):
        if self.radiation != "convolution":
            return memory
        v, _ = self.geometry.velocity_and_bias(kin)
        hist = jnp.concatenate([v[np.asarray(self.conv_dofs)][None], memory[1][:-1]], axis=0)
        return (t, hist)

    def _series(self, values, t):
        s = (t - self.exc_t0) / self.exc_step
        n = values.shape[0]
        k = jnp.clip(jnp.floor(s), 0, n - 2).astype(int)
        w = jnp.clip(s - k, 0.0, 1.0)
        return (1.0 - w) * values[k] + w * values[k + 1]

    def radiation_force(self, t, v, z, memory):
        """−∫K ξ̇ and the state derivative: the product-integration weights of the convolution
        (:meth:`HydroSpec.kernel`) applied to the velocity history, or the modal state space."""
        if self.radiation == "state_space":
            n = len(self.ss_in)
            zr, zi = z[:n], z[n:]
            pr, pi = self.ss_p[:, 0], self.ss_p[:, 1]
            u = v[np.asarray(self.ss_in)]
            zd = jnp.concatenate([pr * zr - pi * zi + u, pr * zi + pi * zr])
            F = self.ss_C[..., 0] @ zr - self.ss_C[..., 1] @ zi
            return -jnp.zeros_like(v).at[np.asarray(self.ss_out)].set(F), zd
        if self.radiation == "none":
            return jnp.zeros_like(v), None
        t_n, hist = memory
        # which stage of the step this is: offset 0, dt/2 or dt (the integrators' stage times)
        r = jnp.clip(jnp.round(2.0 * (t - t_n) / self.dt), 0, 2).astype(int)
        idx = np.asarray(self.conv_dofs)
        F = self.W_current[r] @ v[idx] + jnp.einsum("jab,jb->a", self.W_lag[r], hist)
        return -jnp.zeros_like(v).at[idx].set(F), None

    def _forces(self, t, kin, z, memory):
        g = self.geometry
        xi = g.xi(kin)
        v, hbias = g.velocity_and_bias(kin)
        exc = self._series(self.exc_values, t)
        rad, zd = self.radiation_force(t, v, z, memory)
        hyd_stat = -(self.C_wp @ xi)
        vv = v.reshape(-1, 6)[:, :3]
        drag = jnp.zeros_like(v).reshape(-1, 6).at[:, :3].set(-self.drag * jnp.abs(vv) * vv).reshape(-1)
        return dict(excitation=exc, radiation=rad, hydrostatic=hyd_stat, drag=drag,
                    added_mass_bias=-(self.A_inf @ hbias)), zd, v, hbias

    def _buoyancy(self, kin):
        """ρgV ẑ at each centre of buoyancy: as loads at r_k (6K,) and the CoB lever (K, 3)."""
        R = kin.E[np.asarray(self.geometry.body_index), :3, :3]
        lever = jnp.einsum("kab,kb->ka", R, self.d_cob)
        f = jnp.zeros_like(lever).at[:, 2].set(self.buoyancy)
        return f, lever

    def _buoyancy_wrench(self, kin, n_bodies):
        f, lever = self._buoyancy(kin)
        F = jnp.concatenate([f, jnp.zeros_like(f)], axis=1).reshape(-1)
        return self.geometry.to_body_wrench(F, kin, n_bodies, point_offset=lever)

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        comps, zd, _, _ = self._forces(t, kin, z, memory)
        F = sum(comps.values())
        H, _, _ = self.geometry.h_matrix(kin)
        rhs = self.added_mass == "rhs" and qdd_guess is not None
        if rhs:
            # seed 001 §5: −A∞ ξ̈ on the right-hand side with the corrector's acceleration iterate.
            # Without an iterate (start of a run, linearisation) the iteration's converged value
            # is used instead: A∞ on the left.
            F = F - self.A_inf @ (H @ qdd_guess)
        body = self.geometry.to_body_wrench(F, kin, model.n_bodies) + self._buoyancy_wrench(kin, model.n_bodies)
        mass = None if rhs else H.T @ self.A_inf @ H
        return LoadOutput(body=body, zd=zd, mass=mass)

    def reaction_loads(self, model, t, q, qd, qdd, z, kin, memory, out):
        # out.body holds −A∞ Ḣq̇; add −A∞ H q̈ so that the bodies feel the whole −A∞ ξ̈ (with
        # added_mass="rhs" out.body already holds −A∞ H q̈ of the recorded iterate)
        if self.added_mass == "rhs" and out.mass is None:
            return out.body
        H, _, _ = self.geometry.h_matrix(kin)
        return out.body + self.geometry.to_body_wrench(-(self.A_inf @ (H @ qdd)), kin, model.n_bodies)

    def diagnostics(self, model, t, q, qd, qdd, z, kin, memory, out):
        comps, _, v, hbias = self._forces(t, kin, z, memory)
        H, _, _ = self.geometry.h_matrix(kin)
        comps["added_mass"] = -(self.A_inf @ (H @ qdd + hbias))
        comps.pop("added_mass_bias")
        f, lever = self._buoyancy(kin)
        rho = self.geometry._frames(kin)[2]
        buoy = jnp.concatenate([f, jnp.cross(lever - rho, f)], axis=1)
        comps["buoyancy"] = buoy.reshape(-1)
        return {"eta": self._series(self.eta_values, t), "xi": self.geometry.xi(kin),
                "hydro_force": jnp.stack([comps[c] for c in HYDRO_COMPONENTS])}

    def annotate(self, ds, rec):
        ds = ds.assign_coords(hydro_dof=list(self.dofs), component=list(HYDRO_COMPONENTS))
        ds["eta"] = (("time",), rec["eta"], {"long_name": "wave elevation at the origin", "units": "m"})
        ds["xi"] = (("time", "hydro_dof"), rec["xi"],
                    {"long_name": "hydro coordinates: displacement of each body's reference point "
                     "(m) and rotation vector (rad), inertial axes", "units": "m or rad"})
        ds["hydro_force"] = (("time", "component", "hydro_dof"), rec["hydro_force"],
                             {"long_name": "hydrodynamic loads on each body's reference point, "
                              "inertial axes", "units": "N or N m"})
        ds.attrs["radiation"] = self.radiation
        ds.attrs["added_mass"] = self.added_mass
        return ds


HYDRO_COMPONENTS = ("excitation", "radiation", "added_mass", "hydrostatic", "buoyancy", "drag")


# ------------------------------------------------------------------------------------ building
class HydroSpec:
    """Host-side description of a model's water, made by :func:`mfm.load` from the config's
    ``[hydro]`` table: the database restricted to the config's bodies (in config order), where
    each hydro body sits on the tree, drag, and the options. Impulse responses and state-space fits
    are computed on demand and cached here (per dt and per radiation option).

    Identity-hashed on purpose: it rides on the Model as static metadata, so a Model keeps one
    compiled simulation as long as it keeps its HydroSpec.
    """

    def __init__(self, db: xr.Dataset, body_index: Sequence[int], config_names: Sequence[str],
                 com0: np.ndarray, drag: np.ndarray, *, body_coupling: bool = True,
                 added_mass_inf: str = "consistent", source: str = "", moving=None):
        from hydro.database import validate

        self.db_names = [str(b) for b in db["body"].values]
        self.config_names = list(config_names)
        self.body_index = tuple(int(i) for i in body_index)
        self.body_coupling = bool(body_coupling)
        self.source = source
        validate(db)
        self.rho = float(db.attrs["rho"])
        self.g = float(db.attrs["g"])
        self.water_depth = float(db.attrs.get("water_depth", math.inf))
        nb = len(self.db_names)
        mask = np.kron(np.eye(nb), np.ones((6, 6))) if not body_coupling else np.ones((6 * nb, 6 * nb))
        self.mask = mask
        self.db = db
        self.dofs = tuple(str(d) for d in db["influenced_dof"].values)
        # the dofs the mechanics can move (:func:`moving_dofs`); radiation is modelled on these
        self.moving = tuple(range(len(self.dofs))) if moving is None else tuple(int(k) for k in moving)
        ref = np.asarray(db["reference_point"].values, dtype=float)
        self.ref0 = ref
        self.d_ref = ref - com0
        self.d_cob = np.asarray(db["center_of_buoyancy"].values, dtype=float) - com0
        self.volume = np.asarray(db["displaced_volume"].values, dtype=float)
        self.C_wp = np.asarray(db["waterplane_stiffness"].values, dtype=float)
        self.drag = 0.5 * self.rho * np.asarray(drag, dtype=float)
        A_inf = np.asarray(db["added_mass_inf"].values, dtype=float)
        self.A_inf_db = 0.5 * (A_inf + A_inf.T) * mask
        if added_mass_inf not in ("consistent", "database"):
            raise ValueError(f"hydro.added_mass_inf: {added_mass_inf!r}; accepted: 'consistent' "
                             "(A∞ corrected to agree with A(ω) and B(ω)), 'database'")
        self.added_mass_inf_option = added_mass_inf
        self._cache = {}

    # -- radiation
    def database(self) -> xr.Dataset:
        """The database as both domains use it: A(ω), B(ω), A∞ symmetrized (reciprocity: an
        asymmetry is BEM discretisation error, and RM3's asymmetric surge–pitch tails give K(t)
        spikes no time step resolves) and, without body coupling, cross-body blocks zeroed."""
        if "db" in self._cache:
            return self._cache["db"]
        db = self.db.copy()
        mask = xr.DataArray(self.mask, dims=("influenced_dof", "radiating_dof"))
        for v in ("added_mass", "radiation_damping", "added_mass_inf"):
            da = db[v]
            swapped = da.rename(influenced_dof="radiating_dof", radiating_dof="influenced_dof")
            db[v] = (0.5 * (da + swapped.transpose(*da.dims).values) * mask).transpose(*da.dims)
            db[v].attrs = self.db[v].attrs
        self._cache["db"] = db
        return db

    def impulse_response(self, t):
        from hydro.radiation import impulse_response

        return np.asarray(impulse_response(self.database(), np.asarray(t)).values)

    def memory(self, rtol: float = 1e-3) -> float:
        """Memory length T_K (s): where |K| stays below rtol·max|K| (from the decay of K, not Tp)."""
        if "memory" not in self._cache:
            from hydro.radiation import memory_length

            t = np.arange(0.0, 400.0, 0.05)
            self._cache["memory"] = memory_length(self.impulse_response(t), t, rtol=rtol)
        return self._cache["memory"]

    def added_mass_inf(self) -> np.ndarray:
        """A∞ used in the time domain. 'consistent': the database's plus the constant (the median
        over :meth:`radiation_band`) that makes A∞ − ∫K sin ωt dt/ω agree with the database A(ω)
        (a BEM A∞ can be off by a constant: RM3's spar pitch by 2.7 %; outside the band the data
        are too noisy to weigh); 'database': as given."""
        if self.added_mass_inf_option == "database":
            return self.A_inf_db
        if "A_inf" not in self._cache:
            from hydro.radiation import added_mass_from_irf

            db = self.database()
            om = np.asarray(db["omega"].values)
            t = np.arange(0.0, max(2 * self.memory(), 60.0), min(0.02, np.pi / om.max() / 4))
            K = self.impulse_response(t)
            A_rebuilt = np.asarray(added_mass_from_irf(K, t, self.A_inf_db, om))
            lo, hi = self.radiation_band()
            sel = (om >= lo) & (om <= hi)
            # the median: robust to the stretches of a BEM grid where A(ω) is noisy or irregular
            delta = np.median(np.asarray(db["added_mass"].values)[sel] - A_rebuilt[sel], axis=0)
            delta = delta * self.mask
            self._cache["A_inf"] = self.A_inf_db + 0.5 * (delta + delta.T)
            self._cache["A_inf_band"] = (lo, hi)
        return self._cache["A_inf"]

    def radiation_band(self, fraction: float = 0.05):
        """(ω_lo, ω_hi): where some diagonal damping B_ii(ω) is at least ``fraction`` of its own
        peak: the band where radiation matters and the BEM data are meaningful (above it, BEM
        damping is numerical noise; CAPYTAINE.md). Diagonals below 1e-6 of the largest (by
        dimension group) are ignored."""
        db = self.database()
        om = np.asarray(db["omega"].values)
        B = np.asarray(db["radiation_damping"].values)
        diag = np.einsum("wii->wi", B)
        peak = np.abs(diag).max(axis=0)
        active = np.zeros(len(om), dtype=bool)
        for i in range(diag.shape[1]):
            group = [j for j in range(diag.shape[1]) if (j % 6 < 3) == (i % 6 < 3)]
            if peak[i] > 1e-6 * peak[group].max():
                active |= diag[:, i] >= fraction * peak[i]
        idx = np.flatnonzero(active)
        return float(om[idx[0]]), float(om[idx[-1]])

    def state_space(self, **options):
        """The passive state-space fit of :mod:`hydro.statespace` (cached per options). The fit
        band defaults to (0.2 ω_c, 2 ω_c) with the Froude frequency ω_c = √(g/L), L the cube root
        of the largest displaced volume: RM3's (0.2, 2.0) rad/s at full scale, 1.2–12 rad/s for the
        M4 model, so each database is fitted where its waves act (clipped to its grid). Only the
        dofs the model moves are fitted (:attr:`moving`), with one common pole set when more
        than two bodies are coupled (``pole_sharing``, :func:`hydro.statespace.fit_state_space`)."""
        options.setdefault("dofs", tuple(self.dofs[k] for k in self.moving))
        # many coupled bodies: one pole set for all entries (states O(n_dof · order) instead of
        # the per-entry fit's O(n_dof² · order))
        many = self.body_coupling and len(self.db_names) > 2
        options.setdefault("pole_sharing", "common" if many else "entry")
        if "omega_fit" not in options:
            om = np.asarray(self.db["omega"].values)
            wc = math.sqrt(self.g / float(np.max(self.volume)) ** (1.0 / 3.0))
            options["omega_fit"] = (max(0.2 * wc, float(om[0])), min(2.0 * wc, float(om[-1])))
        key = ("ss", tuple(sorted(options.items())))
        if key not in self._cache:
            from hydro.statespace import fit_state_space

            self._cache[key] = fit_state_space(self.database(), **options)
        return self._cache[key]

    def kernel(self, dt: float, memory: float | None = None, subdivisions: int = 16):
        """Convolution weights for the stage offsets s = 0, dt/2, dt of a step.

        The velocity history is piecewise linear between its samples (at τ = 0 the current
        velocity, at τ = s + j·dt the step-start samples j = 0 … N−1), so

            ∫₀^{T_K} K(τ) ξ̇(t − τ) dτ = W_c ξ̇(t) + Σ_j W_j ξ̇(t_n − j dt),

        W = ∫ K(τ) φ(τ) dτ with φ the hat functions of those knots (product integration: exact for
        the interpolated velocity, however sharp K is near τ = 0). K is sampled ``subdivisions``
        times per step. Returns (W_c (3, n, n), W (3, N, n, n)), N = ceil(T_K/dt) + 1, over the
        n dofs the model moves (:attr:`moving`, in that order).
        """
        T_K = self.memory() if memory is None else float(memory)
        n = max(int(math.ceil(T_K / dt)), 2) + 1
        key = ("W", float(dt), n, subdivisions)
        if key not in self._cache:
            from hydro.radiation import check_grid

            check_grid(self.database(), (n - 1) * dt, on_fail="warn")
            h = dt / subdivisions
            tau = np.arange((n + 1) * subdivisions + 1) * h     # up to s + (N−1) dt + … ≤ (N+1) dt
            mv = np.asarray(self.moving)
            K = self.impulse_response(tau)[:, mv][:, :, mv]
            wq = np.full(len(tau), h)
            wq[0] = wq[-1] = 0.5 * h
            Wc, W = [], []
            for r in range(3):
                s = 0.5 * r * dt
                knots = s + np.arange(n) * dt                 # history knots
                if r:
                    knots = np.concatenate([[0.0], knots])      # the current velocity at τ = 0
                inside = tau <= knots[-1] + 1e-12
                k = np.clip(np.searchsorted(knots, tau[inside], side="right") - 1, 0, len(knots) - 2)
                frac = (tau[inside] - knots[k]) / (knots[k + 1] - knots[k])
                Kw = K[inside] * wq[inside][:, None, None]
                # each sample feeds its two hat functions (k sorted: sums by segments, no dense φ)
                Wk = (_segment_sums(k, Kw * (1.0 - frac)[:, None, None], len(knots))
                      + _segment_sums(k + 1, Kw * frac[:, None, None], len(knots)))
                if r:
                    Wc.append(Wk[0])
                    W.append(Wk[1:])
                else:
                    Wc.append(np.zeros_like(Wk[0]))
                    W.append(Wk)
            self._cache[key] = (np.stack(Wc), np.stack(W))
        return self._cache[key]


def build_water(model: Model, spec: HydroSpec, sea, *, dt: float, duration: float, t0: float = 0.0,
                ramp: float = 0.0, radiation: str = "convolution", memory: float | None = None,
                state_space_options: dict | None = None, added_mass: str = "lhs") -> Water:
    """The :class:`Water` load of ``model`` for one sea state and time grid.

    sea: a ``hydro.waves`` sea state (Regular, Jonswap, …) or None for still water.
    radiation: "convolution" (direct, over the memory length from the decay of K), "state_space"
    (the passive fit of hydro.statespace; its corrected A∞), or "none" (A∞ only).
    """
    from hydro.excitation import excitation_time_series
    from hydro.waves import elevation

    if radiation not in ("convolution", "state_space", "none"):
        raise ValueError(f"radiation={radiation!r}; accepted: 'convolution', 'state_space', 'none'")
    nd = len(spec.dofs)
    # excitation and elevation on the half-step grid (the integrators' stage times), one past the end
    n_half = int(round(duration / dt)) * 2 + 3
    t_grid = t0 + 0.5 * dt * np.arange(n_half)
    if sea is None:
        exc = np.zeros((n_half, nd))
        eta = np.zeros(n_half)
    else:
        comps = sea.components(water_depth=spec.water_depth, g=spec.g)
        exc = excitation_time_series(spec.database(), comps, t_grid, ramp_duration=ramp)
        eta = np.asarray(elevation(comps, t_grid, ramp_duration=ramp)).reshape(-1)
    ss_p, ss_C, ss_in, ss_out = np.zeros((0, 2)), np.zeros((0, 0, 2)), (), ()
    W_current, W_lag = np.zeros((3, nd, nd)), np.zeros((3, 1, nd, nd))
    A_inf = spec.added_mass_inf()
    n_lags = 1
    if radiation == "state_space":
        ss = spec.state_space(**(state_space_options or {}))
        P, C, ss_in, ss_out = modal_form(ss)
        ss_p, ss_C = np.stack([P.real, P.imag], 1), np.stack([C.real, C.imag], -1)
        A_inf = np.asarray(ss.added_mass_inf) * spec.mask
    elif radiation == "convolution":
        W_current, W_lag = spec.kernel(dt, memory)          # over the moved dofs
        n_lags = W_lag.shape[1]
    geometry = BodyPoints(body_index=spec.body_index, d_ref=jnp.asarray(spec.d_ref),
                          ref0=jnp.asarray(spec.ref0))
    f64 = lambda a: jnp.asarray(a, dtype=jnp.float64)  # noqa: E731
    return Water(geometry=geometry, A_inf=f64(A_inf), C_wp=f64(spec.C_wp),
                 buoyancy=f64(spec.rho * spec.g * spec.volume), d_cob=f64(spec.d_cob),
                 drag=f64(spec.drag), ss_p=f64(ss_p), ss_C=f64(ss_C), ss_in=ss_in, ss_out=ss_out,
                 W_current=f64(W_current), W_lag=f64(W_lag), dt=f64(dt), exc_t0=f64(t0), exc_step=f64(0.5 * dt),
                 exc_values=f64(exc), eta_values=f64(eta), radiation=radiation, n_lags=n_lags,
                 added_mass=added_mass, conv_dofs=tuple(spec.moving),
                 dofs=spec.dofs)


def _segment_sums(idx, vals, n_out):
    """out[i] = Σ vals[j] over j with idx[j] = i, for non-decreasing idx."""
    out = np.zeros((n_out,) + vals.shape[1:])
    if len(idx):
        starts = np.flatnonzero(np.r_[True, np.diff(idx) != 0])
        out[idx[starts]] = np.add.reduceat(vals, starts, axis=0)
    return out


def modal_form(ss):
    """The modal realisation of a state-space fit: poles P (n_x,) complex, one per input dof j and
    pole of the entries (i, j) fitted with the same pole set (Im p ≥ 0 representatives: a pair's
    conjugate is folded into the residue × 2); output residues C (n_out, n_x); the input dof of
    each state; the output dofs (rows of C)."""
    groups = {}                                       # (j, poles) -> [(i, residues)]
    for (i, j), P, R in zip(ss.entries, ss.poles, ss.residues):
        keep = P.imag >= 0.0
        key = (j, P[keep].tobytes())
        groups.setdefault(key, (P[keep], []))[1].append((i, R[keep] * np.where(P[keep].imag > 0, 2.0, 1.0)))
    outs = tuple(sorted({i for i, _ in ss.entries}))
    poles, ins, cols = [], [], []
    for (j, _), (P, members) in groups.items():
        C = np.zeros((len(outs), len(P)), dtype=complex)
        for i, r in members:
            C[outs.index(i)] += r
        poles.append(P)
        cols.append(C)
        ins += [j] * len(P)
    if not poles:
        return np.zeros(0, complex), np.zeros((0, 0), complex), (), ()
    return np.concatenate(poles), np.concatenate(cols, axis=1), tuple(ins), outs


def open_any_database(path: Path, *, names=None, rho=None, g=None) -> xr.Dataset:
    """Open a hydro database: our NetCDF, a capytaine NetCDF (converted), or WAMIT output."""
    from hydro import bem
    from hydro.database import from_capytaine, open_database
    from hydro.wamit import read_wamit

    path = Path(path)
    if path.suffix == ".nc":
        if not path.exists():
            raise FileNotFoundError(f"hydro.database: {str(path)!r} not found; generate it with "
                                    "`mfm hydro CONFIG` or fix the path (relative to the config)")
        with xr.open_dataset(path) as raw:
            ours = "added_mass_inf" in raw.data_vars
        return open_database(path) if ours else from_capytaine(bem.load(path))
    stem = path.with_suffix("") if path.suffix in (".out", ".1", ".3", ".hst") else path
    if not stem.with_suffix(".out").exists():
        raise FileNotFoundError(f"hydro.database: {str(path)!r}: no WAMIT output {stem}.out and not "
                                "a .nc file; accepted: a NetCDF database or a WAMIT .out/.1/.3/.hst set")
    kw = {}
    if rho is not None:
        kw["rho"] = float(rho)
    if g is not None:
        kw["g"] = float(g)
    return read_wamit(stem, body_names=names, **kw)


def load_hydro_spec(model: Model, bodies, options: dict, config_dir: Path,
                    body_coupling: bool | None = None) -> HydroSpec:
    """Build a model's :class:`HydroSpec` from the parsed ``[hydro]`` table."""
    from hydro.database import select_bodies

    path = Path(options["database"])
    if not path.is_absolute():
        path = Path(config_dir) / path
    db = open_any_database(path, names=options.get("names"), rho=options.get("rho"), g=options.get("g"))
    available = [str(b) for b in db["body"].values]
    tagged = [(b.name, b.extra["hydro"]) for b in bodies if "hydro" in b.extra]
    if tagged:
        wet = [(name, h["body"], h["drag"]) for name, h in tagged]
    else:
        wet = [(b.name, b.name, np.zeros(3)) for b in bodies if b.name in available]
    if not wet:
        raise ValueError(f"hydro: no config body is in the database {str(path)!r} (database bodies "
                         f"{available}, config bodies {[b.name for b in bodies]}); give each wet "
                         "body a [bodies.hydro] table with body = \"<database name>\"")
    missing = [db_name for _, db_name, _ in wet if db_name not in available]
    if missing:
        raise ValueError(f"hydro: database bodies {missing} named by the config are not in "
                         f"{str(path)!r}; available: {available}")
    db = select_bodies(db, [db_name for _, db_name, _ in wet])
    idx = [model.body_index(name) for name, _, _ in wet]
    com0 = np.asarray(model.com)[idx]
    coupling = options.get("body_coupling", True) if body_coupling is None else body_coupling
    return HydroSpec(db, idx, [name for name, _, _ in wet], com0, np.stack([d for _, _, d in wet]),
                     body_coupling=coupling, added_mass_inf=options.get("added_mass_inf", "consistent"),
                     source=str(path), moving=moving_dofs(model, idx, np.asarray(db["reference_point"].values) - com0))


def moving_dofs(model: Model, body_index, d_ref, n_samples: int = 3, seed: int = 0) -> np.ndarray:
    """Indices of the hydro dofs (6 per wet body: the velocity of its reference point and its
    angular velocity, inertial axes) that the model's joints can move: the rows of H(q) in
    ξ̇ = H q̇ that are not 0 at ``n_samples`` random configurations (|q| ≤ 0.3). A structural zero
    (a planar model has no sway, roll or yaw) is 0 at every q; a row that is 0 by accident at
    three random q is not generic. Radiation is modelled on these dofs only."""
    from .kinematics import kinematics

    geo = BodyPoints(body_index=tuple(int(i) for i in body_index), d_ref=jnp.asarray(d_ref),
                     ref0=jnp.zeros((len(body_index), 3)))
    rng = np.random.default_rng(seed)
    peak = 0.0
    for _ in range(n_samples):
        q = jnp.asarray(rng.uniform(-0.3, 0.3, model.n_coordinates))
        H = np.abs(np.asarray(geo.h_matrix(kinematics(model, q, jnp.zeros_like(q)))[0]))
        peak = np.maximum(peak, H.max(axis=1))
    return np.flatnonzero(peak > 1e-12 * max(float(np.max(peak)), 1e-300))
