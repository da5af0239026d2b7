"""Morison elements: drag and inertia of the relative flow at points and along slender members.

Config table ``[[morison]]``, one element each: ``body``; either ``point = [x, y, z]`` (m,
inertial axes at rest: a point fixed on the body) or a strip ``from = [x, y, z]``, ``to = [x, y,
z]`` with ``segments = N`` (a member along the line between them, integrated by the midpoint rule
on N equal segments); ``cd`` (drag coefficient, ≥ 0); ``diameter`` D (m) or ``area`` (m²: the
projected area per metre of a strip, the area of a point); ``ca`` (added-mass coefficient, ≥ 0,
default 0); ``volume`` (m³ for a point, default 0; m³ per metre for a strip, default π D²/4 from
the diameter); optional ``name``, ``notes``. A point's ``diameter`` gives its area π D²/4 (its
volume must be given). The force per element (per metre of a strip) is

    f = ½ ρ C_D A |u_n − v_n| (u_n − v_n) + ρ (1 + C_A) V u̇_n − ρ C_A V v̇_n,

with u, u̇ the incident wave's particle velocity and local acceleration
(:func:`hydro.wetted.particle_velocity`, :func:`hydro.wetted.particle_acceleration`: linear
kinematics, Wheeler-stretched, 0 above the instantaneous surface), v, v̇ the element's velocity and
acceleration, and subscript n the part normal to a strip's axis (the flow along a slender member's
axis is not Morison's: x_n = x − e (e·x), e the member's unit axis turning with its body); a point
takes all three components. The force acts at the element's point (a strip's segment midpoint):
its moment about the body's CoM follows.

**The added mass on the mass side.** −ρ C_A V v̇_n, with v̇ = H q̈ + Ḣ q̇ (H the point's
translational rows of ξ̇ = H q̇, :class:`~mfm.mechanics.points.BodyPoints`), is put in the load's
acceleration-proportional matrix, ``mass`` = Σ_p ρ C_A V_p H_pᵀ (I − e eᵀ) H_p (as the water's A∞
enters M*, :mod:`mfm.loads.water`), and its velocity part −ρ C_A V (Ḣ q̇)_n in the generalised
load: no acceleration iterate, no lag, every integrator.

The sea comes through :meth:`MorisonElements.for_run` (every component of the run's sea:
headings, spreading), ramped as the water's excitation is; still water leaves the drag on the
element's own velocity. ρ, g and the water depth are the model's ``[hydro]`` (a ``[[morison]]``
without one is refused). Linearised at rest (equilibrium, natural frequencies) the load is its
added mass (the drag has zero slope at rest).

**In the frequency domain.** The inertia term's linear part is a wave force per unit complex
amplitude (:meth:`MorisonElements.frequency_terms`),

    F(ω, β) = Σ_p H_pᵀ ρ (1 + C_A) V_p (I − e_p e_pᵀ) (−iω) û_p(ω, β),

û the linear particle velocity at the point's rest position (:func:`hydro.wetted.velocity_transfer`;
0 above the mean surface), the added mass ρ C_A V already on the mass side: so
:func:`mfm.frequency_response` takes the element, with its drag's zero slope (a response per unit
amplitude has no sea to linearise on: with C_D ≠ 0 it is the inertia part alone, as with C_D = 0).
:func:`mfm.spectral_response` (and ``mfm.sweep(level="spectral")``) adds the drag linearised
stochastically on the relative normal flow of each sea, per point (:meth:`quadratic_drag`,
:mod:`mfm.frequency.drag`: ½ ρ C_D A |w_n| w_n ≈ C w_n, C = ½ ρ C_D A E[|w| I + w wᵀ/|w|] of the
Gaussian w_n, iterated to a fixed point): damping C on the point's normal velocity, excitation C
û_n. The linear level (:func:`mfm.linear_response`) takes the same: the inertia's wave force
synthesised from :meth:`frequency_terms` at the sea's components, the drag linearised.
``simulate_batch`` takes it for any seas: each case's wave arrays padded to the batch's most
components with zero amplitudes (``RunGrid.n_components``), stacked on the case axis.

Outputs (dims ``morison_element``, ``axis``): ``morison_force`` the force on each element (its
segments summed), inertial axes (N), the added-mass term included.
"""
from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..backend import device_array
from ..errors import ConfigError
from ..mechanics import se3
from ..mechanics.points import BodyPoints
from ..validation import (body_ref, element_name, number, tables, unique_names,
                          vector)
from .base import FrequencyTerms, Load, LoadOutput, QuadraticDrag

KEYS = {"name", "body", "point", "from", "to", "segments", "cd", "diameter", "area", "ca",
        "volume", "notes"}


def _no_components(spec):
    """Still water as wave components (none), at the water's depth and g: a batch's still-water
    case, padded like the others."""
    from hydro.waves import WaveComponents

    z = np.zeros(0)
    return WaveComponents(z, z, z, z, z, water_depth=float(spec.water_depth), g=float(spec.g))


def _safe_norm(x):
    """|x| over the last axis with derivative 0 at x = 0 (the linearisation at rest meets
    u − v = 0 exactly: sqrt's derivative there would be a NaN)."""
    n2 = jnp.sum(x * x, axis=-1)
    pos = n2 > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, n2, 1.0)), 0.0)


class MorisonElements(Load):
    """The ``[[morison]]`` elements of a model as P integration points (a point element is one, a
    strip N, at its segments' midpoints).

    ``points`` (:class:`BodyPoints`, P); ``axis`` (P, 3) the member's unit axis in body axes (0
    for a point element: all components normal); ``drag`` (P,) ½ ρ C_D A w; ``inertia`` (P,)
    ρ (1 + C_A) V w; ``added`` (P,) ρ C_A V w, with w the segment's length (1 for a point);
    ``wave`` (:class:`hydro.wetted.WaveField`, no ramp) and ``ramp`` (s) of the run. Static:
    ``element`` (P,) each point's element, ``names`` (E,), ``kinds`` (E,) "point" or "strip".
    """
    points: BodyPoints
    axis: jnp.ndarray
    drag: jnp.ndarray
    inertia: jnp.ndarray
    added: jnp.ndarray
    wave: object
    ramp: jnp.ndarray
    element: tuple = eqx.field(static=True, default=())
    names: tuple = eqx.field(static=True, default=())
    kinds: tuple = eqx.field(static=True, default=())
    rho: float = eqx.field(static=True, default=1025.0)
    g: float = eqx.field(static=True, default=9.81)
    # whether any element has an added mass (C_A V > 0): else no mass matrix at all
    has_added: bool = eqx.field(static=True, default=False)
    reads_sea = True

    # -- physics
    def _terms(self, kin, t):
        """(f without the acceleration's term (P, 3), H's translational rows (P, 3, n_q),
        the normal projection of H's rows (P, 3, n_q)): f = ½ ρ C_D A |w_n| w_n + ρ (1 + C_A) V u̇_n
        − ρ C_A V (Ḣ q̇)_n, w = u − v."""
        from hydro.wetted import particle_acceleration, particle_velocity, ramped

        P = self.axis.shape[0]
        H, R, _ = self.points.h_matrix(kin)
        H3 = H.reshape(P, 6, -1)[:, :3]
        v, bias = self.points.velocity_and_bias(kin)
        v3, b3 = v.reshape(P, 6)[:, :3], bias.reshape(P, 6)[:, :3]
        e = se3.rotate(R, self.axis)                                  # (P, 3) inertial

        def normal(x):            # x − e (e·x) over axis 1 of (P, 3, ...)
            ex = jnp.sum(e.reshape(e.shape + (1,) * (x.ndim - 2)) * x, axis=1, keepdims=True)
            return x - e.reshape(e.shape + (1,) * (x.ndim - 2)) * ex

        pos = self.points.positions(kin)
        wave = ramped(self.wave, self.ramp, t)
        w = normal(particle_velocity(wave, pos, t) - v3)
        f = (self.drag[:, None] * _safe_norm(w)[:, None] * w
             + self.inertia[:, None] * normal(particle_acceleration(wave, pos, t))
             - self.added[:, None] * normal(b3))
        return f, H3, normal(H3)

    def evaluate(self, ctx):
        f, H3, Hn = self._terms(ctx.kin, ctx.t)
        tau = jnp.einsum("pai,pa->i", H3, f)
        # −ρ C_A V (H q̈)_n: Σ_p ρ C_A V_p H_pᵀ (I − e eᵀ) H_p on the left-hand side
        mass = jnp.einsum("p,pai,paj->ij", self.added, H3, Hn) if self.has_added else None
        return LoadOutput(tau=tau, mass=mass)

    def _forces(self, ctx):
        """The whole force at each point (P, 3), the added-mass term of ``ctx.qdd`` included."""
        f, _, Hn = self._terms(ctx.kin, ctx.t)
        if not self.has_added:
            return f
        return f - self.added[:, None] * jnp.einsum("pai,i->pa", Hn, ctx.qdd)

    def reaction_loads(self, ctx, out):
        f = self._forces(ctx)
        F = jnp.concatenate([f, jnp.zeros_like(f)], axis=1).reshape(-1)
        return self.points.to_body_wrench(F, ctx.kin, ctx.model.n_bodies)

    def diagnostics(self, ctx, out):
        el = np.asarray(self.element)
        S = (np.arange(el.max() + 1)[:, None] == el[None]).astype(float)
        return {"morison_force": jnp.einsum("ep,pa->ea", S, self._forces(ctx))}

    def outputs(self):
        return {"coords": {"morison_element": list(self.names), "axis": ["x", "y", "z"]},
                "morison_force": (("morison_element", "axis"), {
                    "long_name": "Morison force on each element (½ ρ C_D A |u_n − v_n|(u_n − v_n) "
                                 "+ ρ (1 + C_A) V u̇_n − ρ C_A V v̇_n, summed over a strip), "
                                 "inertial axes", "units": "N"})}

    # -- a run
    def for_run(self, model, run):
        from hydro.wetted import WaveField, still

        spec = model.hydro
        if run.sea is None and run.n_components is None:
            wave = still(self.wave)
        else:
            # a batch's case: padded to the batch's most components (still water: all padding)
            comps = (run.sea.components(water_depth=spec.water_depth, g=spec.g)
                     if run.sea is not None else _no_components(spec))
            wave = WaveField.of(comps, pad_to=run.n_components, g=spec.g)
        return dataclasses.replace(self, wave=wave, ramp=device_array(float(run.ramp)))

    def static_load(self):
        from hydro.wetted import still

        return dataclasses.replace(self, wave=still(self.wave))

    def _rest(self, kin0):
        """At q₀: H's translational rows (P, 3, n_q), the normal projector I − e eᵀ (P, 3, 3)
        (I at a point element: e = 0) and the points' positions (P, 3), numpy."""
        from ..mechanics.points import h_matrix_at

        P = self.axis.shape[0]
        H3 = np.asarray(h_matrix_at(self.points, kin0)).reshape(P, 6, -1)[:, :3]
        R = np.asarray(self.points._frames(kin0)[1])
        e = np.einsum("pab,pb->pa", R, np.asarray(self.axis))
        Pn = np.eye(3)[None] - e[:, :, None] * e[:, None, :]
        return H3, Pn, np.asarray(self.points.positions(kin0), dtype=float)

    def _inertia_forces(self, kin0, omega, heading):
        """The inertia term's linear wave force at each point per unit complex wave amplitude,
        ρ (1 + C_A) V (I − e eᵀ) (−iω û) (n_ω, P, 3) (û: :func:`hydro.wetted.velocity_transfer`
        at the rest position), with H₃ and the positions of :meth:`_rest`."""
        from hydro.waves import wavenumber
        from hydro.wetted import velocity_transfer

        H3, Pn, pos = self._rest(kin0)
        omega = np.asarray(omega, dtype=float)
        depth = float(self.wave.water_depth)
        u = velocity_transfer(pos, omega, wavenumber(omega, depth, self.g),
                              np.full(omega.shape, float(heading)), depth)
        f = np.einsum("p,pab,wpb->wpa", np.asarray(self.inertia), Pn,
                      -1j * omega[:, None, None] * u)
        return f, H3, pos

    def frequency_terms(self, model, q0, kin0, omega, heading, options):
        """The wave force per unit amplitude about q₀: the inertia term's linear part

            F(ω, β) = Σ_p H_pᵀ ρ (1 + C_A) V_p (I − e_p e_pᵀ) u̇̂_p(ω, β),   u̇̂ = −iω û,

        û the flow's velocity at the point's rest position (0 above the mean surface), H_p its
        translational rows (ρ C_A V's added mass is in the mass already). The drag's slope at
        rest is 0: a frequency response per unit amplitude (no sea) leaves it out;
        :func:`mfm.spectral_response` linearises it stochastically on the sea's relative flow
        (:meth:`quadratic_drag`, :mod:`mfm.frequency.drag`)."""
        if not options.get("excitation", True):
            return FrequencyTerms()
        f, H3, _ = self._inertia_forces(kin0, omega, heading)
        return FrequencyTerms(force=np.einsum("pai,wpa->wi", H3, f))

    def frequency_body_loads(self, model, q0, kin0, omega, heading, options, x):
        """The inertia term's wave force of :meth:`frequency_terms` at the points, as body
        wrenches (the map of :meth:`~mfm.mechanics.points.BodyPoints.to_body_wrench`, linear: real
        and imaginary parts each); none without excitation."""
        omega = np.asarray(omega, dtype=float)
        if not options.get("excitation", True):
            return np.zeros((len(omega), model.n_bodies, 6), dtype=complex)
        f, _, _ = self._inertia_forces(kin0, omega, heading)
        F = np.concatenate([f, np.zeros_like(f)], axis=2).reshape(len(omega), -1)   # (n_ω, 6P)
        wrench = jax.vmap(lambda v: self.points.to_body_wrench(v, kin0, model.n_bodies))
        return (np.asarray(wrench(jnp.asarray(F.real))) + 1j * np.asarray(wrench(jnp.asarray(F.imag))))

    def quadratic_drag(self, model, kin0):
        """The drag ½ ρ C_D A |w_n| w_n of every point with C_D A > 0, w_n = (I − e eᵀ)(u − v) at
        its rest position, for the spectral level's stochastic linearisation on the relative
        normal flow (:mod:`mfm.frequency.drag`, the vector form: |·| the length)."""
        D = np.asarray(self.drag, dtype=float)
        keep = np.flatnonzero(D > 0)
        if keep.size == 0:
            return None
        H3, Pn, pos = self._rest(kin0)
        el = np.asarray(self.element)
        count = {}
        labels = []
        for p in range(len(D)):
            i = count.get(el[p], 0)
            count[el[p]] = i + 1
            labels.append(f"{self.names[el[p]]}[{i}]" if self.names else f"morison[{p}]")
        return QuadraticDrag(rows=np.einsum("pab,pbi->pai", Pn, H3)[keep], project=Pn[keep],
                             drag=D[keep], kind="vector", positions=pos[keep],
                             labels=tuple(labels[p] for p in keep))

    def host_view(self):
        # the names are the host's (outputs, provenance): loads that differ only in them share
        # one compilation
        return dataclasses.replace(self, names=(), kinds=())

    def provenance(self):
        return {"morison_elements": ", ".join(f"{n} ({k})" for n, k in zip(self.names, self.kinds))}

    # -- construction
    @classmethod
    def create(cls, model, body: str, *, point=None, start=None, end=None, segments=None,
               cd: float, diameter=None, area=None, ca: float = 0.0, volume=None,
               name: str | None = None) -> "MorisonElements":
        """One element on ``body`` from Python, as a ``[[morison]]`` entry would give it: a point
        (``point``) or a strip from ``start`` to ``end`` (the table's ``from``, ``to``) in
        ``segments``; the same checks and errors."""
        entry = {"body": body, "cd": cd, "ca": ca}
        for key, v in (("point", point), ("from", start), ("to", end)):
            if v is not None:
                entry[key] = np.asarray(v, dtype=float).tolist()
        for key, v in (("segments", segments), ("diameter", diameter), ("area", area),
                       ("volume", volume), ("name", name)):
            if v is not None:
                entry[key] = v
        return cls.from_parsed(cls.parse_table([entry], list(model.body_names)), model)

    # -- config
    @staticmethod
    def parse_table(raw, names):
        out = []
        for i, (where, t) in enumerate(tables(raw, "morison", KEYS)):
            body = body_ref(t, "body", where, names)
            item = {"where": where, "body": body,
                    "name": element_name(t, where, f"{body}_morison{i}")}
            strip = "from" in t or "to" in t
            if strip == ("point" in t):
                raise ConfigError(f"{where}: give either point = [x, y, z] (a point element) or "
                                  "from = [x, y, z], to = [x, y, z] and segments = N (a strip), "
                                  f"not {'both' if strip else 'neither'}")
            if strip:
                for key in ("from", "to", "segments"):
                    if key not in t:
                        raise ConfigError(f"{where}.{key}: missing; a strip takes from = [x, y, z], "
                                          "to = [x, y, z] (m, inertial axes at rest) and segments "
                                          "= N (a whole number ≥ 1 of integration segments)")
                a, b = vector(t["from"], 3, f"{where}.from"), vector(t["to"], 3, f"{where}.to")
                if not np.linalg.norm(b - a) > 0:
                    raise ConfigError(f"{where}: from and to are one point {a.tolist()}; a strip "
                                      "needs a length (or give point = [x, y, z])")
                n = t["segments"]
                if isinstance(n, bool) or not isinstance(n, int) or n < 1:
                    raise ConfigError(f"{where}.segments: {n!r}; give a whole number ≥ 1 of "
                                      "segments (the strip's integration points, at their "
                                      "midpoints)")
                item.update(kind="strip", start=a, end=b, segments=n)
            else:
                if "segments" in t:
                    raise ConfigError(f"{where}.segments: a point element has no segments; give "
                                      "from/to for a strip, or leave segments out")
                item.update(kind="point", point=vector(t["point"], 3, f"{where}.point"))
            if "cd" not in t:
                raise ConfigError(f"{where}.cd: missing; give the drag coefficient C_D ≥ 0 (e.g. "
                                  "1.0 for a cylinder in the drag-dominated regime, 0 for none)")
            for key, default, what in (("cd", None, "a drag coefficient ≥ 0"),
                                       ("ca", 0.0, "an added-mass coefficient ≥ 0 (1 for a "
                                                   "circular cylinder)")):
                v = number(t.get(key, default), f"{where}.{key}")
                if v < 0:
                    raise ConfigError(f"{where}.{key}: {t[key]!r}; give {what}")
                item[key] = v
            if ("diameter" in t) == ("area" in t):
                raise ConfigError(f"{where}: give diameter (m) or area (m², per metre of a strip), "
                                  f"{'not both' if 'area' in t else 'one of them'}")
            for key in ("diameter", "area", "volume"):
                if key in t:
                    v = number(t[key], f"{where}.{key}")
                    if v < 0 or (v == 0 and key != "volume"):
                        raise ConfigError(f"{where}.{key}: {t[key]!r}; give a {'positive' if key != 'volume' else 'non-negative'} "
                                          f"{'length in m' if key == 'diameter' else 'area in m²' if key == 'area' else 'volume'}")
                    item[key] = v
            D = item.get("diameter")
            if strip:
                item["A"] = D if D is not None else item["area"]                 # m²/m
                item["V"] = item.get("volume", math.pi * D**2 / 4 if D is not None else 0.0)
            else:
                item["A"] = math.pi * D**2 / 4 if D is not None else item["area"]   # m²
                item["V"] = item.get("volume", 0.0)
            if item["ca"] > 0 and item["V"] == 0:
                raise ConfigError(f"{where}.ca: {item['ca']:g} on an element of no volume; give "
                                  "volume (m³ for a point, m³ per metre for a strip) or a "
                                  "strip's diameter")
            out.append(item)
        unique_names(out, "morison")
        return out

    @classmethod
    def from_parsed(cls, parsed, model):
        from hydro.wetted import WaveField

        spec = model.hydro
        if spec is None:
            raise ConfigError(f"{parsed[0]['where']}: [[morison]] elements need the model's "
                              "[hydro] (the water's density, gravity and depth, and its sea); "
                              "add a [hydro] table")
        rho = float(spec.rho)
        idx, pts, axis, drag, inertia, added, element = [], [], [], [], [], [], []
        for e, t in enumerate(parsed):
            if t["kind"] == "strip":
                n, a, b = t["segments"], t["start"], t["end"]
                L = float(np.linalg.norm(b - a))
                mids = a + (b - a) * ((np.arange(n) + 0.5) / n)[:, None]
                w, ax = L / n, (b - a) / L
            else:
                n, mids, w, ax = 1, t["point"][None], 1.0, np.zeros(3)
            i = model.body_index(t["body"])
            # the axis in body axes: at rest the bodies' frames are the inertial axes (E = I at
            # q = 0, as the points' d_ref)
            for p in mids:
                idx.append(i)
                pts.append(p)
                axis.append(ax)
                drag.append(0.5 * rho * t["cd"] * t["A"] * w)
                inertia.append(rho * (1 + t["ca"]) * t["V"] * w)
                added.append(rho * t["ca"] * t["V"] * w)
                element.append(e)
        f = lambda x: device_array(np.asarray(x, dtype=np.float64))  # noqa: E731
        z = f(np.zeros(0))
        wave = WaveField(z, z, z, z, z, float(spec.water_depth))      # still water until a run
        return cls(points=BodyPoints.on_bodies(model.com, idx, pts), axis=f(axis), drag=f(drag),
                   inertia=f(inertia), added=f(added), wave=wave, ramp=f(0.0),
                   element=tuple(element), names=tuple(t["name"] for t in parsed),
                   kinds=tuple(t["kind"] for t in parsed), rho=rho, g=float(spec.g),
                   has_added=bool(np.any(np.asarray(added) > 0)))
