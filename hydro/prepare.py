"""Hydro preparation: a database made ready for both domains, apart from the mechanics.

:class:`HydroSpec` restricts a database to the wet bodies of a model (in model order), symmetrises
A(ω), B(ω), A∞ (reciprocity), applies the body-coupling mask, corrects A∞ to be consistent with
A(ω) and B(ω), and computes on demand (cached) the impulse response K(t), its memory length, the
convolution weights of a time step and the passive state-space fit. :func:`modal_form` realises a
fit in modal form; :func:`open_any_database` opens any database file by its type (above the
schema and the readers, so none of them imports another in a circle). Nothing here imports :mod:`mfm`: the mechanics hands in where each
body's reference point sits (``com0``, ``body_index``) and which dofs its joints move (``moving``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np
import xarray as xr

from .checks import check_netcdf_file
from .database import _ours, from_capytaine, read_netcdf
from .wamit import read_wamit


class HydroSpec:
    """Host-side description of a model's water, made by :func:`mfm.load` from the config's
    ``[hydro]`` table: the database restricted to the config's bodies (in config order), where
    each hydro body sits on the tree, drag, and the options. Impulse responses and state-space fits
    are computed on demand and cached here (per dt and per radiation option).

    ``body_index``: the model index of each hydro body (the mechanics' bookkeeping, carried along);
    ``com0`` (K, 3): each body's centre of mass at q = 0; ``drag`` (K, 3): C_D A per inertial axis
    (m²); ``moving``: the hydro dofs the mechanics can move (radiation is modelled on these).

    Hashed and compared by content (:meth:`fingerprint`: the database's every array and attribute,
    the bodies, drag and options): it rides on the Model as static metadata, part of each compiled
    function's cache key, so the same config loaded twice (a test's fixture, a notebook re-run, a
    sweep's unpickled copy) reuses the first one's compilations instead of compiling again, while
    any difference in the data compiles anew.
    """

    def __init__(self, db: xr.Dataset, body_index: Sequence[int], config_names: Sequence[str],
                 com0: np.ndarray, drag: np.ndarray, *, body_coupling: bool = True,
                 added_mass_inf: str = "consistent", source: str = "", moving=None):
        from .database import validate

        self.db_names = [str(b) for b in db["body"].values]
        self.config_names = list(config_names)
        self.body_index = tuple(int(i) for i in body_index)
        self.body_coupling = bool(body_coupling)
        self.source = source
        validate(db, source=source or None)
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

    def replace(self, *, body_coupling: bool | None = None, moving=None) -> "HydroSpec":
        """A copy with other options (the same database, bodies and drag; its own caches, so its
        fits and kernels are made anew): ``body_coupling`` (True, False; None keeps this one's),
        ``moving`` (indices of the hydro dofs radiation is modelled on; None keeps this one's).
        The copy is kept in this spec's cache: asked again, the same object answers, with the
        fits and kernels it has made."""
        import copy

        if body_coupling is not None and not isinstance(body_coupling, bool):
            raise ValueError(f"body_coupling: {body_coupling!r}; accepted: True, False or None "
                             "(keep the spec's)")
        if moving is not None:
            try:
                moving = tuple(sorted(int(k) for k in moving))
            except (TypeError, ValueError):
                raise ValueError(f"moving: {moving!r}; give indices of the hydro dofs") from None
            if not moving or moving[0] < 0 or moving[-1] >= len(self.dofs) \
                    or len(set(moving)) != len(moving):
                raise ValueError(f"moving: {moving!r}; give distinct indices in "
                                 f"[0, {len(self.dofs)}) of the hydro dofs")
        key = ("replace", body_coupling, moving)
        if key in self._cache:
            return self._cache[key]
        new = copy.copy(self)
        new._cache = {}
        if body_coupling is not None:
            nb = len(self.db_names)
            new.body_coupling = body_coupling
            new.mask = (np.ones((6 * nb, 6 * nb)) if body_coupling
                        else np.kron(np.eye(nb), np.ones((6, 6))))
            A_inf = np.asarray(self.db["added_mass_inf"].values, dtype=float)
            new.A_inf_db = 0.5 * (A_inf + A_inf.T) * new.mask
        if moving is not None:
            new.moving = moving
        self._cache[key] = new
        return new

    def fingerprint(self) -> str:
        """sha256 of everything the spec holds: the database's every array and attribute (hashed
        once: the dataset is not modified in place) and each of the spec's own attributes, hashed
        on every call (microseconds) so that an attribute set after the spec was made counts."""
        import hashlib

        def add(h, *items):
            # containers item by item, so an array inside an attribute dict or a tuple is hashed by
            # its bytes (its repr elides the middle of a large array)
            for x in items:
                if isinstance(x, dict):
                    h.update(f"dict{len(x)}".encode())
                    for k in sorted(x, key=repr):
                        add(h, k, x[k])
                    continue
                if isinstance(x, (list, tuple)):
                    h.update(f"{type(x).__name__}{len(x)}".encode())
                    add(h, *x)
                    continue
                a = np.asarray(x) if not isinstance(x, (str, bytes)) else None
                if a is not None and a.dtype.kind in "fciub":
                    h.update(f"{a.dtype.str}{a.shape}".encode())
                    h.update(np.ascontiguousarray(a).tobytes())
                else:
                    h.update(repr(x).encode())

        if "db_fingerprint" not in self._cache:
            h = hashlib.sha256()
            for name in sorted(map(str, self.db.variables)):
                v = self.db.variables[name]
                add(h, name, v.dims, v.values, dict(v.attrs))
            # when a WAMIT file set was read is provenance, not data
            add(h, {k: v for k, v in self.db.attrs.items() if k != "date_read"})
            self._cache["db_fingerprint"] = h.hexdigest()
        h = hashlib.sha256(self._cache["db_fingerprint"].encode())
        for k in sorted(vars(self)):
            if k not in ("db", "_cache"):
                add(h, k, getattr(self, k))
        return h.hexdigest()

    def __eq__(self, other):
        return self is other or (isinstance(other, HydroSpec)
                                 and self.fingerprint() == other.fingerprint())

    def __hash__(self):
        return hash(self.fingerprint())

    def provenance(self) -> dict:
        """Where the data came from and how they are used, for a result's attributes."""
        if "sha256" not in self._cache:
            import hashlib

            h = hashlib.sha256()
            p = Path(self.source)
            if p.is_dir() or p.name.lower() == "nemoh.cal":      # a NEMOH run: its inputs/results
                run = p if p.is_dir() else p.parent
                files = sorted(f for pat in ("Nemoh.cal", "[Rr]esults/*.tec", "[Mm]esh/*.dat")
                               for f in run.glob(pat))
            else:
                files = [p] if p.suffix == ".nc" else sorted(p.parent.glob(p.stem + ".*"))
            for f in files:
                if f.is_file():
                    h.update(f.read_bytes())
            self._cache["sha256"] = h.hexdigest() if files else ""
        return {"database": self.source, "database_sha256": self._cache["sha256"],
                "body_coupling": str(self.body_coupling),
                "added_mass_inf": self.added_mass_inf_option, "rho": self.rho, "g": self.g,
                "water_depth": self.water_depth}

    @property
    def stored_in(self) -> str | None:
        """The database file that may store this water's fits and values (``mfm fits``,
        :mod:`hydro.fitstore`): the config's NetCDF database, else None."""
        return self.source if str(self.source).endswith(".nc") else None

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
        from .radiation import impulse_response

        return np.asarray(impulse_response(self.database(), np.asarray(t)).values)

    def memory(self, rtol: float = 1e-3) -> float:
        """Memory length T_K (s): where |K| stays below rtol·max|K| (from the decay of K, not Tp)."""
        key = ("memory", float(rtol))
        if key not in self._cache:
            from .fitcache import cached_value
            from .radiation import impulse_response_memory

            t = np.arange(0.0, 400.0, 0.05)
            # memory_length(impulse_response(t), t, rtol), K not formed for every time and entry;
            # kept by the database's content (hydro.fitcache): ~0.4 s of every first run
            self._cache[key] = float(cached_value(
                self.database(), "memory", {"rtol": float(rtol)},
                lambda: impulse_response_memory(self.database(), t, rtol=rtol),
                stored=self.stored_in))
        return self._cache[key]

    def added_mass_inf(self) -> np.ndarray:
        """A∞ used in the time domain. 'consistent': the database's plus the constant (the median
        over :meth:`radiation_band`) that makes A∞ − ∫K sin ωt dt/ω agree with the database A(ω)
        (a BEM A∞ can be off by a constant: RM3's spar pitch by 2.7 %; outside the band the data
        are too noisy to weigh); 'database': as given."""
        if self.added_mass_inf_option == "database":
            return self.A_inf_db
        if "A_inf" not in self._cache:
            from .fitcache import cached_value

            # kept by the database's content and the coupling mask (hydro.fitcache): up to 1.6 s
            # of every first run (Wu & Yuan)
            self._cache["A_inf"] = cached_value(self.database(), "added_mass_inf_consistent",
                                                {"mask": np.asarray(self.mask, float)},
                                                self._consistent_added_mass_inf,
                                                stored=self.stored_in)
        return self._cache["A_inf"]

    def _consistent_added_mass_inf(self) -> np.ndarray:
        """:meth:`added_mass_inf`'s 'consistent' A∞, made."""
        from .radiation import impulse_response_transform

        db = self.database()
        om = np.asarray(db["omega"].values)
        t = np.arange(0.0, max(2 * self.memory(), 60.0), min(0.02, np.pi / om.max() / 4))
        # A(ω) rebuilt from K by Ogilvie (hydro.radiation.added_mass_from_irf: A∞ − ∫K sin ωt
        # dt / ω), with ∫K e^{−iωt} dt formed as one linear map of the damping nodes, K itself
        # not formed (n_t × n_dof² values: 23,440 × 8,100 for Wu & Yuan); the same numbers up
        # to round-off (tests/test_hydro_radiation.py)
        T = impulse_response_transform(db, t, om)           # Im T = −∫ K sin ωt dt
        A_rebuilt = self.A_inf_db[None] + T.imag / om[:, None, None]
        lo, hi = self.radiation_band()
        sel = (om >= lo) & (om <= hi)
        # the median: robust to the stretches of a BEM grid where A(ω) is noisy or irregular
        delta = np.median(np.asarray(db["added_mass"].values)[sel] - A_rebuilt[sel], axis=0)
        delta = delta * self.mask
        return self.A_inf_db + 0.5 * (delta + delta.T)

    def radiation_band(self, fraction: float = 0.05):
        """(ω_lo, ω_hi): where some diagonal damping B_ii(ω) is at least ``fraction`` of its own
        peak: the band where radiation matters and the BEM data are meaningful (above it, BEM
        damping is numerical noise; CAPYTAINE.md). Diagonals below 1e-6 of the largest (by
        dimension group) are ignored (:func:`hydro.radiation.radiation_band` of the database)."""
        from .radiation import radiation_band

        db = self.database()
        return radiation_band(db["omega"].values, db["radiation_damping"].values, fraction)

    def wave_band(self) -> tuple[float, float]:
        """(0.2 ω_c, 2 ω_c) clipped to the grid, ω_c = √(g/L) the Froude frequency of the cube root
        L of the largest displaced volume: where the waves act on these bodies (RM3 0.2–2.0 rad/s,
        M4 1.2–12 rad/s). The band the state-space fit fits and the grid check judges."""
        om = np.asarray(self.db["omega"].values)
        wc = math.sqrt(self.g / float(np.max(self.volume)) ** (1.0 / 3.0))
        return (max(0.2 * wc, float(om[0])), min(2.0 * wc, float(om[-1])))

    def check_grid(self, memory_length: float) -> float:
        """:func:`hydro.radiation.check_grid` of a kernel of length `memory_length` (s) as a run
        uses it: the dofs the model moves, the wave band (:meth:`wave_band`); warns.

        The warning names what the user can do (:func:`grid_advice`) instead of only the step
        π/T_K: T_K is measured on the interpolated K, which holds the grid's own alias of K near
        2π/Δω, so π/T_K asks for a step finer than the one that would pass (issue 51: dω for
        T_K = 353 s, a grid no one makes) and grows again with each refinement."""
        import warnings

        from .database import HydroDatabaseWarning
        from .radiation import check_grid

        db = self.database()
        band = self.wave_band()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ratio = check_grid(db, memory_length, on_fail="warn", band=band, dofs=self.moving)
        for w in caught:
            text = str(w.message)
            if issubclass(w.category, HydroDatabaseWarning) and "too coarse" in text:
                text = grid_advice(db, memory_length, ratio, text, band=band)
            warnings.warn(text, w.category, stacklevel=2)
        return ratio

    def state_space(self, **options):
        """The passive state-space fit of :mod:`hydro.statespace` (cached per options). The fit
        band defaults to (0.2 ω_c, 2 ω_c) with the Froude frequency ω_c = √(g/L), L the cube root
        of the largest displaced volume: RM3's (0.2, 2.0) rad/s at full scale, 1.2–12 rad/s for the
        M4 model, so each database is fitted where its waves act (clipped to its grid). Only the
        dofs the model moves are fitted (:attr:`moving`), with one common pole set when more
        than two bodies are coupled (``pole_sharing``, :func:`hydro.statespace.fit_state_space`).
        A fit made before, in this process or an earlier one, is read back (:mod:`hydro.fitcache`).
        """
        options.setdefault("dofs", tuple(self.dofs[k] for k in self.moving))
        # many coupled bodies: one pole set for all entries (states O(n_dof · order) instead of
        # the per-entry fit's O(n_dof² · order))
        many = self.body_coupling and len(self.db_names) > 2
        options.setdefault("pole_sharing", "common" if many else "entry")
        if "omega_fit" not in options:
            options["omega_fit"] = self.wave_band()
        key = ("ss", tuple(sorted(options.items())))
        if key not in self._cache:
            from .fitcache import cached_fit

            # kept by content, in the process and on disk (hydro.fitcache), or stored in the
            # database file by `mfm fits` (hydro.fitstore): seconds per fit
            self._cache[key] = cached_fit(self.database(), stored=self.stored_in, **options)
        return self._cache[key]

    def kernel(self, dt: float, memory: float | None = None, subdivisions: int = 16,
               offsets=(0.0, 0.5, 1.0)):
        """Convolution weights for the stage offsets s of a step (``offsets``: fractions of dt in
        [0, 1], those of the integrator; RK4's are 0, ½, 1).

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
        offsets = tuple(float(o) for o in offsets)
        if not all(0.0 <= o <= 1.0 for o in offsets):
            raise ValueError(f"stage offsets {offsets}: each must lie in [0, 1] (fractions of dt)")
        key = ("W", float(dt), n, subdivisions, offsets)
        if key not in self._cache:
            self.check_grid((n - 1) * dt)
            h = dt / subdivisions
            tau = np.arange((n + 1) * subdivisions + 1) * h     # up to s + (N−1) dt + … ≤ (N+1) dt
            mv = np.asarray(self.moving)
            K = self.impulse_response(tau)[:, mv][:, :, mv]
            wq = np.full(len(tau), h)
            wq[0] = wq[-1] = 0.5 * h
            Wc, W = [], []
            for off in offsets:
                s = off * dt
                knots = s + np.arange(n) * dt                 # history knots
                if s > 0:
                    knots = np.concatenate([[0.0], knots])      # the current velocity at τ = 0
                inside = tau <= knots[-1] + 1e-12
                k = np.clip(np.searchsorted(knots, tau[inside], side="right") - 1, 0, len(knots) - 2)
                frac = (tau[inside] - knots[k]) / (knots[k + 1] - knots[k])
                Kw = K[inside] * wq[inside][:, None, None]
                # each sample feeds its two hat functions (k sorted: sums by segments, no dense φ)
                Wk = (_segment_sums(k, Kw * (1.0 - frac)[:, None, None], len(knots))
                      + _segment_sums(k + 1, Kw * frac[:, None, None], len(knots)))
                if s > 0:
                    Wc.append(Wk[0])
                    W.append(Wk[1:])
                else:
                    Wc.append(np.zeros_like(Wk[0]))
                    W.append(Wk)
            self._cache[key] = (np.stack(Wc), np.stack(W))
        return self._cache[key]


def grid_advice(db, memory_length: float, ratio: float, message: str, *, band=None,
                tol: float = 0.05) -> str:
    """The grid check's message (:func:`hydro.radiation.check_grid`) with what the user can do.

    The check fails when K beyond t_N = π/Δω, the part the ω grid cannot tell from its own
    alias, changes the radiation impedance by E > tol (``ratio`` = E/tol). Three ways out:

    - ``radiation="state_space"``: fits A(ω), B(ω) on the grid itself; no K beyond it is used.
    - ``memory = t_N``: the window the grid resolves; the impedance then misses that same part.
    - a finer grid. Linear interpolation of B attenuates the alias image of K's peak by
      sinc²: its size goes as Δω² (check_grid's docstring), so when the excess is the alias the
      step Δω·sqrt(1/ratio)/1.5 passes (the 1.5: a margin for K's own tail). When K's own memory
      is that long the step must reach π/T_K; which of the two holds is not known from the grid
      alone, so both are given, each with its n_omega over the grid's range. π/T_K alone was the
      old advice: for a T_K of the alias image it asks for a grid no one makes.
    """
    om = np.asarray(db["omega"].values, dtype=float)
    lo, hi = (om[0], om[-1]) if band is None else (float(band[0]), float(band[1]))
    d = np.diff(om)
    meet = (om[1:] >= lo) & (om[:-1] <= hi)
    dw = float(d[meet].max() if meet.any() else d.max())
    t_N = math.pi / dw
    span = float(om[-1] - om[0])
    alias = dw * math.sqrt(1.0 / max(ratio, 1.0)) / 1.5
    own = math.pi / memory_length
    head = message.split(" Recompute the database")[0].rstrip(". ")
    return (f"{head}. What you can do: (1) radiation='state_space' (mfm.simulate(..., "
            f"radiation='state_space'); mfm simulate --radiation state_space): it fits A(ω), "
            f"B(ω) on this grid and uses no K beyond it; (2) memory={t_N:.4g} "
            f"(mfm.simulate(..., memory={t_N:.4g})): the kernel window this grid resolves, "
            f"π/Δω, K beyond it dropped; (3) a finer ω grid: when the excess is the grid's alias "
            f"of K (K decayed within π/Δω; its size goes as Δω²) a step of about {alias:.3g} "
            f"rad/s (n_omega ≈ {int(math.ceil(span / alias)) + 1} over {om[0]:.4g}–"
            f"{om[-1]:.4g} rad/s, now {len(om)}); only when K's own memory is T_K = "
            f"{memory_length:.4g} s does it need {own:.3g} rad/s (n_omega ≈ "
            f"{int(math.ceil(span / own)) + 1}).")


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


def open_any_database(path, *, names=None, rho=None, g=None) -> xr.Dataset:
    """Any hydro database file as the internal schema (:func:`_open_any`: every reader), checked
    by the one validation behind all of them (:func:`hydro.database.validate`'s errors, naming
    `path`; its warnings come when a model uses the database)."""
    from .database import validate

    return validate(_open_any(path, names=names, rho=rho, g=g), source=str(path), warn=False)


def _open_any(path, *, names=None, rho=None, g=None) -> xr.Dataset:
    """Any hydro database as the internal schema, in memory, by what `path` names:

    - a ``.nc``: our NetCDF (:func:`to_netcdf`), a capytaine 3 file of ``mfm hydro`` /
      ``hydro.bem.save`` (:func:`from_capytaine`), or a capytaine file of another version or
      made without ``mfm hydro`` (:func:`hydro.formats.from_other_capytaine`: complex dim,
      scalar settings, no ω = ∞, hydrostatics from the KH/Hydrostatics files beside it);
    - a NEMOH run: its folder, its ``Nemoh.cal`` or its ``Results/`` (:func:`hydro.nemoh.read_nemoh`,
      v2 and v3);
    - WAMIT output: the ``.out`` (or ``.1``/``.3``/``.hst``, or the stem) of a run with its
      ``.1``/``.3``/``.hst`` beside it (:func:`hydro.wamit.read_wamit`);
    - a BEMIO HDF5 file, ``.h5`` (WEC-Sim's and SEA-Stack's; :func:`hydro.bemio.read_bemio`).

    `names`: the bodies in the file's order (WAMIT, NEMOH: their names; another capytaine's file:
    renames them; ignored for the project's own files, whose names are the config's). `rho`, `g`: WAMIT's and BEMIO's scaling (as :func:`hydro.wamit.read_wamit` takes
    them); for NEMOH and other capytaine files (dimensional) they must equal the file's, or the
    call is refused. A
    NetCDF file is read once, whole (:func:`read_netcdf`): safe while the process holds it open.
    """
    from . import bemio, formats, nemoh

    path = Path(path)
    if bemio.is_bemio(path):
        return bemio.read_bemio(path, body_names=names, rho=rho, g=g)
    if path.suffix == ".nc":
        if not path.exists():
            raise FileNotFoundError(f"hydro.database: {str(path)!r} not found; generate it with "
                                    "`mfm hydro CONFIG` or fix the path (relative to the config)")

        raw = read_netcdf(check_netcdf_file(path))
        if "added_mass_inf" in raw.data_vars:
            return _ours(raw)                                # ours has A∞ as a variable
        if ("waterplane_stiffness" in raw.data_vars and "omega" in raw.coords
                and np.any(np.isinf(np.asarray(raw["omega"].values, dtype=float)))):
            return from_capytaine(raw, source=path)          # mfm hydro's capytaine file
        # (the project's own files keep their behaviour: names and rho there are the generator's)
        db = formats.from_other_capytaine(raw, path, names=names)
        _same_setting(db, path, rho=rho, g=g)
        return db
    if path.is_dir() or path.name.lower() == "nemoh.cal":
        if nemoh.is_nemoh(path):
            return nemoh.read_nemoh(nemoh.find_nemoh_cal(path), body_names=names, rho=rho, g=g)
        raise FileNotFoundError(f"hydro.database: {str(path)!r} is a folder without a Nemoh.cal; "
                                "accepted: a NetCDF database (.nc), a BEMIO file (.h5), a NEMOH run "
                                "(its folder or Nemoh.cal) or a WAMIT .out/.1/.3/.hst set")

    stem = path.with_suffix("") if path.suffix in (".out", ".1", ".3", ".hst") else path
    if not stem.with_suffix(".out").exists():
        raise FileNotFoundError(f"hydro.database: {str(path)!r}: no WAMIT output {stem}.out and not "
                                "a .nc file or a NEMOH run; accepted: a NetCDF database (.nc), a "
                                "BEMIO file (.h5), a NEMOH run (its folder or Nemoh.cal) or a WAMIT "
                                ".out/.1/.3/.hst set")
    kw = {}
    if rho is not None:
        kw["rho"] = float(rho)
    if g is not None:
        kw["g"] = float(g)
    return read_wamit(stem, body_names=names, **kw)


def _same_setting(db, path, **given):
    """A dimensional database (NetCDF) was computed with its rho and g: a config asking for others
    is refused (they cannot be rescaled here)."""
    for name, v in given.items():
        if v is not None and not np.isclose(float(v), float(db.attrs[name]), rtol=1e-6):
            raise ValueError(f"hydro.{name} = {v} differs from the {name} = {db.attrs[name]} of "
                             f"{str(path)!r}, whose coefficients are dimensional; drop hydro.{name} "
                             f"or set it to {db.attrs[name]}")
