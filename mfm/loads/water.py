"""The water: Cummins hydrodynamics through Bᵀ F, the one load that joins `mfm` to `hydro`.

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
  load (Ḣ q̇ from the tree walk's velocity-product accelerations). ``added_mass="rhs"`` instead
  puts −A∞ ξ̈ on the right-hand side with the corrector's acceleration iterate (Lande-Sudall et al. §5).
- Buoyancy is the constant force ρgV ẑ at the centre of buoyancy (a point fixed in the body), plus
  the linear water-plane stiffness C_wp about r_k (the database's ``waterplane_stiffness``: no
  ρgV z_B, no m g z_G, so gravity and buoyancy are not counted twice). Weights act exactly (mfm).
- Radiation memory by a strategy (:mod:`mfm.loads.radiation`): convolution, state space or none.
- Quadratic drag −½ ρ C_D A |u| u per inertial axis on the velocity u of r_k, or with
  ``[hydro] drag_flow = "relative"`` on its velocity relative to the incident wave's flow there
  (:func:`hydro.wetted.particle_velocity`; no current); it is not linearised in the frequency
  domain (zero slope at rest).
- Mean wave drift (``[hydro] drift = "mean" | "newman"``, :mod:`hydro.drift`): the second-order
  drift force from the database's ``mean_drift``, a table on the excitation's grid
  (``drift_values``) applied at the reference points like the excitation (and ramped as it is);
  recorded as ``drift_force``. The equilibrium in a sea (``mfm.equilibrium(model, sea=)``) takes
  its mean Σ_j D(ω_j, β_j) a_j² as a constant load (:meth:`Water.in_mean_drift`): a moored
  body's mean offset. The frequency domain does not see it (a mean force: linearise about that
  equilibrium).

In the frequency domain the same load gives, about q₀, the impedance −ω² Hᵀ(A(ω) − A∞)H
− iω HᵀB(ω)H of its radiation strategy (A∞ H itself is in the mass, from ``mass``) and the wave
force Hᵀ X(ω, β).
"""
from __future__ import annotations

import dataclasses
import os
import warnings
from pathlib import Path
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from hydro import phases
from hydro.seabatch import components_many
# the ramp and still water of a wave field live beside it: the Morison elements
# (mfm.loads.morison) ramp their flow as the water does
from hydro.wetted import ramped as _ramped, still as _still

from .. import host
from ..backend import device_array
from ..mechanics import se3
from ..mechanics.points import BodyPoints, h_matrix_at
from .base import FrequencyTerms, LinearHydro, Load, LoadOutput, QuadraticDrag
from .radiation import NoRadiation, grid_subdivisions, strategy, strategy_many

MODES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
HYDRO_COMPONENTS = ("excitation", "radiation", "added_mass", "hydrostatic", "buoyancy", "drag")


class Hulls(eqx.Module):
    """The nonlinear level's hulls (``[hydro] hydrostatics = "nonlinear"``): the pressure of the
    undisturbed flow, hydrostatic and the incident wave's, on each hydro body's instantaneous
    wetted hull (:func:`hydro.wetted.pressure_loads`), in place of the constant buoyancy, the
    linear water-plane stiffness and the Froude–Krylov part of the excitation.

    ``tri``: per hydro body, its closed hull's triangles in body axes about its CoM, as rows
    (3, 3, n_k): vertex, axis, triangle (:func:`hydro.wetted.soa`);
    ``wave``: the run's incident components (:class:`hydro.wetted.WaveField`, no ramp);
    ``ramp``: s, the excitation's start-up ramp, applied to the amplitudes; ``rho``, ``g``."""
    tri: tuple
    wave: object
    ramp: jnp.ndarray
    rho: float = eqx.field(static=True, default=1025.0)
    g: float = eqx.field(static=True, default=9.81)
    # the pressure sampled every few steps (HeldHulls), or None: at every evaluation
    hold: object = None

    def loads(self, geometry, kin, t):
        """(hydrostatic, Froude–Krylov), each (6K,): force and moment about each reference point
        r_k (inertial axes) of the two pressures on the wetted hull cut at the instantaneous
        surface."""
        from hydro.wetted import pressure_loads_rows

        wave = _ramped(self.wave, self.ramp, t)
        idx = np.asarray(geometry.body_index)
        ref = geometry.positions(kin)
        hs, fk = [], []
        for k, tri in enumerate(self.tri):
            E = kin.E[idx[k]]
            h, f = pressure_loads_rows(tri, E[:3, :3], E[:3, 3], ref[k], wave, t, rho=self.rho,
                                       g=self.g)
            hs.append(h)
            fk.append(f)
        return jnp.concatenate(hs), jnp.concatenate(fk)

    def still(self) -> "Hulls":
        """These hulls in still water, their pressure evaluated at every call (the
        linearisation's static load)."""
        return dataclasses.replace(self, wave=_still(self.wave), hold=None)

    # -- the pressure sampled every few steps ([hydro] nonlinear_dt): module docstring of HeldHulls
    def correction(self, geometry, kin, t):
        """Δ (2, 6K): the pressure loads (hydrostatic, Froude–Krylov) less what the linear level
        gives at the same pose and time (:meth:`HeldHulls.linear`)."""
        hs, fk = self.loads(geometry, kin, t)
        hs_lin, fk_lin = self.hold.linear(geometry, kin, _ramped(self.wave, self.ramp, t), t)
        return jnp.stack([hs - hs_lin, fk - fk_lin])

    def init_held(self, geometry, kin, t0):
        """The held samples at the run's start: (count, t_a, t_b, t_c, Δ_a, Δ_b, Δ_c), newest
        first, the three the same (no slope before a second sample, no curvature before a
        third)."""
        d = self.correction(geometry, kin, t0)
        t0 = jnp.asarray(t0, jnp.float64)
        return (jnp.asarray(0, jnp.int32), t0, t0, t0, d, d, d)

    def update_held(self, geometry, kin, t, held):
        """The held samples after a step ending at (t, kin): every ``every`` steps a new sample,
        the two before it kept (the extrapolation's), the oldest dropped; else unchanged."""
        count, t_a, t_b, t_c, d_a, d_b, d_c = held
        count = count + 1

        def sample(_):
            return (jnp.asarray(0, jnp.int32), jnp.asarray(t, jnp.float64), t_a, t_b,
                    self.correction(geometry, kin, t), d_a, d_b)

        if self.hold.every == 1:
            return sample(None)
        # a step counter the cases of a batch share: a branch taken, not both evaluated
        return jax.lax.cond(count >= self.hold.every, sample,
                            lambda _: (count, t_a, t_b, t_c, d_a, d_b, d_c), None)

    def held_loads(self, geometry, kin, t, held):
        """(hydrostatic, Froude–Krylov) at a stage (t, kin) of the held level: the linear
        level's hydrostatics (the Froude–Krylov's is in the water's tables) and Δ extrapolated
        from the last three samples by Newton's divided differences,

            Δ(t) = Δ_a + (t − t_a) (Δ[a, b] + (t − t_b) Δ[a, b, c]),

        Δ[a, b] = (Δ_a − Δ_b)/(t_a − t_b), Δ[a, b, c] = (Δ[a, b] − Δ[b, c])/(t_a − t_c); a
        divided difference over samples not yet taken (equal times, the run's start) is 0."""
        _, t_a, t_b, t_c, d_a, d_b, d_c = held

        def divided(x, y, gap):
            return jnp.where(gap > 0, (x - y) / jnp.where(gap > 0, gap, 1.0), 0.0)

        s_ab = divided(d_a, d_b, t_a - t_b)
        s_bc = divided(d_b, d_c, t_b - t_c)
        curv = jnp.where(t_b > t_c, divided(s_ab, s_bc, t_a - t_c), 0.0)
        d = d_a + (t - t_a) * (s_ab + (t - t_b) * curv)
        hs_lin = self.hold.hydrostatic(geometry, kin)
        return hs_lin + d[0], d[1]


class HeldHulls(eqx.Module):
    """The nonlinear level with its hull pressure sampled every ``every`` steps
    (``[hydro] nonlinear_dt`` = every × dt, as WEC-Sim's ``dtNL``): each stage of each step takes
    the linear level's loads (the database's buoyancy, water-plane stiffness and excitation, at
    the stage's own pose and time) plus the nonlinear level's excess over them,

        Δ = F_pressure(q, t) − [ρgV ẑ at the CoB − C_wp ξ + F_FK,lin(t)],

    evaluated on the wetted hull at the samples only and extrapolated quadratically from the last
    three between them. At rest and in small waves Δ is second order in the motions and the
    wave, so the error of sampling it is a fraction |Δ|/|F| of the extrapolation's own,
    O((ω h)³) per interval h = nonlinear_dt (tests/test_nonlinear_held.py: ×8 per doubling); what
    stiffens the equations (C_wp, the wave force) is still evaluated at every stage. One pressure
    integral per ``every`` steps instead of RK4's four per step.

    ``C_wp`` (6K, 6K), ``buoyancy`` (K,) ρgV, ``d_cob`` (K, 3): the linear level's hydrostatics;
    ``fk_re``, ``fk_im`` (J, 6K): the hulls' linear Froude–Krylov coefficients X_FK at the wave
    field's components (:func:`hydro.wetted.froude_krylov_linear`; per metre of amplitude),
    F_FK,lin(t) = Σ_j a_j r(t) Re[X_FK,j e^{i(φ_j − ω_j t)}], what the tables' excitation holds."""
    C_wp: jnp.ndarray
    buoyancy: jnp.ndarray
    d_cob: jnp.ndarray
    fk_re: jnp.ndarray
    fk_im: jnp.ndarray
    every: int = eqx.field(static=True, default=1)

    def hydrostatic(self, geometry, kin):
        """The linear level's hydrostatic load (6K,): ρgV ẑ at each centre of buoyancy (as loads
        at r_k) − C_wp ξ."""
        return (buoyancy_load(geometry, kin, self.buoyancy, self.d_cob)
                - self.C_wp @ geometry.xi(kin))

    def linear(self, geometry, kin, wave, t):
        """(hydrostatic, Froude–Krylov) of the linear level at (t, kin), ``wave`` ramped."""
        ph = wave.phase - wave.omega * t
        c, s = wave.amplitude * jnp.cos(ph), wave.amplitude * jnp.sin(ph)
        return self.hydrostatic(geometry, kin), c @ self.fk_re - s @ self.fk_im


def buoyancy_load(geometry, kin, buoyancy, d_cob):
    """ρgV ẑ at each centre of buoyancy as loads at the reference points r_k (6K,): force and
    moment (CoB − r_k) × f, inertial axes; ``buoyancy`` (K,) ρgV, ``d_cob`` (K, 3) CoB − CoM in
    body axes. The linear level's buoyancy (:meth:`Water._forces`, :meth:`HeldHulls.hydrostatic`)."""
    R = kin.E[np.asarray(geometry.body_index), :3, :3]
    lever = se3.rotate(R, d_cob)
    f = jnp.zeros_like(lever).at[:, 2].set(buoyancy)
    return jnp.concatenate([f, jnp.cross(lever - geometry._frames(kin)[2], f)],
                           axis=1).reshape(-1)


class Flow(eqx.Module):
    """The incident wave's flow for drag on the relative velocity (``[hydro] drag_flow =
    "relative"``): ``wave`` (:class:`hydro.wetted.WaveField`, no ramp), ``ramp`` (s)."""
    wave: object
    ramp: jnp.ndarray

    def velocity(self, points, t):
        """The flow's velocity (K, 3) at ``points`` (K, 3), ramped as the excitation is."""
        from hydro.wetted import particle_velocity

        return particle_velocity(_ramped(self.wave, self.ramp, t), points, t)

    def still(self) -> "Flow":
        """This flow in still water (the linearisation's static load)."""
        return dataclasses.replace(self, wave=_still(self.wave))


class Water(Load):
    """The hydrodynamic load of a model. Build with :func:`build_water`.

    Arrays (float64): ``A_inf`` (6K, 6K); ``C_wp`` (6K, 6K); ``buoyancy`` (K,) = ρ g V, N;
    ``d_cob`` (K, 3) CoB − CoM at q = 0; ``drag`` (K, 3) = ½ ρ C_D A per inertial axis; the
    excitation ``exc_values`` (n, 6K) on the grid ``exc_t0 + j·exc_step`` and the wave elevation
    at the origin ``eta_values`` (n,) on the same grid; ``rad`` the radiation strategy.
    Static: ``spec`` (the :class:`~hydro.prepare.HydroSpec`), ``dofs``, ``added_mass``,
    ``grid_m`` (excitation samples per step). Nothing that differs between sea states is static,
    so a batch of seas stacks into one structure.
    """
    geometry: BodyPoints
    A_inf: jnp.ndarray
    C_wp: jnp.ndarray
    buoyancy: jnp.ndarray
    d_cob: jnp.ndarray
    drag: jnp.ndarray
    exc_t0: jnp.ndarray
    exc_step: jnp.ndarray
    exc_values: jnp.ndarray
    eta_values: jnp.ndarray
    rad: NoRadiation
    dofs: tuple[str, ...] = eqx.field(static=True)
    added_mass: str = eqx.field(static=True, default="lhs")
    spec: object = eqx.field(static=True, default=None)
    grid_m: int = eqx.field(static=True, default=2)   # excitation samples per step
    # the moved hydro dofs (spec.moving): what traced code needs of the spec, kept apart so that
    # the compiled functions can be handed the water without its spec (loads.assembly.compile_view)
    moving: tuple | None = eqx.field(static=True, default=None)
    # the nonlinear level's hulls (Hulls), or None: the linear hydrostatics and excitation
    hulls: object = None
    # the incident flow of drag on the relative velocity (Flow), or None: drag on ξ̇ alone
    flow: object = None
    # the wave drift force (n, 6K) on the excitation's grid ([hydro] drift), or None: none
    drift_values: jnp.ndarray | None = None
    # the mean drift force (6K,) the water keeps at rest (in_mean_drift: the equilibrium in a sea),
    # or None: still water has none
    drift_at_rest: jnp.ndarray | None = None
    reads_sea: ClassVar[bool] = True

    # the older names, kept for code that reads them
    @property
    def radiation(self) -> str:
        return self.rad.name

    @property
    def n_lags(self) -> int:
        return getattr(self.rad, "n_lags", 1)

    @property
    def conv_dofs(self) -> tuple[int, ...]:
        return getattr(self.rad, "dofs", ())

    @property
    def n_states(self) -> int:
        return self.rad.n_states

    @property
    def _held(self) -> bool:
        """Whether the hull pressure is sampled every few steps (:class:`HeldHulls`): the memory
        is then (the radiation's, the held samples)."""
        return self.hulls is not None and self.hulls.hold is not None

    def _rad_memory(self, memory):
        return memory[0] if self._held else memory

    def init_memory(self, model, t0, q0, qd0, dt):
        from ..mechanics.kinematics import kinematics

        kin = kinematics(model, q0, qd0)
        v, _ = self.geometry.velocity_and_bias(kin)
        rad = self.rad.init_memory(v, t0)
        if not self._held:
            return rad
        return rad, self.hulls.init_held(self.geometry, kin, t0)

    def update_memory(self, model, t, q, qd, kin, memory):
        v, _ = self.geometry.velocity_and_bias(kin)
        rad = self.rad.update_memory(v, t, self._rad_memory(memory))
        if not self._held:
            return rad
        return rad, self.hulls.update_held(self.geometry, kin, t, memory[1])

    def _series(self, values, t):
        s = (t - self.exc_t0) / self.exc_step
        n = values.shape[0]
        k = jnp.clip(jnp.floor(s), 0, n - 2).astype(int)
        w = jnp.clip(s - k, 0.0, 1.0)
        return (1.0 - w) * values[k] + w * values[k + 1]

    def radiation_force(self, t, v, z, memory):
        """−∫K ξ̇ and the state derivative, by the radiation strategy."""
        return self.rad.force(t, v, z, memory)

    def _forces(self, t, kin, z, memory, rows, hull=None):
        """The Cummins terms of the module docstring on the hydro dofs ``rows`` (static indices),
        each (len(rows),): buoyancy as a load at r_k (moment (CoB − r_k) × f), −A∞ Ḣq̇ as
        ``added_mass_bias``; and the radiation's ż, ξ̇ and Ḣq̇ (6K,). The time step asks for the
        moved dofs only, the outputs and reactions for all. ξ̇ and Ḣq̇ are 0 outside the moved
        dofs m (:func:`moving_dofs`), so A∞ Ḣq̇ reads columns m only."""
        g, mv = self.geometry, self._moved
        xi = g.xi(kin)
        v, hbias = g.velocity_and_bias(kin)
        r_rad, F_rad, zd = self.rad.force_rows(t, v, z, self._rad_memory(memory))
        if r_rad is None:
            rad = jnp.zeros(len(rows))
        elif tuple(r_rad) == tuple(rows):
            rad = F_rad
        else:   # placed by a static 0/1 matrix: a scatter would keep XLA from compiling the time
            # loop whole (mfm.runner.xla)
            P = (np.asarray(rows)[:, None] == np.asarray(r_rad)[None, :]).astype(float)
            rad = jnp.sum(P * F_rad[None, :], axis=1)
        # quadratic drag on the translational dofs (k = body, a = axis), dense for the same reason
        k, a = rows // 6, rows % 6
        vr = v[rows]
        if self.flow is not None:
            # drag on the velocity relative to the undisturbed flow at each reference point
            u = self.flow.velocity(g.positions(kin), t)                       # (K, 3)
            vr = vr - jnp.concatenate([u, jnp.zeros_like(u)], axis=1).reshape(-1)[rows]
        exc = self._series(self.exc_values, t)
        if self.hulls is None:
            buoy = buoyancy_load(g, kin, self.buoyancy, self.d_cob)
        else:
            # the pressure on the wetted hull: its hydrostatic part is the buoyancy and the
            # restoring (C_wp is 0 here), its wave part adds to the tables' diffraction (made
            # once a recorded sample: evaluate hands them to reaction_loads and diagnostics)
            buoy, fk = self.hulls.loads(g, kin, t) if hull is None else hull
            exc = exc + fk
        out = dict(excitation=exc[rows], radiation=rad,
                   hydrostatic=-(self.C_wp[rows] @ xi),
                   drag=-(self.drag[k, np.minimum(a, 2)] * (a < 3)) * jnp.abs(vr) * vr,
                   added_mass_bias=-(self.A_inf[rows][:, mv] @ hbias[mv]),
                   buoyancy=buoy[rows])
        if self.drift_values is not None:
            out["drift"] = self._series(self.drift_values, t)[rows]
        return out, zd, v, hbias

    @property
    def _moved(self) -> np.ndarray:
        """Indices of the moved hydro dofs (static): the rows of H that are not structurally 0."""
        return self._all if self.moving is None else np.asarray(self.moving)

    @property
    def _all(self) -> np.ndarray:
        return np.arange(self.A_inf.shape[0])

    def _moved_load(self, ctx, H, hull=None):
        """The hydro load on the moved dofs, F[m] (n_m,), with ``H`` = H[m] (n_m, n_q) (with
        ``added_mass="rhs"`` −A∞ H q̈ of the iterate), and the radiation's ż. Its virtual power is
        the whole load's: the rows of H outside m are 0 at every q (:func:`moving_dofs`), so
        Hᵀ F = H[m]ᵀ F[m]."""
        mv = self._moved
        comps, zd, _, _ = self._forces(ctx.t, ctx.kin, ctx.z, ctx.memory, mv, hull)
        F = sum(comps.values())
        if self.added_mass == "rhs" and ctx.qdd_guess is not None:
            # Lande-Sudall et al. §5: −A∞ ξ̈ on the right-hand side with the corrector's acceleration iterate.
            # Without an iterate (start of a run, linearisation) the iteration's converged value
            # is used instead: A∞ on the left.
            F = F - self.A_inf[mv][:, mv] @ (H @ ctx.qdd_guess)
        return F, zd

    def evaluate(self, ctx):
        # generalised loads Hᵀ F on the moved dofs directly: no body wrenches in the time step
        # (they are made for the joint reactions only, :meth:`reaction_loads`)
        mv = self._moved
        H = self.geometry.h_matrix(ctx.kin)[0][mv]
        hull = self._hull_loads(ctx)
        F, zd = self._moved_load(ctx, H, hull)
        tau = jnp.sum(H * F[:, None], axis=0)
        rhs = self.added_mass == "rhs" and ctx.qdd_guess is not None
        mass = None if rhs else se3.matmul_small(H, se3.matmul_small(self.A_inf[mv][:, mv], H),
                                                 transpose_x=True)
        return LoadOutput(tau=tau, zd=zd, mass=mass, extra=hull)

    def _hull_loads(self, ctx):
        """The nonlinear level's (hydrostatic, Froude–Krylov) at the context's state: the
        pressure on the wetted hull, or with ``[hydro] nonlinear_dt`` the held level's
        (:meth:`Hulls.held_loads`); None for the linear level."""
        if self.hulls is None:
            return None
        if self._held:
            return self.hulls.held_loads(self.geometry, ctx.kin, ctx.t, ctx.memory[1])
        return self.hulls.loads(self.geometry, ctx.kin, ctx.t)

    def reaction_loads(self, ctx, out):
        # the whole −A∞ ξ̈ on the bodies: −A∞ Ḣq̇ and −A∞ H q̈ (with added_mass="rhs" the load
        # already holds −A∞ H q̈ of the recorded iterate)
        kin = ctx.kin
        comps, _, _, _ = self._forces(ctx.t, kin, ctx.z, ctx.memory, self._all, out.extra)
        H, _, _ = self.geometry.h_matrix(kin)
        qdd = ctx.qdd_guess if out.mass is None else ctx.qdd
        F = sum(comps.values()) - self.A_inf @ (H @ qdd)
        return self.geometry.to_body_wrench(F, kin, ctx.model.n_bodies)

    def diagnostics(self, ctx, out):
        kin = ctx.kin
        comps, _, v, hbias = self._forces(ctx.t, kin, ctx.z, ctx.memory, self._all, out.extra)
        H, _, _ = self.geometry.h_matrix(kin)
        comps["added_mass"] = -(self.A_inf @ (H @ ctx.qdd + hbias))
        comps.pop("added_mass_bias")
        out = {"eta": self._series(self.eta_values, ctx.t), "xi": self.geometry.xi(kin),
               "hydro_force": jnp.stack([comps[c] for c in HYDRO_COMPONENTS])}
        if self.drift_values is not None:
            out["drift_force"] = comps["drift"]
        return out

    def outputs(self):
        return {"coords": {"hydro_dof": list(self.dofs), "component": list(HYDRO_COMPONENTS)},
                "eta": ((), {"long_name": "wave elevation at the origin", "units": "m"}),
                "xi": (("hydro_dof",), {"long_name": "hydro coordinates: displacement of each "
                                        "body's reference point (m) and rotation vector (rad), "
                                        "inertial axes", "units": "m or rad"}),
                "hydro_force": (("component", "hydro_dof"),
                                {"long_name": "hydrodynamic loads on each body's reference point, "
                                 "inertial axes", "units": "N or N m"}),
                **({} if self.drift_values is None else {"drift_force": (("hydro_dof",), {
                    "long_name": "wave drift force on each body's reference point, inertial axes "
                                 "(not in hydro_force)", "units": "N or N m",
                    "drift": self.spec.drift if self.spec is not None else ""})})}

    def batch_outputs(self, save_every, n_saved):
        # (n_saved,), or (B, n_saved) for the water of many cases (build_water_batch)
        eta = np.asarray(self.eta_values)[..., ::self.grid_m * save_every][..., :n_saved]
        return {"eta": (eta, {"long_name": "wave elevation at the origin", "units": "m"})}

    def host_view(self):
        # traced code reads the moved dofs (kept apart in ``moving``), never the spec
        return dataclasses.replace(self, spec=None, rad=self.rad.host_view())

    def linear_hydro(self):
        return LinearHydro(self.spec, self.geometry, self.A_inf, self.drag, self._frequency_coefficients)

    def with_tables(self, exc_values, eta_values, drift_values=None):
        """This water with its excitation (n, 6K or the moved columns) and elevation (n,) tables
        replaced, and its drift table (n, 6K) where given: a batch's tables made on the device
        (:class:`WaveSum`)."""
        out = dataclasses.replace(self, exc_values=exc_values, eta_values=eta_values)
        return out if drift_values is None else dataclasses.replace(out, drift_values=drift_values)

    def provenance(self):
        out = {"added_mass": self.added_mass, **self.rad.provenance(),
               "hydrostatics": "linear" if self.hulls is None else "nonlinear",
               "drag_flow": "body" if self.flow is None else "relative"}
        if self.hulls is not None:
            out["hull_panels"] = ", ".join(str(int(t.shape[-1])) for t in self.hulls.tri)
            if self._held:
                out["hull_pressure"] = (f"sampled every {int(self.hulls.hold.every)} steps "
                                        "(hydro.nonlinear_dt), extrapolated between")
        if self.spec is not None:
            out.update(self.spec.provenance())
        return out

    def describe_nonfinite(self, model, q, qd):
        if self.added_mass != "rhs":
            return None
        from ..mechanics.dynamics import mass_matrix
        from ..mechanics.kinematics import kinematics

        # the fixed-point iteration a ← M*⁻¹(F − Hᵀ A∞ H a) contracts only if the spectral radius
        # of M*⁻¹ Hᵀ A∞ H is below 1
        H = np.asarray(self.geometry.h_matrix(kinematics(model, q, qd))[0])
        Ms = np.asarray(mass_matrix(model, q))
        r = float(np.abs(np.linalg.eigvals(np.linalg.solve(Ms, H.T @ np.asarray(self.A_inf) @ H))).max())
        if r < 1.0:
            return None
        return (f"Likely cause: added_mass='rhs' (Lande-Sudall et al.'s iteration of A∞ ξ̈ on the right-hand "
                f"side) diverges here: the spectral radius of M*⁻¹ Hᵀ A∞ H is {r:.3g} ≥ 1 (added "
                "mass larger than the structural mass). Use added_mass='lhs' (A∞ in M*, no "
                "iteration).")

    # -- linearisation
    def static_load(self):
        """Still water, no memory: buoyancy, water-plane stiffness, A∞ (in the mass). Its tables
        are two rows of zeros (the interpolation clips to them: zero at every t) whatever the
        run's length: the loads at rest of every run of a model have one structure (one compiled
        linearisation, :func:`mfm.frequency.rest.linearised_at_rest`) and hold no table of the run's
        length (M4 134, 10⁶ RK4 steps: 0.8 GB)."""
        def zeros(a):           # numpy onto the device: no compiled broadcast per shape
            return device_array(np.zeros((2,) + a.shape[1:], a.dtype))

        still = eqx.tree_at(lambda w: (w.exc_values, w.eta_values, w.rad),
                            self, (zeros(self.exc_values), zeros(self.eta_values), NoRadiation()))
        if self.drift_values is not None:
            still = dataclasses.replace(still, drift_values=zeros(self.drift_values))
        if self.drift_at_rest is not None:
            # the mean drift of in_mean_drift, a constant table (two equal rows: every t reads it)
            mean = np.asarray(self.drift_at_rest, np.float64)
            still = dataclasses.replace(still, drift_values=device_array(
                np.broadcast_to(mean, (2,) + mean.shape).copy()))
        if self.hulls is not None:
            still = dataclasses.replace(still, hulls=self.hulls.still())
        if self.flow is not None:
            still = dataclasses.replace(still, flow=self.flow.still())
        return still

    def in_mean_drift(self, sea, mean_drift=None) -> "Water":
        """This water holding, at rest, the mean wave drift force of ``sea``,

            F̄_i = Σ_j D_i(ω_j, β_j) a_j²      (N, N m; inertial axes at the reference points),

        D the database's ``mean_drift`` (interpolated as the time domain's drift is,
        :class:`hydro.drift.DriftTable`) and a_j the components' amplitudes: what
        ``[hydro] drift = "mean"`` applies in a run after its ramp, and Newman's slow drift's
        mean. Its :meth:`static_load` carries F̄, so the equilibrium of a model with this water
        is the mean position in that sea (a moored body's mean offset); the waves' first-order
        forces average to zero there. Whatever ``[hydro] drift`` says (the question is the
        mean offset); a database without ``mean_drift`` is refused, naming how to make one.
        ``mean_drift``: a :class:`mfm.frequency.drift.MeanDrift` in place of the database's
        (the drift of the model's own motions)."""
        from hydro.drift import mean_drift_of

        spec = self.spec
        if mean_drift is None:
            require_mean_drift(spec.database(), spec.source, "mfm.equilibrium(sea=...)")
        comps = sea.components(water_depth=spec.water_depth, g=spec.g)
        mean = np.asarray(mean_drift_of(_drift_source(spec, mean_drift), comps), np.float64)
        if mean.shape != (self.A_inf.shape[0],):
            raise ValueError(f"mfm.equilibrium(sea=...): the database's mean drift has "
                             f"{mean.shape[0]} dofs, the water {self.A_inf.shape[0]}")
        return dataclasses.replace(self, drift_at_rest=mean)

    def _frequency_coefficients(self, kin0, omega, heading, options, excitation=True):
        """(A(ω) − A∞, B(ω), X(ω, β) or None, H₀) of ``options["radiation"]``: (n_ω, 6K, 6K),
        (n_ω, 6K, 6K), (n_ω, 6K), (6K, n_q)."""
        from hydro.excitation import GRID_RTOL, excitation_coefficients
        from hydro.waves import WaveComponents, wavenumber

        spec = self.spec
        from ..radiation import resolve

        # a strategy object or its alias, resolved here behind every frequency-domain front door
        name, _, fit_options = resolve(options.get("radiation", "database"), None,
                                       options.get("state_space_options"), domain="frequency")
        rad = strategy(spec, name, frequency_domain=True, state_space_options=fit_options)
        om_db = np.asarray(spec.database()["omega"].values)
        om_db = om_db[np.isfinite(om_db)]
        # a frequency within GRID_RTOL beyond an end of the grid is that end (six-decimal grids)
        if omega.min() < om_db[0] * (1 - GRID_RTOL) or omega.max() > om_db[-1] * (1 + GRID_RTOL):
            raise ValueError(f"omega: [{omega.min():.7g}, {omega.max():.7g}] rad/s lies outside the "
                             f"database's [{om_db[0]:.7g}, {om_db[-1]:.7g}] rad/s; choose frequencies "
                             "inside it or regenerate the database")
        A, B = rad.coefficients(spec, np.clip(omega, om_db[0], om_db[-1]))
        H0 = np.asarray(h_matrix_at(self.geometry, kin0))
        A_rel = np.asarray(A) - np.asarray(self.A_inf)[None]
        if not excitation:
            return A_rel, np.asarray(B), None, H0
        comps = WaveComponents(omega=omega, amplitude=np.ones_like(omega), phase=np.zeros_like(omega),
                               heading=np.full_like(omega, heading),
                               wavenumber=wavenumber(omega, spec.water_depth, spec.g),
                               water_depth=spec.water_depth, g=spec.g)
        X = np.asarray(excitation_coefficients(spec.database(), comps))
        return A_rel, np.asarray(B), X, H0

    def frequency_terms(self, model, q0, kin0, omega, heading, options):
        """−ω² Hᵀ(A(ω) − A∞)H − iω HᵀB(ω)H (A∞ is in the mass already) and Hᵀ X(ω, β), with A and
        B those of ``options["radiation"]`` ("database", or a time-domain strategy's)."""
        excitation = options.get("excitation", True)
        A_rel, B, X, H0 = self._frequency_coefficients(kin0, omega, heading, options, excitation)
        w = omega[:, None, None]
        # Hᵀ Z H as two matrix products (a three-operand einsum without a contraction order is
        # one loop over every index: Wu & Yuan's 78 dofs on 450 frequencies, 8 s against 0.1 s)
        Z = H0.T[None] @ (-w**2 * A_rel - 1j * w * B) @ H0[None]
        if X is None:
            return FrequencyTerms(impedance=Z)
        return FrequencyTerms(impedance=Z, force=np.einsum("ai,wa->wi", H0, X))

    def quadratic_drag(self, model, kin0):
        """The drag per inertial axis a at each reference point (at its rest position), for the
        spectral level's stochastic linearisation (:mod:`mfm.frequency.drag`): with ``[hydro]
        drag_flow = "relative"`` −D_a |ξ̇_a − u_a| (ξ̇_a − u_a) on the flow relative to the point,
        with ``"body"`` (the default) −D_a |ξ̇_a| ξ̇_a on its own velocity (``flow`` False: the
        linearisation :func:`mfm.optimize` makes in jax, :mod:`mfm.studies.design`). None where
        every D is 0."""
        if not np.any(np.asarray(self.drag) != 0):
            return None
        K = self.drag.shape[0]
        H0 = np.asarray(h_matrix_at(self.geometry, kin0)).reshape(K, 6, -1)[:, :3]
        pos = np.asarray(self.geometry.positions(kin0), dtype=float).reshape(K, 3)
        labels = tuple(self.dofs[6 * k].rsplit("__", 1)[0] for k in range(K))
        return QuadraticDrag(rows=H0, project=np.broadcast_to(np.eye(3), (K, 3, 3)).copy(),
                             drag=np.asarray(self.drag, dtype=float), kind="axis",
                             positions=pos, labels=labels, flow=self.flow is not None)

    def frequency_body_loads(self, model, q0, kin0, omega, heading, options, x):
        """The wave and radiation-memory loads at the reference points,

            F̂_ξ(ω) = X(ω, β) − [−ω² (A(ω) − A∞) − iω B(ω)] H₀ x̂

        (A∞ is in the mass, hydrostatics and buoyancy in the static load), as body wrenches at q₀
        (the map of :meth:`~mfm.mechanics.points.BodyPoints.to_body_wrench`, linear: real and imaginary
        parts each)."""
        A_rel, B, X, H0 = self._frequency_coefficients(kin0, omega, heading, options,
                                                       options.get("excitation", True))
        w = omega[:, None, None]
        xi = np.einsum("ai,wi->wa", H0, np.asarray(x))
        F = -np.einsum("wab,wb->wa", -w**2 * A_rel - 1j * w * B, xi)
        if X is not None:
            F = F + X
        T = np.asarray(_wrench_map(self.geometry, kin0, model.n_bodies))
        return np.einsum("nbk,wk->wnb", T, F)

    def frequency_range(self):
        om = np.asarray(self.spec.database()["omega"].values)
        return float(om[0]), float(om[-1])

    def frequency_outputs(self, model, kin0, x, omega):
        H0 = np.asarray(h_matrix_at(self.geometry, kin0))
        return {"xi_rao": (("hydro_dof",), np.einsum("ai,wi->wa", H0, x),
                           {"long_name": "hydro coordinates (reference points) RAO",
                            "units": "m/m or rad/m"}),
                "coords": {"hydro_dof": list(self.dofs)}}


def build_water(model, spec, sea, *, dt: float, duration: float, t0: float = 0.0,
                ramp: float = 0.0, radiation: str = "convolution", memory: float | None = None,
                state_space_options: dict | None = None, added_mass: str = "lhs",
                stage_offsets=(0.0, 0.5, 1.0), mean_drift=None, sampled: bool = True) -> Water:
    """The :class:`Water` load of ``model`` for one sea state and time grid.

    sea: a ``hydro.waves`` sea state (Regular, Jonswap, …) or None for still water.
    radiation: "convolution" (direct, over the memory length from the decay of K), "state_space"
    (the passive fit of hydro.statespace; its corrected A∞), or "none" (A∞ only).
    stage_offsets: the integrator's stage times as fractions of dt (RK4: 0, ½, 1): the excitation
    is tabulated so that each stage falls on a sample, and the convolution has weights per stage.
    mean_drift: with ``[hydro] drift``, a :class:`mfm.frequency.drift.MeanDrift` in place of the
    database's ``mean_drift`` (the drift of the model's own motions,
    :func:`mfm.frequency.drift.run_mean_drift`).
    sampled: with ``[hydro] nonlinear_dt``, the hull pressure sampled every nonlinear_dt / dt
    steps (:class:`HeldHulls`); False: at every evaluation (a water that serves at rest only).
    """
    from hydro.excitation import excitation_time_series
    from hydro.waves import elevation

    rad = strategy(spec, radiation, dt=dt, memory=memory, state_space_options=state_space_options,
                   stage_offsets=stage_offsets)
    nd = len(spec.dofs)
    m = grid_subdivisions(stage_offsets)
    # excitation and elevation on the stage grid, one step past the end
    n_grid = int(round(duration / dt)) * m + m + 1
    step = dt / m
    t_grid = t0 + step * np.arange(n_grid)
    if sea is None:
        exc = np.zeros((n_grid, nd))
        eta = np.zeros(n_grid)
    else:
        comps = sea.components(water_depth=spec.water_depth, g=spec.g)
        exc = excitation_time_series(spec.database(), comps, t_grid, ramp_duration=ramp)
        eta = np.asarray(elevation(comps, t_grid, ramp_duration=ramp)).reshape(-1)
    geometry = BodyPoints(body_index=spec.body_index, d_ref=device_array(spec.d_ref),
                          ref0=device_array(spec.ref0))
    C_wp, buoyancy, hulls, flow = spec.C_wp, spec.rho * spec.g * spec.volume, None, None
    comps = None if sea is None else sea.components(water_depth=spec.water_depth, g=spec.g)
    if nonlinear(spec):
        every = nonlinear_every(spec, dt) if sampled else None
        hulls = make_hulls(spec, comps, ramp)
        if every is None:
            exc = exc - froude_krylov_series(spec, comps, t_grid, ramp)
        else:
            # the tables keep the database's whole excitation: each stage takes the linear level
            # and the held excess over it (HeldHulls)
            hulls = dataclasses.replace(hulls, hold=held_hulls(
                spec, froude_krylov_coefficients(spec, comps), every))
        C_wp, buoyancy = np.zeros_like(C_wp), np.zeros_like(buoyancy)
    if relative_drag(spec):
        from hydro.wetted import WaveField, still_water

        flow = Flow(wave=still_water() if comps is None else WaveField.of(comps),
                    ramp=jnp.asarray(float(ramp)))
    drift = None
    if wave_drift(spec):
        from hydro.drift import drift_time_series

        # still water (the linearisation's loads, a decay) has no drift: no table read
        drift = _f64(np.zeros((len(t_grid), len(spec.dofs))) if comps is None else
                     drift_time_series(_drift_source(spec, mean_drift), comps, t_grid,
                                       mode=spec.drift, reference_points=spec.ref0,
                                       ramp_duration=ramp))
    return Water(geometry=geometry, A_inf=_f64(rad.added_mass_inf(spec)), C_wp=_f64(C_wp),
                 buoyancy=_f64(buoyancy), d_cob=_f64(spec.d_cob),
                 drag=_f64(spec.drag), exc_t0=_f64(t0), exc_step=_f64(step),
                 exc_values=_f64(exc), eta_values=_f64(eta), rad=rad, dofs=spec.dofs, added_mass=added_mass, spec=spec,
                 grid_m=int(m), moving=spec.moving, hulls=hulls, flow=flow, drift_values=drift)


# the attributes that put a spec above linear potential flow (set by load_hydro_spec only when
# asked, so that every other spec keeps its content key)
ABOVE_LINEAR = ("hulls", "hydrostatics", "nonlinear_dt", "drag_flow", "drift")


def linear_spec(spec):
    """A copy of ``spec`` with the linear water (no hulls, drag on the body's velocity): the same
    database, bodies and options, its own cache holding what ``spec`` has made (the radiation's
    fits and kernels, the same for both) but not its replaced copies (those carry the hulls)."""
    return _spec_copy(spec, drop=ABOVE_LINEAR)


def sampled_spec(spec, nonlinear_dt: float | None):
    """A copy of ``spec`` (at the nonlinear level) whose hull pressure is sampled every
    ``nonlinear_dt`` s (:class:`HeldHulls`), or at every evaluation (None); its caches shared as
    :func:`linear_spec`'s."""
    out = _spec_copy(spec, drop=("nonlinear_dt",))
    if nonlinear_dt is not None:
        out.nonlinear_dt = float(nonlinear_dt)
    return out


def _spec_copy(spec, drop):
    """A copy of ``spec`` without the attributes ``drop``, its own cache holding what ``spec`` has
    made but not its replaced copies (keyed ``("replace", …)``: those carry the attributes)."""
    import copy

    out = copy.copy(spec)
    for name in drop:
        out.__dict__.pop(name, None)
    out._cache = {k: v for k, v in spec._cache.items()
                  if not (isinstance(k, tuple) and k and k[0] == "replace")}
    return out


def relative_drag(spec) -> bool:
    """Whether the spec's drag acts on the velocity relative to the flow (``[hydro] drag_flow``)."""
    return getattr(spec, "drag_flow", "body") == "relative"


def _drift_source(spec, mean_drift=None):
    """What the drift is read from: the database, or the :class:`hydro.drift.DriftTable` of
    ``mean_drift`` (a :class:`mfm.frequency.drift.MeanDrift`)."""
    return spec.database() if mean_drift is None else mean_drift.table()


def require_mean_drift(db, path, what: str, *, error=ValueError, fix: str = "",
                       kochin: bool = False) -> None:
    """Refuse a database without ``mean_drift`` for ``what`` (one check behind the config's
    ``[hydro] drift`` and the equilibrium in a sea), naming the file and how to make one.
    ``kochin``: a database with the layout's Kochin functions will do (the drift of the model's
    own motions is made from them, :mod:`mfm.frequency.drift`)."""
    if kochin and "kochin_diffraction" in db and "kochin_radiation" in db:
        return
    if "mean_drift" not in db:
        raise error(
            f"{what} needs the database's mean_drift (the mean drift force per unit wave amplitude "
            f"squared), which {str(path)!r} does not have: make it with `mfm hydro` and "
            "[hydro.bem] drift = \"free\" (one wet body) or \"kochin\" (a layout: the drift of "
            f"the model's own motions), or give WAMIT output with its .8/.9 files{fix}")


def wave_drift(spec) -> bool:
    """Whether the spec's water adds the wave drift force (``[hydro] drift``)."""
    return getattr(spec, "drift", "off") != "off"


def nonlinear(spec) -> bool:
    """Whether the spec's water takes the nonlinear level (``[hydro] hydrostatics``)."""
    return getattr(spec, "hydrostatics", "linear") == "nonlinear"


def make_hulls(spec, comps, ramp: float) -> Hulls:
    """The :class:`Hulls` of the spec's hull meshes (at rest, inertial axes: ``spec.hulls``) in
    body axes about each body's CoM, with the run's wave components (None: still water)."""
    from hydro.wetted import WaveField, soa, still_water

    com0 = np.asarray(spec.ref0) - np.asarray(spec.d_ref)
    tri = tuple(soa(np.asarray(T) - com0[k]) for k, T in enumerate(spec.hulls))
    wave = still_water() if comps is None else WaveField.of(comps)
    return Hulls(tri=tri, wave=wave, ramp=jnp.asarray(float(ramp)), rho=float(spec.rho),
                 g=float(spec.g))


def nonlinear_every(spec, dt: float) -> int | None:
    """The steps between two samples of the hull pressure, ``[hydro] nonlinear_dt`` / dt (None:
    at every evaluation). Refused unless nonlinear_dt is a whole multiple of the run's dt."""
    ndt = getattr(spec, "nonlinear_dt", None)
    if ndt is None:
        return None
    dt = float(dt)
    k = int(round(ndt / dt))
    if k < 1 or abs(k * dt - ndt) > 1e-9 * ndt:
        lo, hi = max(1, int(ndt // dt)), max(1, int(ndt // dt)) + 1
        raise ValueError(
            f"hydro.nonlinear_dt: {ndt!r} s is not a whole multiple of the run's dt {dt!r} s: "
            f"the hull pressure is sampled at the end of a step; give nonlinear_dt = "
            f"{lo * dt:.6g} or {hi * dt:.6g} s ({lo} or {hi} steps), or a dt that divides it")
    return k


def held_hulls(spec, X_fk, every: int) -> "HeldHulls":
    """The :class:`HeldHulls` of ``spec`` sampled every ``every`` steps, ``X_fk`` (J, 6K) complex
    (or (B, J, 6K) for a batch) the hulls' linear Froude–Krylov coefficients at the run's
    components (:func:`froude_krylov_coefficients`)."""
    X_fk = np.asarray(X_fk, complex)
    return HeldHulls(C_wp=_f64(spec.C_wp), buoyancy=_f64(spec.rho * spec.g * spec.volume),
                     d_cob=_f64(spec.d_cob), fk_re=_f64(X_fk.real.copy()),
                     fk_im=_f64(X_fk.imag.copy()), every=int(every))


def froude_krylov_coefficients(spec, comps) -> np.ndarray:
    """The hulls' linear Froude–Krylov force per metre of amplitude at each component, (J, 6K)
    complex, about each body's reference point at rest (:func:`hydro.wetted.froude_krylov_linear`
    at the component's k and heading); (0, 6K) in still water."""
    if comps is None or len(comps.omega) == 0:
        return np.zeros((0, 6 * len(spec.hulls)), complex)
    return _froude_krylov_at(spec, comps.wavenumber, comps.heading)


def _froude_krylov_at(spec, wavenumber, heading) -> np.ndarray:
    """X_FK (J, 6K) complex of every hull at the wavenumbers and headings (J,)."""
    from hydro.wetted import froude_krylov_linear

    return np.concatenate([froude_krylov_linear(T, spec.ref0[k], wavenumber, heading,
                                                water_depth=spec.water_depth, rho=spec.rho,
                                                g=spec.g)
                           for k, T in enumerate(spec.hulls)], axis=1)


def froude_krylov_series(spec, comps, t, ramp: float) -> np.ndarray:
    """The linear Froude–Krylov force of the hulls at rest, (len(t), 6K): what the nonlinear
    level takes out of the database's excitation (its tables keep the diffraction), so that in
    small waves the two add up to the database's (:func:`hydro.wetted.froude_krylov_linear` at
    each component's k and heading: no interpolation)."""
    from hydro.waves import _harmonic_sum, ramp as ramp_of

    t = np.asarray(t, float)
    if comps is None or len(comps.omega) == 0:
        return np.zeros((len(t), 6 * len(spec.hulls)))
    X = froude_krylov_coefficients(spec, comps)                             # (J, 6K)
    out = _harmonic_sum(np.asarray(comps.omega, float), comps.complex_amplitude[:, None] * X, t)
    return out * ramp_of(t, ramp)[:, None] if ramp else out


def excitation_table(spec):
    """The spec's excitation X(ω, β) made ready for interpolation
    (:class:`hydro.excitation.ExcitationTable`), made once and kept with the spec's other caches."""
    from hydro.excitation import ExcitationTable

    if "excitation_table" not in spec._cache:
        spec._cache["excitation_table"] = ExcitationTable(spec.database())
    return spec._cache["excitation_table"]


class WaveSum(eqx.Module):
    """The wave tables of a :class:`Water` as what makes them: the sums

        y(t_k) = r(t_k) Re Σ_j c_j e^{−iω_j t_k},   t_k = t0 + k·step,  k = 0 … n_grid − 1,

    whose columns are the excitation (c_j = a_j e^{iφ_j} X(ω_j, β_j), N or N m; 0 for a
    component outside the database's ω grid) and, last, the elevation at the origin
    (c_j = a_j e^{iφ_j}, m); r the start-up ramp of ``hydro.waves.ramp`` over ``ramp`` s (none at
    0). Per component (n_c,): ``omega`` rad/s, the complex amplitude a_j e^{iφ_j} as ``amp_re``,
    ``amp_im`` (m), ``active`` (1, or 0 outside the grid) and where it falls on the excitation
    table (:meth:`hydro.excitation.ExcitationTable.brackets`: ``i0``, ``k0``, ``k1``, ``sw``,
    ``sb``); X itself comes from the table's polar form, handed to :meth:`tables` (one for every
    case). With a leading case axis on every array, the tables of many cases: made on the device
    (:meth:`tables`), a batch's tables never pass through the host, and its cases carry ~10³
    numbers each instead of n_grid × n_dof (15 MB for 20,000 steps of M4 134)."""
    omega: jnp.ndarray
    amp_re: jnp.ndarray
    amp_im: jnp.ndarray
    active: jnp.ndarray
    i0: jnp.ndarray
    k0: jnp.ndarray
    k1: jnp.ndarray
    sw: jnp.ndarray
    sb: jnp.ndarray
    t0: jnp.ndarray
    step: jnp.ndarray
    ramp: jnp.ndarray
    n_grid: int = eqx.field(static=True)
    one_heading: bool = eqx.field(static=True)
    # the excitation columns made (None: all); the others are 0. A run that records no output
    # of the water reads only the moved dofs' (Water._forces), so a batch makes those alone
    columns: tuple | None = eqx.field(static=True, default=None)
    # the nonlinear level: the hulls' linear Froude–Krylov coefficients X_FK (n_c, n_dof), real
    # and imaginary parts, taken out of the excitation's (its tables keep the diffraction, as
    # build_water's); None: the linear level
    fk_re: jnp.ndarray | None = None
    fk_im: jnp.ndarray | None = None
    # the wave drift force ([hydro] drift): "mean" (``drift_mean`` (n_dof,), Σ_j D_j a_j²) or
    # "newman" (``drift_re``, ``drift_im`` (n_c, n_dof): c_j s_j √|D_j|, ``drift_sign``
    # sgn D_j: hydro.drift's S and S₊); None: none
    drift: str | None = eqx.field(static=True, default=None)
    drift_mean: jnp.ndarray | None = None
    drift_re: jnp.ndarray | None = None
    drift_im: jnp.ndarray | None = None
    drift_sign: jnp.ndarray | None = None

    def coefficients(self, polar, xp=jnp):
        """(c_re, c_im) (n_c, n_cols + 1): the excitation columns a e^{iφ} X(ω, β) (those of
        ``columns``), X by :func:`hydro.excitation.polar_interpolation` from ``polar``, then the
        elevation's a e^{iφ}."""
        from hydro.excitation import polar_interpolation

        if self.columns is not None:
            polar = tuple(a[..., list(self.columns)] for a in polar)
        X = polar_interpolation(xp, polar, self.i0, self.k0, self.k1, self.sw, self.sb,
                                one_heading=self.one_heading)
        a = (self.amp_re + 1j * self.amp_im)[:, None]
        if self.fk_re is None:
            c = xp.concatenate([a * X * self.active[:, None], a], axis=1)
        else:
            # the nonlinear level: the tables keep the diffraction, X − X_FK (every component's
            # X_FK, as froude_krylov_series: it is not the table's, so none is outside a grid)
            fk = self.fk_re + 1j * self.fk_im
            fk = fk if self.columns is None else fk[:, list(self.columns)]
            c = xp.concatenate([a * (X * self.active[:, None] - fk), a], axis=1)
        return xp.real(c), xp.imag(c)

    def tables(self, polar):
        """(exc (n_grid, n_dof), eta (n_grid,)) of one case, in jax, and with a drift
        (``drift``) its table (n_grid, n_dof) third: the uniform-grid form of
        :func:`hydro.waves._harmonic_sum` (:meth:`_sums`), so the numbers equal build_water's
        numpy tables to round-off."""
        c_re, c_im = self.coefficients(polar)
        y = self._sums(c_re, c_im)
        r = self._ramp()
        out = (self._placed(jnp, y[:, :-1] * r[:, None], polar[0].shape[-1]), y[:, -1] * r)
        return out if self.drift is None else out + (self._drift_table(r),)

    def _sums(self, c_re, c_im):
        """Re Σ_j c_j e^{−iω_j t_k} (n_grid, n_cols) for coefficients (n_c, n_cols), in jax: the
        block form of :func:`hydro.waves._harmonic_sum` (e^{−iω(t0 + (aK + b)h)} = e^{−iω b h} ·
        e^{−iω(t0 + aKh)}: sines and cosines of K × n_c and n_blocks × n_c phases, each from its
        own product ω·time, then real matrix products)."""
        # blocks of 256 rows, as the numpy route (fewer rows per block make the sines and cosines
        # fewer, (K + n/K) × n_c, but the matrix products slower: K = √n measured 1.7–1.9× slower
        # for M4 134's 401 and 4,001 rows on one CPU core)
        n, K = self.n_grid, min(256, self.n_grid)
        nb = -(-n // K)
        w = self.omega
        kh = self.step * jnp.arange(K)
        ck, sk = jnp.cos(kh[:, None] * w[None, :]), jnp.sin(kh[:, None] * w[None, :])
        ph = w[None, :] * (self.t0 + (K * self.step) * jnp.arange(nb))[:, None]   # (nb, n_c)
        rr, ri = jnp.cos(ph), -jnp.sin(ph)             # e^{−iω(t0 + aKh)}
        cr = c_re[None] * rr[:, :, None] - c_im[None] * ri[:, :, None]
        ci = c_re[None] * ri[:, :, None] + c_im[None] * rr[:, :, None]
        y = (jnp.einsum("bj,ajm->abm", ck, cr) + jnp.einsum("bj,ajm->abm", sk, ci))
        return y.reshape(nb * K, -1)[:n]

    def _ramp(self):
        """r(t_k) (n_grid,): :func:`hydro.waves.ramp` over ``ramp`` s (1 at 0), in jax."""
        t = self.t0 + self.step * jnp.arange(self.n_grid)
        T = self.ramp
        return jnp.where(T > 0.0, jnp.where(t < 0.0, 0.0, 0.5 * (1.0 - jnp.cos(
            jnp.pi * jnp.clip(t, 0.0, T) / jnp.where(T > 0.0, T, 1.0)))), 1.0)

    def _drift_parts(self):
        """Newman's four sums' coefficients (n_c, 4 n_dof), real and imaginary parts: S's c,
        then −i c (Im S = Re Σ (−i c) e^{−iωt}), then S₊'s sgn(D) c and −i sgn(D) c."""
        dr, di, sg = self.drift_re, self.drift_im, self.drift_sign
        return ((dr, di, sg * dr, sg * di), (di, -dr, sg * di, -sg * dr))

    def _drift_table(self, r):
        """The drift force (n_grid, n_dof) of :func:`hydro.drift.drift_time_series`: r(t) Σ_j
        D_j a_j² ("mean"), or r(t) Re[S₊(t) conj S(t)] = r (Re S₊ Re S + Im S₊ Im S)
        ("newman")."""
        if self.drift == "mean":
            return r[:, None] * self.drift_mean[None, :]
        re, im = self._drift_parts()
        y = self._sums(jnp.concatenate(re, axis=1), jnp.concatenate(im, axis=1))
        S_re, S_im, P_re, P_im = jnp.split(y, 4, axis=1)
        return (P_re * S_re + P_im * S_im) * r[:, None]

    def _placed(self, xp, exc, n_dof):
        """The made columns in a table of every dof (the others 0)."""
        if self.columns is None:
            return exc
        if xp is np:
            out = np.zeros((exc.shape[0], n_dof))
            out[:, list(self.columns)] = exc
            return out
        # a static 0/1 matrix, not a scatter (as the water's own placements)
        P = (np.arange(n_dof)[None, :] == np.asarray(self.columns)[:, None]).astype(float)
        return exc @ P

    def tables_numpy(self, polar):
        """:meth:`tables` of one case on the host, by build_water's own numpy route (hydro.waves,
        hydro.drift)."""
        from hydro.waves import _harmonic_sum, ramp as ramp_fn

        c_re, c_im = self.coefficients(polar, xp=np)
        t = float(self.t0) + float(self.step) * np.arange(self.n_grid)
        w = np.asarray(self.omega)
        y = _harmonic_sum(w, c_re + 1j * c_im, t)
        r = ramp_fn(t, float(self.ramp)) if float(self.ramp) else np.ones_like(t)
        if float(self.ramp):
            y = y * r[:, None]
        out = (self._placed(np, y[:, :-1], np.shape(polar[0])[-1]), y[:, -1])
        if self.drift is None:
            return out
        if self.drift == "mean":
            return out + (r[:, None] * np.asarray(self.drift_mean)[None, :],)
        re, im = (np.concatenate([np.asarray(x) for x in p], axis=1) for p in self._drift_parts())
        S_re, S_im, P_re, P_im = np.split(_harmonic_sum(w, re + 1j * im, t), 4, axis=1)
        return out + ((P_re * S_re + P_im * S_im) * r[:, None],)


def build_water_batch(model, spec, seas, *, dts, ramps, n_steps: int, t0: float = 0.0,
                      radiation: str = "convolution", memory: float | None = None,
                      state_space_options: dict | None = None, added_mass: str = "lhs",
                      stage_offsets=(0.0, 0.5, 1.0), mean_drift=None):
    """The :class:`Water` of B cases at once (a batch's seas, time steps and ramps, each run
    ``n_steps`` steps): ``(water, batched, waves, polar)``. ``water`` is one Water whose fields
    that differ between the cases carry a leading case axis (``batched``: a pytree of bools like
    it, True on those fields), its tables left out (None): ``waves``, a :class:`WaveSum` with a
    leading case axis, makes them (:meth:`WaveSum.tables`, on the device) with the excitation
    table's polar form ``polar`` (shared by every case). Case b's water, its
    tables made, is the one :func:`build_water` makes for ``seas[b]``, ``dts[b]``, ``ramps[b]``
    to round-off (tests/test_batch_prepare.py, tests/test_batch_nonlinear.py).

    Above linear, each case's water carries its own sea's components (B, n_c) where the time step
    reads them: the nonlinear level's ``hulls.wave`` (the wave pressure on the cut hulls; the
    tables then hold X − X_FK, X_FK the hulls' linear Froude–Krylov force at each case's
    components, :func:`_froude_krylov_many`), the relative drag's ``flow.wave``, each with the
    case's ramp; the wave drift's table (n, 6K) is made on the device with the others
    (:meth:`WaveSum._drift_table`: r Σ_j D_j a_j², or Newman's r Re[S₊ S̄]), its coefficients from
    :func:`_drift_coefficients`.

    What the cases share is made once: the radiation strategy for every distinct time step
    (:func:`~mfm.loads.radiation.strategy_many`: only its arrays that follow dt get a case axis)
    and X(ω, β) sorted once
    (:func:`excitation_table`), every case's wave components placed on it in one call; the
    interpolation of X at the components and the tables are the device's.
    Cases with fewer wave components than the most are padded with zero coefficients and zero
    amplitudes (a term 0 · cos = 0 exactly; the wave fields' padding has a wavenumber of 1 rad/s,
    so the depth decays stay finite), still water is all padding: one structure for the batch,
    whatever its seas. Raises ValueError when the cases' radiation differs in structure (a
    convolution's number of lags follows dt)."""
    B = len(seas)
    dts = np.broadcast_to(np.asarray(dts, dtype=float), (B,))
    ramps = np.broadcast_to(np.asarray(ramps, dtype=float), (B,))
    uniq = np.unique(dts)
    stacked = strategy_many(spec, radiation, dts, memory=memory,
                            state_space_options=state_space_options, stage_offsets=stage_offsets)
    if stacked is None:
        raise ValueError("simulate_batch: the cases' loads differ in structure (with "
                         "radiation='convolution' the number of lags follows dt: give every case "
                         "the same dt and memory, or use radiation='state_space')")
    rad, rad_batched = stacked
    m = grid_subdivisions(stage_offsets)
    # the grid of build_water: excitation and elevation on the stage grid, one step past the end
    n_grids = {int(round(n_steps * float(d) / float(d))) * m + m + 1 for d in uniq}
    if len(n_grids) != 1:
        raise ValueError(f"n_steps={n_steps}: the time steps {uniq} give tables of different "
                         "lengths; give one n_steps that each dt divides the duration of")
    n_grid = n_grids.pop()
    steps = dts / m
    live = [i for i, sea in enumerate(seas) if sea is not None]
    comps = components_many([seas[i] for i in live], water_depth=spec.water_depth, g=spec.g)
    table = excitation_table(spec)
    outside, br = table.brackets_many(comps)
    n_c = max([len(c) for c in comps] + [1])
    # per case and component (padding: a zero amplitude, so 0 · cos = 0 exactly)
    arrays = {k: np.zeros((B, n_c), dtype=int if k in ("i0", "k0", "k1") else float)
              for k in ("amp_re", "amp_im", "active", "i0", "k0", "k1", "sw", "sb")}
    omega = np.ones((B, n_c))
    for j, (c, i) in enumerate(zip(comps, live)):
        n = len(c)
        a = c.complex_amplitude
        omega[i, :n] = c.omega
        arrays["amp_re"][i, :n], arrays["amp_im"][i, :n] = a.real, a.imag
        arrays["active"][i, :n] = ~outside[j]
        for name, values in zip(("i0", "k0", "k1", "sw", "sb"), br):
            arrays[name][i, :n] = values[j]
    every = None
    if nonlinear(spec):
        steps_between = {nonlinear_every(spec, float(d)) for d in uniq}
        if len(steps_between) != 1:
            raise ValueError(f"hydro.nonlinear_dt: {spec.nonlinear_dt!r} s is {sorted(steps_between)} "
                             f"steps of the cases' time steps {uniq}: the steps between two "
                             "samples of the hull pressure are one structure for the batch; give "
                             "every case the same dt")
        every = steps_between.pop()
    above = _above_linear_batch(spec, comps, live, B, n_c, omega, mean_drift,
                                fk_in_tables=every is None)
    waves = WaveSum(omega=omega, **arrays, t0=np.full(B, float(t0)), step=steps.copy(),
                    ramp=ramps.copy(), n_grid=n_grid, one_heading=table.beta.shape[0] == 1,
                    **above["waves"])
    geometry = BodyPoints(body_index=spec.body_index, d_ref=device_array(spec.d_ref),
                          ref0=device_array(spec.ref0))
    C_wp, buoyancy, hulls, flow = spec.C_wp, spec.rho * spec.g * spec.volume, None, None
    field = above.get("field")
    if nonlinear(spec):
        # the hulls' pressure in place of the buoyancy, C_wp and the Froude–Krylov part (as
        # build_water), each case's sea in its wave field
        C_wp, buoyancy = np.zeros_like(C_wp), np.zeros_like(buoyancy)
        hulls = dataclasses.replace(make_hulls(spec, None, 0.0), wave=field, ramp=ramps.copy())
        if every is not None:
            hulls = dataclasses.replace(hulls, hold=held_hulls(spec, above["fk"], every))
    if relative_drag(spec):
        flow = Flow(wave=field, ramp=ramps.copy())
    water = Water(geometry=geometry, A_inf=_f64(rad.added_mass_inf(spec)),
                  C_wp=_f64(C_wp),
                  buoyancy=_f64(buoyancy), d_cob=_f64(spec.d_cob),
                  drag=_f64(spec.drag), exc_t0=_f64(t0), exc_step=steps.copy(),
                  exc_values=None, eta_values=None, rad=rad, dofs=spec.dofs,
                  added_mass=added_mass, spec=spec, grid_m=int(m), moving=spec.moving,
                  hulls=hulls, flow=flow)
    batched = jax.tree_util.tree_map(lambda _: False, water)
    # what follows dt has the case axis whatever the values: one compilation for every batch
    batched = eqx.tree_at(lambda w: (w.exc_step, w.rad), batched, (True, rad_batched))
    # so has each case's sea, where the water reads it at the time step (the hulls' wave
    # pressure, the relative flow): a wave field (B, n_c) and the ramp (B,)
    each = jax.tree_util.tree_map(lambda _: True, field)
    if hulls is not None:
        batched = eqx.tree_at(lambda w: (w.hulls.wave, w.hulls.ramp), batched, (each, True))
        if hulls.hold is not None:
            batched = eqx.tree_at(lambda w: (w.hulls.hold.fk_re, w.hulls.hold.fk_im), batched,
                                  (True, True))
    if flow is not None:
        batched = eqx.tree_at(lambda w: (w.flow.wave, w.flow.ramp), batched, (each, True))
    return water, batched, waves, tuple(jnp.asarray(a) for a in table.polar)


# components of the hulls' linear Froude–Krylov force made in one numpy call (the panels' midpoints
# × components complex table: 2,600 facets × 6 midpoints × 64 components, 16 MB)
FK_CHUNK = 64


def _above_linear_batch(spec, comps, live, B: int, n_c: int, omega, mean_drift=None,
                        fk_in_tables: bool = True) -> dict:
    """What the above-linear options add to a batch (``comps``: the components of the cases
    ``live``, each padded to ``n_c`` with zero amplitudes, as :class:`WaveSum`'s; ``omega``
    (B, n_c) its frequencies, 1 rad/s on the padding): ``"waves"``, the :class:`WaveSum` fields
    (the hulls' X_FK of the nonlinear level, taken out of the tables unless ``fk_in_tables`` is
    False: the held level's tables keep the whole excitation; the drift's coefficients);
    ``"fk"`` (B, n_c, 6K) complex, the X_FK of each case's components (nonlinear level);
    ``"field"``, a
    :class:`hydro.wetted.WaveField` (B, n_c) of each case's components for the hulls and the
    relative flow (None when neither). A padded component has amplitude 0 and a wavenumber of
    its 1 rad/s (finite, positive: the depth decays stay finite), so every term it adds to a sum
    is 0 exactly."""
    from hydro.waves import wavenumber
    from hydro.wetted import WaveField

    out = {"waves": {}, "field": None}
    nd = len(spec.dofs)
    if nonlinear(spec) or relative_drag(spec):
        cols = {k: np.zeros((B, n_c)) for k in ("amplitude", "wavenumber", "heading", "phase")}
        cols["wavenumber"][:] = wavenumber(1.0, spec.water_depth, spec.g)
        for c, i in zip(comps, live):
            n = len(c.omega)
            for k in cols:
                cols[k][i, :n] = np.asarray(getattr(c, k), float)
        out["field"] = WaveField(cols["amplitude"], np.array(omega, float), cols["wavenumber"],
                                 cols["heading"], cols["phase"], float(spec.water_depth))
    if nonlinear(spec):
        fk = np.zeros((B, n_c, nd), complex)
        for c, i, X in zip(comps, live, _froude_krylov_many(spec, comps)):
            fk[i, :len(c.omega)] = X
        out["fk"] = fk
        if fk_in_tables:
            out["waves"].update(fk_re=fk.real.copy(), fk_im=fk.imag.copy())
    if wave_drift(spec):
        out["waves"].update(_drift_coefficients(spec, comps, live, B, n_c, mean_drift))
    return out


def _froude_krylov_many(spec, comps) -> list:
    """Each case's X_FK (J_i, 6K) of :func:`froude_krylov_series` (the hulls at rest,
    :func:`hydro.wetted.froude_krylov_linear` at each component's k and heading), the distinct
    (k, β) of every case made once, :data:`FK_CHUNK` at a time."""
    counts = [len(c.omega) for c in comps]
    if not sum(counts):
        return [np.zeros((0, len(spec.dofs)), complex) for _ in comps]
    kb = np.stack([np.concatenate([np.asarray(c.wavenumber, float) for c in comps]),
                   np.concatenate([np.asarray(c.heading, float) for c in comps])], axis=1)
    pairs, inverse = np.unique(kb, axis=0, return_inverse=True)
    X = np.concatenate([_froude_krylov_at(spec, pairs[j:j + FK_CHUNK, 0],
                                          pairs[j:j + FK_CHUNK, 1])
                        for j in range(0, len(pairs), FK_CHUNK)])
    return np.split(X[np.asarray(inverse).reshape(-1)], np.cumsum(counts)[:-1])


def drift_table(spec):
    """The spec's mean drift D(ω, β) made ready for interpolation
    (:class:`hydro.drift.DriftTable`), made once and kept with the spec's other caches."""
    from hydro.drift import DriftTable

    if "drift_table" not in spec._cache:
        spec._cache["drift_table"] = DriftTable(spec.database())
    return spec._cache["drift_table"]


def _drift_coefficients(spec, comps, live, B: int, n_c: int, mean_drift=None) -> dict:
    """The :class:`WaveSum` drift fields of the cases (:func:`hydro.drift.drift_time_series`'s
    terms, the same numpy per case; D_j at every case's components in one interpolation):
    "mean": Σ_j D_j a_j² (B, n_dof); "newman": c_j s_j √|D_j| and sgn D_j (B, n_c, n_dof), 0 on
    the padding (and for still water)."""
    import types

    table = drift_table(spec) if mean_drift is None else mean_drift.table()
    nd = len(table.labels)
    if nd != len(spec.dofs):
        raise ValueError(f"hydro.drift: the database's mean_drift has {nd} dofs "
                         f"{table.labels}, the water {len(spec.dofs)} {list(spec.dofs)}")
    counts = [len(c.omega) for c in comps]
    both = types.SimpleNamespace(
        omega=np.concatenate([np.asarray(c.omega, float) for c in comps] + [np.zeros(0)]),
        heading=np.concatenate([np.asarray(c.heading, float) for c in comps] + [np.zeros(0)]))
    Ds = np.split(table.at(both), np.cumsum(counts)[:-1]) if comps else []
    if spec.drift == "mean":
        mean = np.zeros((B, nd))
        for c, i, D in zip(comps, live, Ds):
            a = np.asarray(c.amplitude, float)
            mean[i] = (D * (a * a)[:, None]).sum(0)
        return {"drift": "mean", "drift_mean": mean}
    re, im, sign = (np.zeros((B, n_c, nd)) for _ in range(3))
    ref = np.repeat(np.asarray(spec.ref0, float)[:, :2], 6, axis=0)[:nd]          # per dof
    for c, i, D in zip(comps, live, Ds):
        n = len(c.omega)
        k, beta = np.asarray(c.wavenumber, float), np.asarray(c.heading, float)
        s = np.exp(1j * (np.multiply.outer(k * np.cos(beta), ref[:, 0])
                         + np.multiply.outer(k * np.sin(beta), ref[:, 1])))
        cj = c.complex_amplitude[:, None] * s * np.sqrt(np.abs(D))
        re[i, :n], im[i, :n], sign[i, :n] = cj.real, cj.imag, np.sign(D)
    return {"drift": "newman", "drift_re": re, "drift_im": im, "drift_sign": sign}


def _assignment_rows(by_name, wet):
    """Rows (config name, database body or bodies, mass, CoM) for the check that each body got its
    own hull's data. A massless hull welded to a parent (mass 0: its parent carries its mass) is
    checked together with the nearest ancestor that has a mass: their masses against the sum of
    their hulls' volumes, the ancestor's CoM against the volume-weighted centre of buoyancy."""
    rows = {}
    for name, d, _ in wet:
        owner = name
        while by_name[owner].mass == 0 and by_name[owner].parent is not None:
            owner = by_name[owner].parent
        rows.setdefault(owner, []).append(d)
    return [(owner, tuple(ds) if len(ds) > 1 else ds[0], by_name[owner].mass, by_name[owner].com)
            for owner, ds in rows.items()]


def load_hydro_spec(model, bodies, options: dict, config_dir: Path, body_coupling: bool | None = None):
    """Build a model's :class:`~hydro.prepare.HydroSpec` from the parsed ``[hydro]`` table."""
    from hydro.checks import check_body_assignment
    from hydro.database import HydroDatabaseWarning, select_bodies
    from hydro.prepare import HydroSpec, open_any_database

    from ..errors import ConfigError

    path = Path(options["database"])
    relative = not path.is_absolute()
    if relative:
        path = Path(config_dir) / path
    phases.say(f"reading the hydro database {path.name}")
    try:
        db = open_any_database(path, names=options.get("names"), rho=options.get("rho"),
                               g=options.get("g"))
    except FileNotFoundError:
        # open_any_database knows every form a database takes (a WAMIT stem among them); where it
        # finds none and the path itself is missing, say what the path is relative to
        if not relative or path.exists():
            raise
        raise FileNotFoundError(
            f"hydro.database: {options['database']!r} is relative to the config's folder "
            f"{str(config_dir)!r}: {os.path.normpath(path)!r} not found (a config copied to "
            "another folder keeps its relative path); give the path from the config's folder, "
            "an absolute path, or copy the database beside the config") from None
    available = [str(b) for b in db["body"].values]
    tagged = [(b.name, b.extra["hydro"]) for b in bodies if "hydro" in b.extra]
    if tagged:
        wet = [(name, h["body"], h["drag"]) for name, h in tagged]
    else:
        wet = [(b.name, b.name, np.zeros(3)) for b in bodies if b.name in available]
        # matched by name: a database body left over while a config body found none is most
        # likely one of them renamed (the config body would run dry: a silent wrong answer)
        unused = [d for d in available if d not in {b.name for b in bodies}]
        dry = [b.name for b in bodies if b.name not in available]
        if wet and unused and dry:
            raise ConfigError(
                f"hydro: database bodies {unused} are used by no config body, and config bodies "
                f"{dry} are not in the database {str(path)!r} (bodies {available}): a body "
                "renamed? Bodies are matched by name; give each wet body a [bodies.hydro] table "
                "with body = \"<database name>\" (with such tables, bodies without one are dry)")
    named = {db_name for _, db_name, _ in wet}
    extra = [d for d in available if d not in named]
    if wet and extra:
        # solved with the others, so its presence is in their A, B and X; but it does not move
        # here: a body of the device left out of the config by mistake would run held fixed
        warnings.warn(f"hydro: database bodies {extra} of {str(path)!r} are named by no config "
                      "body: they are held fixed in the water (the others' coefficients include "
                      "their presence, as solved). If they belong to the device, add them to the "
                      "config (matched by name, or [bodies.hydro] body = \"<database name>\")",
                      HydroDatabaseWarning, stacklevel=4)
    if not wet:
        raise ValueError(f"hydro: no config body is in the database {str(path)!r} (database bodies "
                         f"{available}, config bodies {[b.name for b in bodies]}); give each wet "
                         "body a [bodies.hydro] table with body = \"<database name>\"")
    seen = {}
    for name, db_name, _ in wet:
        if db_name in seen:
            raise ConfigError(f"hydro: bodies {seen[db_name]!r} and {name!r} both name the database "
                              f"body {db_name!r}; each wet body needs its own hull's data (its "
                              f"added mass, excitation and hydrostatics at its own place): give "
                              f"{name!r} its own [bodies.hydro] body, one of {available}")
        seen[db_name] = name
    missing = [db_name for _, db_name, _ in wet if db_name not in available]
    if missing:
        raise ValueError(f"hydro: database bodies {missing} named by the config are not in "
                         f"{str(path)!r}; available: {available}")
    db = select_bodies(db, [db_name for _, db_name, _ in wet])
    # each config body got its own hull's data: volumes and centres of buoyancy against the
    # config's masses and centres of mass (hydro.names in the wrong order is an error)
    by_name = {b.name: b for b in bodies}
    for f in check_body_assignment(db, _assignment_rows(by_name, wet), rho=options.get("rho")):
        if f.kind == "swap":
            raise ConfigError(f"hydro: {f}")
        warnings.warn(str(f), HydroDatabaseWarning, stacklevel=3)
    idx = [model.body_index(name) for name, _, _ in wet]
    com0 = np.asarray(model.com)[idx]
    coupling = options.get("body_coupling", True) if body_coupling is None else body_coupling
    if not isinstance(coupling, bool):
        raise ValueError(f"body_coupling: {coupling!r}; accepted: True, False or None (the config's "
                         "hydro.body_coupling)")
    phases.say("the hydro dofs the joints move (H(q), compiled once per model structure)")
    moving = moving_dofs(model, idx, np.asarray(db["reference_point"].values) - com0)
    spec = HydroSpec(db, idx, [name for name, _, _ in wet], com0, np.stack([d for _, _, d in wet]),
                     body_coupling=coupling, added_mass_inf=options.get("added_mass_inf", "consistent"),
                     source=str(path), moving=moving)
    if options.get("hydrostatics", "linear") == "nonlinear":
        attach_hulls(spec, [by_name[name] for name, _, _ in wet], config_dir)
        if options.get("nonlinear_dt") is not None:
            # set only when asked (the spec's content key); checked against each run's dt
            # where the water is built (nonlinear_every)
            spec.nonlinear_dt = float(options["nonlinear_dt"])
    if options.get("drag_flow", "body") == "relative":
        # set only when asked: every other spec keeps its content key (fingerprint) as before
        spec.drag_flow = "relative"
    if options.get("drift", "off") != "off":
        require_mean_drift(db, path, f"hydro.drift: {options['drift']!r}", error=ConfigError,
                           fix="; or remove hydro.drift", kochin=True)
        spec.drift = options["drift"]       # set only when asked (the spec's content key)
    return spec


# the nonlinear level's hull against its database body: a hull whose volume or centre of buoyancy
# at rest is this far from the database's is another hull (or another draft, or misplaced). 3 %:
# the default panels' facets cost 0.6 % of a sphere's volume, and two meshes of one hull agree
# far better than that; a hull of the wrong size or place is off by much more
HULL_VOLUME_RTOL = 0.03
HULL_COB_RTOL = 0.03


def attach_hulls(spec, bodies, config_dir=None) -> None:
    """Give ``spec`` (its bodies ``bodies``, config BodySpecs in the spec's order) the nonlinear
    level: each body's closed hull (``[bodies.hull]``, :func:`hydro.wetted.hull_mesh`: an analytic
    shape, the body's geometry, or a mesh file read from ``config_dir``), checked closed,
    manifold and outward, its still-water volume and centre of buoyancy against the database's
    (:data:`HULL_VOLUME_RTOL`, :data:`HULL_COB_RTOL` of V^{1/3}): ``spec.hulls`` (triangles at
    rest, inertial axes) and ``spec.hydrostatics = "nonlinear"``. Every path (shape, geometry,
    mesh) passes the same checks here."""
    from hydro.wetted import check_hull, hull_mesh, submerged_volume, triangles

    from ..errors import ConfigError

    hulls = []
    cob_db = np.asarray(spec.db["center_of_buoyancy"].values, dtype=float)
    for k, b in enumerate(bodies):
        where = f"bodies ({b.name!r}).hull"
        if "hull" not in b.extra:
            raise ConfigError(
                f"{where}: missing; hydro.hydrostatics = \"nonlinear\" integrates the pressure over "
                "each wet body's instantaneous wetted hull, so each needs its closed hull, above "
                "the water line too: a [bodies.hull] table such as { shape = \"cylinder\", "
                "radius = 3.0, bottom = -5.0, top = 2.0 } (shapes: sphere, cylinder, box, "
                "revolution, geometry), or { mesh = \"hull.stl\" } (a mesh file of the closed "
                "hull: WAMIT .gdf, NEMOH .dat, STL)")
        h = b.extra["hull"]
        if "mesh" in h:
            where = f"{where}.mesh {h['mesh']!r}"
        elif h.get("shape") == "geometry" and (b.extra.get("hull_geometry") or {}).get("shape") \
                == "mesh":
            where = f"{where} (the body's mesh file {b.extra['hull_geometry'].get('file')!r})"
        try:
            V, F = hull_mesh(h, where=f"bodies ({b.name!r}).hull",
                             geometry=b.extra.get("hull_geometry"), base=config_dir)
        except ValueError as e:
            raise ConfigError(str(e)) from None
        T = triangles(V, F)
        try:
            check_hull(T, what=where)
        except ValueError as e:
            raise ConfigError(str(e)) from None
        vol, cob = submerged_volume(jnp.asarray(T), jnp.eye(3), jnp.zeros(3))
        vol, cob = float(vol), np.asarray(cob)
        v_db = float(spec.volume[k])
        size = abs(v_db) ** (1 / 3)
        if abs(vol / v_db - 1) > HULL_VOLUME_RTOL or \
                np.linalg.norm(cob - cob_db[k]) > HULL_COB_RTOL * size:
            raise ConfigError(
                f"{where}: at rest it displaces {vol:.6g} m³ with its centre of buoyancy at "
                f"({cob[0]:.4g}, {cob[1]:.4g}, {cob[2]:.4g}) m, the database body "
                f"{spec.db_names[k]!r} {v_db:.6g} m³ at ({cob_db[k][0]:.4g}, {cob_db[k][1]:.4g}, "
                f"{cob_db[k][2]:.4g}) m (tolerances {HULL_VOLUME_RTOL:.0%} of the volume, "
                f"{HULL_COB_RTOL:.0%} of V^(1/3) = {HULL_COB_RTOL * size:.3g} m; the centres "
                f"{np.linalg.norm(cob - cob_db[k]):.3g} m apart): not the same hull at the same "
                "place; give the hull's dimensions and center in the config's axes at rest")
        hulls.append(T)
    spec.hulls = tuple(hulls)
    spec.hydrostatics = "nonlinear"


@jax.jit
def _h_samples(model, geo, qs):
    """H(q) at each row of qs, in one compiled call (op by op, the tree walk was ~180 small
    compilations: 8 s of loading M4 134); compiled once per model structure."""
    from ..mechanics.kinematics import kinematics

    return jax.vmap(lambda q: geo.h_matrix(kinematics(model, q, jnp.zeros_like(q)))[0])(qs)


# The frequency domain's map at q₀, compiled: op by op, each primitive compiled on its own
# (Wu & Yuan's first frequency response: ~3 s of it and H₀)
@eqx.filter_jit
def _wrench_map(geometry: BodyPoints, kin0, n_bodies: int):
    """The linear map of loads at the reference points (6K) to body wrenches (n_bodies, 6) at
    the configuration of ``kin0`` (:meth:`BodyPoints.to_body_wrench`), as a matrix: one
    jacobian, not one call per ω."""
    return jax.jacfwd(lambda f: geometry.to_body_wrench(f, kin0, n_bodies))(
        jnp.zeros(6 * len(geometry.body_index)))


def _f64(a):
    """``a`` as a float64 jax array: host data put on the device as it is
    (:func:`mfm.backend.device_array`: no conversion program per shape), a jax array as it is."""
    if isinstance(a, jax.Array) and a.dtype == jnp.float64:
        return a
    return device_array(a, np.float64)


def moving_dofs(model, body_index, d_ref, n_samples: int = 3, seed: int = 0) -> np.ndarray:
    """Indices of the hydro dofs (6 per wet body: the velocity of its reference point and its
    angular velocity, inertial axes) that the model's joints can move: the rows of H(q) in
    ξ̇ = H q̇ that are not 0 at ``n_samples`` random configurations (|q| ≤ 0.3). A structural zero
    (a planar model has no sway, roll or yaw) is 0 at every q; a row that is 0 by accident at
    three random q is not generic. Radiation is modelled on these dofs only."""
    geo = BodyPoints(body_index=tuple(int(i) for i in body_index),
                     d_ref=device_array(np.asarray(d_ref, float)),
                     ref0=device_array(np.zeros((len(body_index), 3))))
    rng = np.random.default_rng(seed)
    qs = device_array(rng.uniform(-0.3, 0.3, (n_samples, model.n_coordinates)))
    args = (model.keyed(), geo, qs)
    # the host's program (the runner's: from disk where an earlier process traced it); run once
    # per load
    samples = host.current().program(_h_samples, "h_samples", args, once=True)(*args)
    peak = np.abs(np.asarray(samples)).max(axis=(0, 2))
    return np.flatnonzero(peak > 1e-12 * max(float(np.max(peak)), 1e-300))
