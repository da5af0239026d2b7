"""Radiation memory as a strategy of the water load: each gives its time-domain force and the
A(ω), B(ω) it amounts to, so the frequency domain uses the time domain's radiation by construction.

    F_rad(t) = −∫₀^{T_K} K(τ) ξ̇(t − τ) dτ            (Cummins; K from B(ω))

- :class:`Convolution`: product integration of the piecewise-linear velocity history against K
  (weights per stage offset that the integrator declares, :meth:`hydro.prepare.HydroSpec.kernel`);
  its A(ω), B(ω) by Ogilvie from the same K: A∞ − ∫K sin ωτ dτ/ω and ∫K cos ωτ dτ.
- :class:`StateSpace`: the passive fit (:mod:`hydro.statespace`) in modal form, ż = p z + ξ̇_j,
  F_i = −Σ Re(C_ik z_k); its A(ω) = A∞ + Im K̂(iω)/ω, B(ω) = Re K̂(iω).
- :class:`ExactStateSpace`: the same fit, its states advanced exactly over each step for a
  velocity linear within the step (memory of the load, not states of the integrator).
- :class:`NoRadiation`: A∞ only (A(ω) = A∞, B = 0).
- :class:`DatabaseRadiation`: the BEM A(ω), B(ω) as given: frequency domain only (a database
  whose A and B are not Kramers–Kronig consistent has no exact time-domain counterpart).

Every strategy acts on the hydro dofs the joints can move (:attr:`HydroSpec.moving`); the others
have zero velocity and their loads do no work.
"""
from __future__ import annotations

import dataclasses
import math
from fractions import Fraction
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from hydro import phases
from ..backend import device_array

STRATEGIES = ("convolution", "state_space", "state_space_exact", "none")

# frequencies per block of the convolution's Filon weights ((block, n_t) complex: 70,000 times of
# a 353 s memory make 72 MB a block)
_OMEGA_BLOCK = 64


def convolution_irf(spec):
    """(t, K (n_t, n, n)): the radiation kernel K(τ) of the moved dofs (:attr:`HydroSpec.moving`)
    on the grid of the convolution's frequency-domain coefficients: graded near τ = 0, where
    entries with slowly decaying damping have a narrow spike (25 steps of step/100), then uniform
    to max(4 T_K, 60 s) at step = min(0.02 s, π/(4 ω_max)). Made once per spec (kept in its
    cache: the moved dofs only, since K of 48 dofs over 4 T_K would be gigabytes)."""
    key = ("convolution_irf",)
    cache = spec._cache
    if key not in cache:
        om_db = np.asarray(spec.database()["omega"].values)
        step = min(0.02, np.pi / np.nanmax(om_db) / 4)
        t = np.concatenate([np.linspace(0.0, 25 * step, 2501)[:-1],
                            np.arange(25 * step, max(4 * spec.memory(), 60.0), step)])
        mv = np.asarray(spec.moving)
        cache[key] = (t, np.ascontiguousarray(spec.impulse_response(t)[:, mv][:, :, mv]))
    return cache[key]


class NoRadiation(eqx.Module):
    name: ClassVar[str] = "none"

    @property
    def n_states(self):
        return 0

    def init_memory(self, v, t0):
        return ()

    def update_memory(self, v, t, memory):
        return memory

    def force(self, t, v, z, memory):
        """The force on every hydro dof (6K,) and the derivative of the strategy's states."""
        rows, F, zd = self.force_rows(t, v, z, memory)
        return (jnp.zeros_like(v) if rows is None
                else jnp.zeros_like(v).at[np.asarray(rows)].set(F)), zd

    def force_rows(self, t, v, z, memory):
        """(rows, F, ż): the force F on the hydro dofs ``rows`` (static) the strategy acts on; it
        is zero on the others (rows None: no force). The water's time step takes this form, so
        that it works on the moved dofs only."""
        return None, None, None

    def added_mass_inf(self, spec):
        return spec.added_mass_inf()

    def coefficients(self, spec, omega):
        A_inf = self.added_mass_inf(spec)
        return np.broadcast_to(A_inf, (len(omega),) + A_inf.shape), np.zeros((len(omega),) + A_inf.shape)

    def provenance(self):
        return {"radiation": self.name}

    def host_view(self):
        """The strategy as compiled programs are handed it (:meth:`mfm.loads.base.Load.host_view`):
        host-only static fields blanked. Default: itself."""
        return self


class DatabaseRadiation(NoRadiation):
    """The database's A(ω), B(ω) (frequency domain only)."""
    name: ClassVar[str] = "database"

    def force_rows(self, t, v, z, memory):  # pragma: no cover - refused when the water is built
        raise ValueError("radiation='database' exists in the frequency domain only")

    def coefficients(self, spec, omega):
        db = spec.database()
        return (db["added_mass"].interp(omega=omega).values,
                db["radiation_damping"].interp(omega=omega).values)


class Convolution(NoRadiation):
    """Direct convolution over the moved dofs ``dofs`` (n of them): the force at a stage offset s
    of the step (``stage_offsets``, fractions of dt, from the integrator) is

        ∫₀^{T_K} K(τ) ξ̇(t − τ) dτ = W_c[s] ξ̇(t) + Σ_j W_j[s] ξ̇(t_n − j dt)   (j = 0 … N−1).

    The history sum does not change within a step, so it is formed once per step for every
    offset, when the memory is updated, as one matrix–vector product ``W_lag`` (S, n, N·n) times
    the history flattened (N·n): a stage then adds only W_c[s] ξ̇(t). (Formed at every evaluation,
    it cost a slice of W and a product of N·n² each time: four per RK4 step.) ``W_current`` (S, n, n).
    Memory: (t_n, history (N, n) newest first, the history sum for each offset (S, n))."""
    W_current: jnp.ndarray
    W_lag: jnp.ndarray
    dt: jnp.ndarray
    memory_length: float = eqx.field(static=True)
    stage_offsets: tuple[float, ...] = eqx.field(static=True)
    dofs: tuple[int, ...] = eqx.field(static=True)
    n_lags: int = eqx.field(static=True)
    name: ClassVar[str] = "convolution"

    def memory_at(self, t, hist):
        """The memory at step start t with velocity history ``hist`` (N, n), newest first."""
        return (jnp.asarray(t, jnp.float64), hist, self.W_lag @ hist.reshape(-1))

    def init_memory(self, v, t0):
        v = v[np.asarray(self.dofs)]
        return self.memory_at(t0, jnp.zeros((self.n_lags, v.shape[0])).at[0].set(v))

    def update_memory(self, v, t, memory):
        return self.memory_at(t, jnp.concatenate([v[np.asarray(self.dofs)][None], memory[1][:-1]],
                                               axis=0))

    def force_rows(self, t, v, z, memory):
        t_n, _, lagged = memory
        # the stage of the step: the nearest of the offsets the integrator declared
        offs = jnp.asarray(self.stage_offsets)
        r = jnp.argmin(jnp.abs((t - t_n) / self.dt - offs))
        F = self.W_current[r] @ v[np.asarray(self.dofs)] + lagged[r]
        return self.dofs, -F, None

    def coefficients(self, spec, omega):
        """A(ω) = A∞ − ∫₀^{t_e} K(τ) sin ωτ dτ / ω and B(ω) = ∫₀^{t_e} K(τ) cos ωτ dτ (Ogilvie), K of
        the moved dofs on :func:`convolution_irf`'s grid (kept on the spec: a natural-frequency
        search asks for one ω at a time, dozens of times); the other dofs keep A∞ and B = 0 (no
        joint moves them: their rows of H are zero). Filon weights per block of ``_OMEGA_BLOCK``
        frequencies (their (n_ω, n_t) table stays small whatever the memory)."""
        from hydro.radiation import filon_weights

        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        t, K = convolution_irf(spec)
        mv = np.asarray(spec.moving)
        A_inf = np.asarray(spec.added_mass_inf())
        A = np.array(np.broadcast_to(A_inf, (len(omega),) + A_inf.shape))
        B = np.zeros_like(A)
        if not mv.size:
            return A, B
        rows, cols = mv[:, None], mv[None, :]
        for lo in range(0, len(omega), _OMEGA_BLOCK):
            w = omega[lo:lo + _OMEGA_BLOCK]
            W = filon_weights(t, w)                         # ∫ f e^{iωτ}: cos + i sin
            blk = np.tensordot(W, K, axes=(1, 0))           # (n_w, n, n)
            A[lo:lo + len(w), rows, cols] = A_inf[rows, cols][None] - blk.imag / w[:, None, None]
            B[lo:lo + len(w), rows, cols] = blk.real
        return A, B

    def provenance(self):
        return {"radiation": self.name, "memory_length_s": self.memory_length,
                "convolution_lags": self.n_lags}

    def host_view(self):
        # the memory length is provenance: the lags' count (static) and weights hold the run's
        return dataclasses.replace(self, memory_length=0.0)

    @classmethod
    def build(cls, spec, dt, memory, stage_offsets):
        W_current, W_lag = spec.kernel(dt, memory, offsets=stage_offsets)
        T_K = spec.memory() if memory is None else float(memory)
        S, N, n, _ = W_lag.shape
        # (S, N, n_a, n_b) -> (S, n_a, N·n_b): row a of offset s against the flattened history
        W_flat = np.ascontiguousarray(np.transpose(W_lag, (0, 2, 1, 3)).reshape(S, n, N * n))
        return cls(W_current=device_array(W_current), W_lag=device_array(W_flat),
                   dt=device_array(dt, np.float64), memory_length=float(T_K),
                   stage_offsets=tuple(float(s) for s in stage_offsets),
                   dofs=tuple(spec.moving), n_lags=N)


class StateSpace(NoRadiation):
    """The modal state space: ``p`` (n_x, 2) complex poles as (re, im); ``C`` (n_out, 2 n_x) the
    real output map [Re R, −Im R] of the output residues R (conjugate pairs folded, × 2), so that
    the force on the output dofs is −C [Re z; Im z] with one matrix–vector product (one contiguous
    matrix: slices of a trailing (re, im) axis cost a copy of R at every evaluation); ``inputs``
    the input dof of each state, ``outputs`` the output dofs, ``A_inf`` the fit's corrected A∞;
    ``options`` the fit options (static, so the frequency domain refits nothing: the fit is cached
    on the HydroSpec)."""
    p: jnp.ndarray
    C: jnp.ndarray
    A_inf: jnp.ndarray
    inputs: tuple[int, ...] = eqx.field(static=True)
    outputs: tuple[int, ...] = eqx.field(static=True)
    options: tuple = eqx.field(static=True, default=())
    report: tuple = eqx.field(static=True, default=())
    name: ClassVar[str] = "state_space"

    @property
    def n_states(self):
        return 2 * len(self.inputs)

    def force_rows(self, t, v, z, memory):
        n = len(self.inputs)
        zr, zi = z[:n], z[n:]
        pr, pi = self.p[:, 0], self.p[:, 1]
        u = v[np.asarray(self.inputs)]
        zd = jnp.concatenate([pr * zr - pi * zi + u, pr * zi + pi * zr])
        return self.outputs, -(self.C @ z), zd

    def added_mass_inf(self, spec):
        return np.asarray(self.A_inf)

    def coefficients(self, spec, omega):
        ss = spec.state_space(**dict(self.options))
        Z = ss.impedance(omega)
        return np.asarray(self.A_inf)[None] + Z.imag / omega[:, None, None], Z.real

    def provenance(self):
        return {"radiation": self.name, "state_space_options": repr(dict(self.options)),
                "state_space_states": self.n_states, **{f"fit_{k}": v for k, v in self.report}}

    def host_view(self):
        # the fit's report is provenance only
        return dataclasses.replace(self, report=())

    @classmethod
    def build(cls, spec, options):
        from hydro.prepare import modal_form

        import inspect

        from hydro.statespace import fit_state_space

        if options is not None and not isinstance(options, dict):
            raise ValueError(f"state_space_options: {options!r}; give a dict of options of "
                             "hydro.statespace.fit_state_space")
        options = dict(options or {})
        accepted = [p for p in inspect.signature(fit_state_space).parameters if p != "db"]
        bad = sorted(set(options) - set(accepted))
        if bad:
            raise ValueError(f"state_space_options: unknown option(s) {bad}; accepted: {accepted} "
                             "(see hydro.statespace.fit_state_space)")
        ss = spec.state_space(**options)
        # the modal form of the fit, kept beside it on the spec: a batch builds one strategy per
        # time step, and the realisation (a pass over every fitted entry) is the same for all
        key = ("modal_form", repr(sorted(options.items())))
        cache = getattr(spec, "_cache", {})
        if cache.get(key, (None,))[0] is not ss:
            phases.say("the state space's modal form")
            cache[key] = (ss, modal_form(ss))
        P, C, ins, outs = cache[key][1]
        report = tuple((k, v) for k, v in (getattr(ss, "report", None) or {}).items()
                       if isinstance(v, (int, float, str)))
        return cls(p=device_array(np.stack([P.real, P.imag], 1).reshape(-1, 2)),
                   C=device_array(np.concatenate([C.real, -C.imag], 1)),
                   A_inf=device_array(np.asarray(ss.added_mass_inf) * spec.mask),
                   inputs=tuple(ins), outputs=tuple(outs),
                   options=tuple(sorted(options.items())), report=report)


def phi_functions(x, n: int):
    """(e^x, φ₁(x), …, φ_n(x)) for complex x, φ_k(x) = Σ_j x^j/(j + k)! (φ₁ = (eˣ − 1)/x,
    φ₂ = (eˣ − 1 − x)/x², φ₃ = (eˣ − 1 − x − x²/2)/x³): ∫₀ʰ s^{k−1} e^{λ(h−s)} ds / (k−1)! =
    h^k φ_k(λh), the weights of an exact step of ẏ = λy + (polynomial input). By the series
    (20 terms) where |x| < 0.5, where the recurrence φ_{k+1} = (φ_k − 1/k!)/x cancels; by the
    recurrence elsewhere (its error there is ≤ ε/|x|^n · n!)."""
    x = np.asarray(x, complex)
    small = np.abs(x) < 0.5
    xs = np.where(small, 1.0, x)
    # eˣ once, from real functions (numpy's complex exp took 80 ns an element, twice: 0.16 s of
    # 960 time steps' arrays for M4 134); the recurrence's values where x is small are not used
    ex = np.exp(x.real) * (np.cos(x.imag) + 1j * np.sin(x.imag))
    out = [ex]
    rec = ex
    for k in range(1, n + 1):
        rec = (rec - 1.0 / math.factorial(k - 1)) / xs
        # Σ_{j<20} x^j/(j + k)! by Horner's rule (20 multiply–adds, not 20 complex powers)
        series = np.full(x.shape, 1.0 / math.factorial(19 + k), dtype=complex)
        for j in range(18, -1, -1):
            series *= x             # in place: the same numbers, without a temporary per term
            series += 1.0 / math.factorial(j + k)
        out.append(np.where(small, series, rec))
    return tuple(out)


class ExactStateSpace(StateSpace):
    """The state space of :class:`StateSpace` with its states advanced exactly over each step,
    outside the integrator, for an input ξ̇ linear in time within the step (first-order hold,
    the history the convolution assumes too). For ż = p z + u, u(s) = uₙ + (u_c − uₙ) s/h:

        z(tₙ + h) = e^{ph} zₙ + h φ₁(ph) uₙ + h φ₂(ph) (u_c − uₙ),   h = c dt,

    φ₁(x) = (eˣ − 1)/x, φ₂(x) = (eˣ − 1 − x)/x². A stage at offset c of the integrator reads z at
    its own velocity u_c; the step's end (c = 1, the accepted velocity) becomes the next zₙ. The
    states are the load's memory, not the integrator's: stable at any dt (|e^{ph}| < 1 for every
    stable pole), so a one-evaluation integrator (``verlet``) can carry lightly damped radiation
    modes; the radiation's own error is that of the hold, O(dt²) (as the convolution's).

    The force F = −Re(R z) is linear in (zₙ, uₙ, u_c), so a stage reads

        F_c = −(Yₙ[c] + (R G_c) uₙ + (R H_c)(u_c − uₙ)),   Yₙ[c] = Re(R e^{p c dt} zₙ),

    with Yₙ computed once per step where zₙ is (:meth:`update_memory`), one matrix–vector
    product of ``RM`` with e^{p c dt} zₙ for each stage after the step's start, and none for a
    stage at its start (c = 0:
    Yₙ₊₁[0] = Re(R zₙ₊₁) follows from the stage at its end, c = 1, by the same linearity). The
    stages themselves cost (n_out × n_in) products, not a pass over the states.

    ``E``, ``G``, ``H`` (2, n_b, n_p): e^{p dt}, dt φ₁, dt φ₂ of the full step as (re, im), with the
    states in blocks (:func:`_blocks`): block b holds the n_p states driven by the input dof
    ``block_inputs[b]`` (padded with states that stay zero), so each input is read once and
    broadcast along its block instead of gathered per state. ``CE`` (n_c, 2, n_b, n_p):
    e^{p c dt} of the stage offsets c ∈ ``matvec_stages``, and ``RM`` (n_out, 2 n_b n_p) the
    residues' output map [Re R, −Im R] on [Re w; Im w]: Yₙ[c] = RM [Re w; Im w], w = e^{p c dt} zₙ.
    RM does not follow dt, so a batch of cases of their own dt shares it: each case carries its
    n_x factors per stage, not an n_out × 2n_x matrix per stage (M4 134: 194 kB per case with
    Verlet's one such stage, 387 kB with RK4's two, read at every step of every case), and the cases' products with RM are one matrix product.
    ``CG``, ``CH`` (S + 1, n_out, n_b): Re(R hφ₁), Re(R hφ₂) summed over each block, per stage
    offset and the full step (last). Memory: (tₙ, Re wₙ, Im wₙ, uₙ, Yₙ), w (n_b, n_p), u (n_b,),
    Y (S, n_out); w = e^{p dt} zₙ where the step's end is a stage with a product with the states
    (Verlet, RK4: :attr:`_carries_free_response`), else zₙ itself."""
    E: jnp.ndarray = None
    G: jnp.ndarray = None
    H: jnp.ndarray = None
    CE: jnp.ndarray = None
    RM: jnp.ndarray = None
    CG: jnp.ndarray = None
    CH: jnp.ndarray = None
    dt: jnp.ndarray = None
    block_inputs: tuple[int, ...] = eqx.field(static=True, default=())
    matvec_stages: tuple[int, ...] = eqx.field(static=True, default=())
    stage_offsets: tuple[float, ...] = eqx.field(static=True, default=(0.0,))
    name: ClassVar[str] = "state_space_exact"

    @property
    def n_states(self):
        return 0

    def init_memory(self, v, t0):
        shape = self.E.shape[1:]
        return (jnp.asarray(t0, jnp.float64), jnp.zeros(shape), jnp.zeros(shape),
                v[np.asarray(self.block_inputs)], jnp.zeros((len(self.stage_offsets), self.CG.shape[1])))

    @property
    def _carries_free_response(self) -> bool:
        """Whether the memory carries wₙ = e^{p dt} zₙ rather than zₙ: where the step's end is a
        stage with a product with the states (Verlet's and RK4's offsets), that stage's
        e^{p·1·dt} zₙ₊₁ (CE at c = 1, the same numbers as E) is the next step's E zₙ₊₁, so the
        update reads it instead of forming it again: one pass over the states a step fewer (the
        batch's largest kernels on a GPU were these passes, memory-bound: 2,500 M4 134 cases on
        an H100, 57 and 30 µs of a 385 µs step)."""
        return 1.0 in self.stage_offsets and self._end in self.matvec_stages

    def update_memory(self, v, t, memory):
        _, ar, ai, u_n, Y = memory
        u = v[np.asarray(self.block_inputs)]
        E, G, H = self.E, self.G, self.H
        du, un = (u - u_n)[:, None], u_n[:, None]
        if self._carries_free_response:
            # (ar, ai) = e^{p dt} zₙ: the same sums, term by term, as the line below
            zr, zi = ar + G[0] * un + H[0] * du, ai + G[1] * un + H[1] * du
        else:
            zr, zi = (E[0] * ar - E[1] * ai + G[0] * un + H[0] * du,
                      E[0] * ai + E[1] * ar + G[1] * un + H[1] * du)
        ar, ai = zr, zi             # the memory's next states: zₙ₊₁, or e^{p dt} zₙ₊₁ below
        rows = [None] * len(self.stage_offsets)
        if self.matvec_stages:
            er, ei = self.CE[:, 0], self.CE[:, 1]                        # (n_c, n_b, n_p)
            wr, wi = er * zr - ei * zi, er * zi + ei * zr
            n_c = len(self.matvec_stages)
            W = jnp.concatenate([wr.reshape(n_c, -1), wi.reshape(n_c, -1)], axis=1)
            for k, s in enumerate(self.matvec_stages):
                # a (1, 2 n_x) row times RMᵀ per stage, not the (n_c, 2 n_x) block at once: in a
                # time loop compiled whole (mfm.runner.xla) XLA runs a product of several rows as one
                # scalar chain per element, a row as a vectorised matrix–vector product (RK4's two
                # stages, M4 134's 20,000 steps: the loop 1.33 -> 0.48 s; Verlet's one row, the
                # same expression, the same bits as before)
                rows[s] = (W[k:k + 1] @ self.RM.T)[0]
            if self._carries_free_response:
                k = self.matvec_stages.index(self._end)
                ar, ai = wr[k], wi[k]
        for s, c in enumerate(self.stage_offsets):
            if rows[s] is None:
                # c = 0: Re(R zₙ₊₁) = the full step's stage output of zₙ and the inputs
                rows[s] = Y[self._end] + jnp.sum(self.CG[-1] * u_n + self.CH[-1] * (u - u_n), axis=1)
        return (t, ar, ai, u, jnp.stack(rows))

    @property
    def _end(self):
        return self.stage_offsets.index(1.0)

    def force_rows(self, t, v, z, memory):
        t_n, _, _, u_n, Y = memory
        offs = jnp.asarray(self.stage_offsets)
        r = jnp.argmin(jnp.abs((t - t_n) / self.dt - offs))
        u = v[np.asarray(self.block_inputs)]
        # (n_out × n_in) products as one fused multiply–reduce: tiny dots are slow on XLA CPU
        F = Y[r] + jnp.sum(self.CG[r] * u_n + self.CH[r] * (u - u_n), axis=1)
        return self.outputs, -F, None

    def provenance(self):
        return {**super().provenance(), "radiation": self.name,
                "state_space_update": "exact for a velocity linear within the step"}

    @classmethod
    def build(cls, spec, options, dt, stage_offsets):
        return cls.from_state_space(StateSpace.build(spec, options), dt, stage_offsets)

    @classmethod
    def from_state_space(cls, ss: StateSpace, dt, stage_offsets):
        """The exact update of ``ss``'s states for steps of ``dt`` and stages at ``stage_offsets``."""
        arrays, shared = cls._arrays(ss, np.asarray([float(dt)]), stage_offsets)
        return cls(p=ss.p, C=ss.C, A_inf=ss.A_inf, inputs=ss.inputs, outputs=ss.outputs,
                   options=ss.options, report=ss.report,
                   **{k: jnp.asarray(v[0]) for k, v in arrays.items()}, **shared)

    @classmethod
    def from_state_space_many(cls, ss: StateSpace, dts, stage_offsets):
        """:meth:`from_state_space` for each of the steps ``dts`` (D,) at once: one strategy
        whose arrays that follow dt (``E``, ``G``, ``H``, ``CE``, ``CG``, ``CH``, ``dt``) carry a
        leading axis of D, the same numbers as D single builds (elementwise, in the same order).
        Returns (strategy, batched): ``batched`` a pytree of bools like it, True on those
        arrays."""
        arrays, shared = cls._arrays(ss, np.asarray(dts, dtype=float), stage_offsets)
        out = cls(p=ss.p, C=ss.C, A_inf=ss.A_inf, inputs=ss.inputs, outputs=ss.outputs,
                  options=ss.options, report=ss.report, **arrays, **shared)
        batched = jax.tree_util.tree_map(lambda _: False, out)
        return out, eqx.tree_at(lambda r: tuple(getattr(r, k) for k in arrays), batched,
                                tuple(True for _ in arrays))

    @staticmethod
    def _arrays(ss: StateSpace, dts, stage_offsets):
        """The arrays of the class docstring that follow dt, for each step of ``dts`` (D,) with a
        leading axis of D, and the fields every dt shares (RM and the static ones)."""
        offsets = tuple(float(c) for c in stage_offsets)
        p = np.asarray(ss.p[:, 0]) + 1j * np.asarray(ss.p[:, 1])
        slot, block_inputs, n_p = _blocks(ss.inputs)
        n_b, n_x = len(block_inputs), len(ss.inputs)
        C = np.asarray(ss.C)
        Rc = C[:, :n_x] - 1j * C[:, n_x:]                 # the complex residues R: F = −Re(R z)

        def blocks(a):
            # (..., n_x) -> (..., n_b, n_p); padded states get zeros (they stay zero)
            out = np.zeros(a.shape[:-1] + (n_b * n_p,), dtype=a.dtype)
            out[..., slot] = a
            return out.reshape(a.shape[:-1] + (n_b, n_p))

        # the poles in the block layout from the start (the layout of every array below), so the
        # D time steps' arrays are made in it rather than placed into it (a scatter per array:
        # 0.12 of 0.37 s for 960 time steps of M4 134)
        pb, live = blocks(p), blocks(np.ones(n_x)) > 0                 # (n_b, n_p)
        fractions = np.asarray(offsets + (1.0,))
        h = dts[:, None, None, None] * fractions[None, :, None, None]    # (D, S + 1, 1, 1)
        # φ of each distinct fraction of the step once (the step's end is also a stage's offset
        # for Verlet and RK4), elementwise, so the same numbers for a third to a half of the
        # work; at the step's start (fraction 0) they are 1, 1, ½ exactly
        uniq, back = np.unique(fractions, return_inverse=True)         # ascending: 0 first
        nz = uniq != 0.0
        parts = phi_functions(pb * (dts[:, None, None, None] * uniq[nz][None, :, None, None]), 2)
        at_zero = lambda v: np.broadcast_to(np.where(live, v, 0.0).astype(complex),  # noqa: E731
                                            (len(dts), int((~nz).sum()), n_b, n_p))
        e, phi1, phi2 = (np.concatenate([at_zero(v), np.where(live, a, 0.0)], axis=1)[:, back]
                         for a, v in zip(parts, (1.0, 1.0, 0.5)))

        def split(a, axis=1):
            # complex (D, …, n_b, n_p) -> real and imaginary parts on a new axis
            return np.stack([a.real, a.imag], axis=axis)

        # the residues (n_out, n_b, n_p), real and imaginary
        Rr, Ri = blocks(Rc.real), blocks(Rc.imag)
        Rb = np.concatenate([Rr, -Ri], axis=-1).transpose(1, 2, 0)         # (n_b, 2 n_p, n_out)

        def per_block(a):
            # Re(R a) summed over each block's states: (D, S + 1, n_out, n_b), as one matrix
            # product per block ([Re a, Im a] against [Re R; −Im R]; numpy's einsum looped it
            # without BLAS: 0.16 s for 960 time steps of M4 134)
            ab = np.concatenate([a.real, a.imag], axis=-1)              # (D, S + 1, n_b, 2 n_p)
            return np.matmul(ab.transpose(2, 0, 1, 3), Rb[:, None]).transpose(1, 2, 3, 0)

        # stages after the step's start need a product with the states; one at the start does not
        # where a stage at the end gives it (see the class docstring)
        matvec = tuple(s for s, c in enumerate(offsets) if c != 0.0 or 1.0 not in offsets)
        CE = split(e[:, list(matvec)], axis=2)                           # (D, n_c, 2, n_b, n_p)
        # the output map of [Re w; Im w], shared by every dt: Re(R w) = Re R Re w − Im R Im w
        n_out = C.shape[0]
        RM = np.concatenate([Rr.reshape(n_out, -1), -Ri.reshape(n_out, -1)], axis=1)
        arrays = dict(E=split(e[:, -1]), G=split(h[:, -1] * phi1[:, -1]),
                      H=split(h[:, -1] * phi2[:, -1]), CE=CE, CG=per_block(h * phi1),
                      CH=per_block(h * phi2), dt=np.asarray(dts, dtype=np.float64))
        return arrays, dict(RM=jnp.asarray(RM), block_inputs=block_inputs, matvec_stages=matvec,
                            stage_offsets=offsets)


def _blocks(inputs):
    """The block layout of states driven by the input dofs ``inputs`` (n_x,): runs of consecutive
    states with one input (the modal form makes one run per input and pole set) become blocks of
    n_p = the longest run, padded; where padding would more than double the states (runs of
    very different lengths), every state is its own block (n_p = 1). Returns the slot of each state
    in the flattened (n_b, n_p) layout, the input of each block and n_p."""
    inputs = np.asarray(inputs, dtype=int)
    if inputs.size == 0:
        return np.zeros(0, int), (), 1
    starts = np.flatnonzero(np.r_[True, inputs[1:] != inputs[:-1]])
    lengths = np.diff(np.r_[starts, inputs.size])
    n_p = int(lengths.max())
    if len(starts) * n_p > 2 * inputs.size:
        return np.arange(inputs.size), tuple(int(j) for j in inputs), 1
    slot = np.concatenate([b * n_p + np.arange(n) for b, n in enumerate(lengths)])
    return slot, tuple(int(inputs[s]) for s in starts), n_p


def strategy(spec, name, *, dt=None, memory=None, state_space_options=None, stage_offsets=(0.0, 0.5, 1.0),
             frequency_domain=False):
    """The radiation strategy ``name`` for a model's :class:`~hydro.prepare.HydroSpec`."""
    accepted = STRATEGIES + (("database",) if frequency_domain else ())
    if name not in accepted:
        raise ValueError(f"radiation={name!r}; accepted: {', '.join(map(repr, accepted))}")
    if name == "state_space" or (name == "state_space_exact" and frequency_domain):
        return StateSpace.build(spec, state_space_options)
    if name == "state_space_exact":
        return ExactStateSpace.build(spec, state_space_options, dt, stage_offsets)
    if name == "convolution":
        if frequency_domain:
            # the coefficients need only K(t) and the memory, not the weights of a time step
            return Convolution(W_current=jnp.zeros((1, 0, 0)), W_lag=jnp.zeros((1, 1, 0, 0)),
                               dt=jnp.asarray(1.0), memory_length=spec.memory(),
                               stage_offsets=(0.0,), dofs=(), n_lags=1)
        return Convolution.build(spec, dt, memory, stage_offsets)
    if name == "database":
        return DatabaseRadiation()
    return NoRadiation()


def stack_cases(items, index):
    """One pytree for many cases from the distinct ``items`` (pytrees of one structure) and the
    item of each case, ``index`` (B,): every leaf stacked along a leading case axis
    (``np.stack(...)[index]``). None where the items differ in structure."""
    flat = [jax.tree_util.tree_flatten(it) for it in items]
    treedef = flat[0][1]
    if any(d != treedef for _, d in flat[1:]):
        return None
    leaves = [np.stack([np.asarray(f[0][k]) for f in flat])[np.asarray(index)]
              for k in range(len(flat[0][0]))]
    return jax.tree_util.tree_unflatten(treedef, leaves)


def strategy_many(spec, name, dts, *, memory=None, state_space_options=None,
                  stage_offsets=(0.0, 0.5, 1.0)):
    """:func:`strategy` for each case's time step ``dts`` (B,) as one strategy: (rad, batched),
    ``batched`` a pytree of bools like it, True on the arrays that carry a leading case axis:
    those that follow dt, whatever the values (so a batch of one dt and one of several share a
    compilation); the others, shared, once. The exact state space makes them for every distinct
    dt at once (:meth:`ExactStateSpace.from_state_space_many`); a convolution is built once per
    distinct dt (its weights); the state space and none do not follow dt. None where the cases'
    strategies differ in structure (a convolution's lags follow dt)."""
    uniq, inverse = np.unique(np.asarray(dts, dtype=float), return_inverse=True)
    if name not in STRATEGIES:
        raise ValueError(f"radiation={name!r}; accepted: {', '.join(map(repr, STRATEGIES))}")
    if name == "state_space_exact":
        rad, batched = ExactStateSpace.from_state_space_many(
            StateSpace.build(spec, state_space_options), uniq, stage_offsets)
        return (jax.tree_util.tree_map(lambda a, b: np.asarray(a)[inverse] if b else a, rad,
                                       batched), batched)
    if name == "convolution":
        rad = stack_cases([strategy(spec, name, dt=float(d), memory=memory,
                                    stage_offsets=stage_offsets) for d in uniq], inverse)
        return None if rad is None else (rad, jax.tree_util.tree_map(lambda _: True, rad))
    rad = strategy(spec, name, dt=float(uniq[0]), memory=memory,
                   state_space_options=state_space_options, stage_offsets=stage_offsets)
    return rad, jax.tree_util.tree_map(lambda _: False, rad)


def grid_subdivisions(stage_offsets) -> int:
    """The smallest m such that every stage offset is a multiple of 1/m (the excitation is
    tabulated at dt/m, so every stage falls on a sample)."""
    m = 1
    for s in stage_offsets:
        f = Fraction(float(s)).limit_denominator(64)
        if abs(float(f) - s) > 1e-12:
            raise ValueError(f"stage offset {s} of the integrator is not a simple fraction of dt")
        m = m * f.denominator // np.gcd(m, f.denominator)
    return int(m)
