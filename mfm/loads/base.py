"""The load protocol: one definition serves the time domain, the equilibrium and the frequency domain.

A load is an immutable pytree (``equinox.Module``). The runner hands it a :class:`Context` (the
model, the time, the state, the kinematics, its own states and memory) and it returns a
:class:`LoadOutput`: Cartesian body loads ``body`` (n, 6: force in inertial axes, moment about the
CoM in body axes), generalised loads ``tau`` (n_q), the derivative ``zd`` of its own first-order
states, and an acceleration-proportional matrix ``mass`` (n_q, n_q) that the solver moves to the
left-hand side. Loads enter the equations of motion as ``Bᵀ body + tau`` (Lande-Sudall et al. eq. 46).

From the same definition the frequency domain takes, about a static equilibrium q₀:

- the static load G(q) and the stiffness −∂G/∂q from :meth:`Load.static_load` (the load at rest,
  in still water: by default the load itself; a wave load drops its excitation and memory),
- the damping −∂Q/∂q̇ and the mass (``mass`` at q₀) by differentiating :meth:`Load.evaluate`,
- what cannot come from a derivative at one instant, :meth:`Load.frequency_terms`: a frequency-
  dependent impedance (radiation memory) and a harmonic force per unit wave amplitude.

So ``equilibrium``, ``frequency_response`` and ``natural_frequencies`` see exactly the loads the
time domain sees. A load records outputs (:meth:`Load.diagnostics` with their dims and units in
:meth:`Load.outputs`) and is read from a config table through the registry
(:mod:`mfm.loads.registry`).
"""
from __future__ import annotations

from typing import Any, ClassVar, NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..backend import device_array

# the six modes of a body point (its hydro dofs): translations then rotations, inertial axes
MODES = ("surge", "sway", "heave", "roll", "pitch", "yaw")


class Context(NamedTuple):
    """Where a load is evaluated. ``kin``: the :class:`~mfm.mechanics.kinematics.Kinematics` at (q, q̇);
    ``z``: the load's own states; ``memory``: its discrete memory of the current step (read-only
    within a step); ``qdd_guess``: the acceleration iterate of a predictor–corrector integrator
    (Beeman) or None; ``qdd``: the accelerations, known only when outputs are recorded."""
    model: Any
    t: Any
    q: Any
    qd: Any
    z: Any
    kin: Any
    memory: Any = ()
    qdd_guess: Any = None
    qdd: Any = None


class LoadOutput(NamedTuple):
    """``extra``: anything the load hands its own :meth:`Load.reaction_loads` and
    :meth:`Load.diagnostics` of the same state (they get this output), so that what they share
    with :meth:`Load.evaluate` is made once when a sample is recorded (None: nothing)."""
    body: jnp.ndarray | None = None
    tau: jnp.ndarray | None = None
    zd: jnp.ndarray | None = None
    mass: jnp.ndarray | None = None
    extra: Any = None


class FrequencyTerms(NamedTuple):
    """A load's frequency-dependent part about q₀, for x(t) = Re[x̂ e^{−iωt}] (hydro convention):
    ``impedance`` (n_ω, n_q, n_q) complex, added to Z(ω) = −ω² M − iω C + K; ``force``
    (n_ω, n_q) complex per metre of wave amplitude; either may be None."""
    impedance: Any = None
    force: Any = None


class LinearDampers(NamedTuple):
    """The power-absorbing dampers a load adds, linearised about q₀ (:meth:`Load.linear_dampers`):
    ``names`` (P,), ``damping`` β (P,) (N s/m or N m s/rad), ``rows`` G (P, n_q) with the rate
    ẇ = G q̇ to first order, ``offset`` w(q₀) (P,). Power β ẇ², displacement w(q₀) + G (q − q₀)."""
    names: tuple
    damping: Any
    rows: Any
    offset: Any


class PTORecords(NamedTuple):
    """A PTO load's pistons over a run (:meth:`Load.pto_records`): ``names`` (P,), ``power``,
    ``displacement`` and ``force`` (time, P) in W, m and N (force may be None)."""
    names: tuple
    power: Any
    displacement: Any
    force: Any = None


class RunGrid(NamedTuple):
    """The run a load is laid on (:meth:`Load.for_run`): ``sea`` (a :mod:`hydro` sea state, or
    None for still water), the start ``t0`` (s), the step ``dt`` (s), ``n_steps``, the wave ramp
    ``ramp`` (s) and the integrator's ``stage_offsets`` (the fractions of dt at which it evaluates
    the loads; a table laid on t0 + (j + c) dt for each offset c is read without interpolation
    error at every stage). ``n_components``: in a batch (:func:`mfm.simulate_batch`), the most
    components of any case's sea: a load that reads the sea's components pads its own to this many
    with zero amplitudes (:meth:`hydro.wetted.WaveField.of`), so that the cases stack on one axis;
    None in a single run."""
    sea: Any
    t0: float
    dt: float
    n_steps: int
    ramp: float
    stage_offsets: tuple
    n_components: int | None = None


class LinearHydro(NamedTuple):
    """The linear potential-flow model a load carries (:meth:`Load.linear_hydro`), what the levels
    built on it alone read (the spectral and linear levels, ``optimize``, the radiation fit's
    check): ``spec`` (the :class:`~hydro.prepare.HydroSpec`: database, water depth, g, ρ),
    ``geometry`` (the reference points: ξ̇ = H(q) q̇, (6K, n_q)), ``A_inf`` (6K, 6K), ``drag``
    (K, 3): ½ ρ C_D A per inertial axis on the reference points' velocity (what the spectral
    levels linearise stochastically), and ``coefficients(kin0, omega, heading, options,
    excitation=True)`` → (A(ω) − A∞, B(ω), X(ω, β) or None, H₀) of the radiation strategy
    ``options["radiation"]``."""
    spec: Any
    geometry: Any
    A_inf: Any
    drag: Any
    coefficients: Any


class QuadraticDrag(NamedTuple):
    """The quadratic drags a load puts on the flow past points, linearised about q₀
    (:meth:`Load.quadratic_drag`, linearised by :mod:`mfm.frequency.drag`): ``rows`` R (P, 3, n_q) the points' velocity
    v = R q̇ already projected (normal to a member), ``project`` P (P, 3, 3) the projector of the
    flow, ``drag`` D: (P, 3) per inertial axis (``kind = "axis"``: D_a |w_a| w_a) or (P,) on the
    vector (``kind = "vector"``: D |w| w), ``positions`` (P, 3) the points at rest (inertial),
    ``labels`` (P,) names of the points (outputs), ``flow``: True for a drag on the velocity
    relative to the incident wave's flow, w = P (u − v); False for one on the points' own
    velocity, w = −P v (u taken as 0: ``[hydro] drag_flow = "body"``)."""
    rows: np.ndarray
    project: np.ndarray
    drag: np.ndarray
    kind: str
    positions: np.ndarray
    labels: tuple
    flow: bool = True


class Load(eqx.Module):
    """Base class of every load: an immutable pytree (``equinox.Module``).

    **Required** (:data:`REQUIRED`): :meth:`evaluate` — the load at one state, as a
    :class:`LoadOutput` (or, the older form, ``__call__(model, t, q, qd, z, kin, memory=(),
    qdd_guess=None)``). A subclass that gives neither is refused when it is defined.

    **Optional** (:data:`OPTIONAL`, each with a default for a load without it):

    - first-order states: :attr:`n_states`, :meth:`initial_state`;
    - a discrete memory of the step: :meth:`init_memory`, :meth:`update_memory`;
    - what a run records: :meth:`diagnostics` with :meth:`outputs`, :meth:`batch_outputs`,
      :meth:`reaction_loads` (acceleration-proportional terms on the bodies), :meth:`pto_records`
      (a load that is a PTO);
    - the linearisation: :meth:`static_load` (its part at rest; None: nothing static),
      :meth:`frequency_terms` with :meth:`frequency_body_loads` and :meth:`frequency_range`,
      :meth:`frequency_outputs`, :meth:`linear_outputs` (what :meth:`diagnostics` records, to
      first order about q₀: the linear levels' series of it), :meth:`linear_dampers` (a PTO's
      damping about q₀),
      :meth:`quadratic_drag` (quadratic drag on the relative flow or on the body's own velocity,
      for the spectral level's stochastic linearisation), :meth:`in_mean_drift` (the load at rest holding a sea's mean wave drift:
      the equilibrium in a sea);
    - words: :meth:`provenance`, :meth:`describe_nonfinite`.

    - a run: :meth:`for_run` (the load laid on a run's sea and time grid: wave tables at the
      integrator's stages; with :attr:`reads_sea` True where it reads the sea), :meth:`host_view` (the load as compiled programs are handed it);
    - :meth:`linear_hydro` (the linear potential-flow model a load carries, if it is one).

    No code finds a load by its type or its place in a tuple: a load that is a PTO, carries a
    sea's tables or a BEM model says so through these methods, the water (:mod:`mfm.loads.water`)
    as any other.

    A load that reads a config table also gives ``parse_table`` and ``from_parsed``
    (:mod:`mfm.loads.registry`).
    """

    # whether the load reads the run's sea (in :meth:`for_run`): a front door refuses a sea that
    # no load of the run reads (a sea on a model without water would otherwise do nothing)
    reads_sea: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.evaluate is Load.evaluate and cls.__call__ is Load.__call__:
            raise TypeError(f"load {cls.__name__}: a Load must define evaluate(ctx) -> LoadOutput "
                            "(or the older __call__(model, t, q, qd, z, kin, memory, qdd_guess)); "
                            f"the other methods are optional: {', '.join(OPTIONAL)}")

    @property
    def n_states(self) -> int:
        return 0

    def initial_state(self, model) -> jnp.ndarray:
        return device_array(np.zeros(self.n_states))

    def init_memory(self, model, t0, q0, qd0, dt):
        """Discrete memory at the start of a run (default: none)."""
        return ()

    def update_memory(self, model, t, q, qd, kin, memory):
        """Memory after a step that ended at (t, q, q̇) (default: unchanged)."""
        return memory

    def evaluate(self, ctx: Context) -> LoadOutput:
        """The load at one state (required: a subclass defines it, or the older ``__call__``,
        which this then calls)."""
        return self(ctx.model, ctx.t, ctx.q, ctx.qd, ctx.z, ctx.kin, ctx.memory,
                    qdd_guess=ctx.qdd_guess)

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None) -> LoadOutput:
        return self.evaluate(Context(model, t, q, qd, z, kin, memory, qdd_guess))

    def reaction_loads(self, ctx: Context, out: LoadOutput):
        """Cartesian loads (n, 6) this load puts on the bodies, for the joint reactions: by default
        ``out.body``; a load with acceleration-proportional terms adds them (``ctx.qdd``)."""
        return out.body

    def diagnostics(self, ctx: Context, out: LoadOutput) -> dict:
        """Named arrays recorded at every saved sample (``ctx.qdd`` is known)."""
        return {}

    def outputs(self) -> dict:
        """What :meth:`diagnostics` records: name → (dims after "time", attrs with "units"), and
        the coordinate values of those dims under the key ``"coords"``."""
        return {}

    def pto_records(self, records: dict) -> "PTORecords | None":
        """For a load that is a PTO, its pistons as the time domain reports them, from this load's
        recorded :meth:`diagnostics` (:mod:`mfm.loads.pto`); None (default): not a PTO."""
        return None

    def batch_outputs(self, save_every: int, n_saved: int) -> dict:
        """Outputs a batched run (no per-sample record) can take from the load itself:
        name → (array (n_saved,), attrs)."""
        return {}

    # -- a run
    def for_run(self, model, run: RunGrid) -> "Load":
        """This load laid on a run (:class:`RunGrid`): what depends on the sea, the start, the step
        or the integrator's stages made here, on the host, once per run (wave kinematics at the
        load's points on the stage times, say). Default: the load itself (nothing depends on the
        run). Called on every load of the model and every extra load of a front door, in the
        time domain only (a linearisation takes :meth:`static_load`)."""
        return self

    def host_view(self) -> "Load":
        """The load as compiled programs are handed it: fields that only the host reads (names,
        reports, provenance) blanked, so that loads that differ only in them share one
        compilation (their static fields are part of jit's key). Nothing traced may read what is
        blanked. Default: the load itself."""
        return self

    def linear_hydro(self) -> "LinearHydro | None":
        """The linear potential-flow model this load carries (:class:`LinearHydro`), or None
        (default): the spectral and linear levels and ``optimize`` are built on it."""
        return None

    # -- linearisation
    def static_load(self) -> "Load | None":
        """The load at rest in still water, for the equilibrium and the stiffness (default: the
        load itself; None: nothing static)."""
        return self

    def in_mean_drift(self, sea, mean_drift=None) -> "Load | None":
        """This load holding, in its :meth:`static_load`, the mean of its second-order wave
        force in ``sea`` (a :mod:`hydro` sea state), for the equilibrium in that sea
        (``mfm.equilibrium(model, sea=)``: a moored body's mean offset); ``mean_drift``: a table
        of the drift per unit amplitude squared to take in place of the load's own (the water's:
        the drift of the model's own motions); None (default): the load has no mean wave
        force."""
        return None

    def frequency_terms(self, model, q0, kin0, omega, heading: float, options: dict) -> FrequencyTerms:
        """Frequency-dependent impedance and wave force about q₀ (default: none)."""
        return FrequencyTerms()

    def frequency_body_loads(self, model, q0, kin0, omega, heading: float, options: dict, x):
        """The body loads (n_ω, n, 6) complex (force inertial, moment about the CoM in body axes,
        per metre of wave amplitude) of this load's :meth:`frequency_terms` for the coordinate
        amplitudes x (n_ω, n_q): F(ω) − Z_load(ω) x̂ put on the bodies, so that the joint reactions
        of a frequency response see them (:func:`mfm.frequency.joint_reactions`). Default: None
        for a load without frequency terms; a load with frequency terms must say where they act,
        else this raises (a reaction without them would be wrong)."""
        if type(self).frequency_terms is Load.frequency_terms:
            return None
        raise NotImplementedError(
            f"load {type(self).__name__}: it adds frequency-dependent terms (frequency_terms) but "
            "does not give the body loads they make (frequency_body_loads), so the joint reactions "
            "cannot include them; define frequency_body_loads, or call frequency_response with "
            "joint_reactions=False")

    def quadratic_drag(self, model, kin0):
        """The quadratic drags this load puts on points, about the kinematics ``kin0`` of q₀, as a
        :class:`QuadraticDrag` (their velocity rows, the flow's projector, the coefficients, the
        points at rest and whether the drag acts on the relative flow or on the points' own
        velocity): what the spectral level linearises stochastically
        (:mod:`mfm.frequency.drag`); None
        (default): none (the drag must already be in :meth:`evaluate`, whose slope at rest is 0)."""
        return None

    def frequency_range(self):
        """(ω_lo, ω_hi) rad/s where :meth:`frequency_terms` is defined, or None (everywhere)."""
        return None

    def frequency_outputs(self, model, kin0, x, omega) -> dict:
        """Outputs of a frequency response from the complex coordinate amplitudes x (n_ω, n_q):
        name → (dims after "omega", array, attrs), plus "coords" (default: none)."""
        return {}

    def linear_outputs(self, model, kin0) -> dict:
        """Outputs this load records in the time domain (:meth:`diagnostics`), to first order
        about the kinematics ``kin0`` of q₀: y ≈ y₀ + L (q − q₀), what the linear levels
        (:func:`mfm.spectral_response`, :func:`mfm.linear_response`) report of them and
        :func:`mfm.reduce` compares across the ladder. name → (dims after the run's own, y₀ (k,),
        L (k, n_q), attrs), plus "coords" (default: none). The same L serves a frequency
        response: ŷ = L x̂ (:meth:`frequency_outputs`)."""
        return {}

    def linear_dampers(self, kin0) -> LinearDampers | None:
        """The PTOs this load adds as seen by the linear levels (:func:`mfm.spectral_response`,
        :func:`mfm.linear_response`), linearised at the kinematics ``kin0`` of q₀, so that every
        level of the fidelity ladder reports the PTOs the time domain reports; None (default):
        none. The damping itself must already be in :meth:`evaluate` (the linearisation takes it
        from there); this only names it and says how its power is read from q̇."""
        return None

    def provenance(self) -> dict:
        """Settings that made this load, for the result's attributes."""
        return {}

    def describe_nonfinite(self, model, q, qd) -> str | None:
        """A likely cause specific to this load when a run went non-finite at (q, q̇), or None."""
        return None


# the load protocol: what a load must define, and what it may (the base gives a default)
REQUIRED = ("evaluate",)
OPTIONAL = ("n_states", "initial_state", "init_memory", "update_memory", "reaction_loads",
            "diagnostics", "outputs", "batch_outputs", "pto_records", "static_load",
            "frequency_terms", "frequency_body_loads", "frequency_range", "frequency_outputs",
            "linear_outputs",
            "linear_dampers", "provenance", "describe_nonfinite", "for_run", "host_view",
            "linear_hydro", "quadratic_drag", "in_mean_drift")
