"""Sea states and their discretisation into linear wave components.

Convention (the project's, capytaine's, time dependence e^{-iωt}): a component j of amplitude a_j
(m), frequency ω_j (rad/s), phase φ_j (rad), heading β_j (rad, 0 = travelling towards +x) and
wavenumber k_j (rad/m) has the elevation

    η_j(x, y, t) = a_j cos(k_j (x cos β_j + y sin β_j) − ω_j t + φ_j)
                 = Re[a_j e^{iφ_j} e^{i(k_j (x cos β_j + y sin β_j) − ω_j t)}],

so a_j e^{iφ_j} is the complex amplitude at the origin, and the excitation it causes is
Re[a_j e^{iφ_j} X(ω_j, β_j) e^{−iω_j t}] (see `hydro.excitation`).

Sea states are immutable descriptions; `.components(water_depth, g)` discretises one into a
`WaveComponents` object:

Every heading is in radians (0 = towards +x); a sea's heading beyond ±2π (degrees given where
radians are meant) is refused by `check_heading`, naming the fix ``math.radians(...)``.

- `Regular(height, period, heading, phase)`: one component, a = H/2.
- `Jonswap`, `PiersonMoskowitz`, `UserSpectrum`: one-sided spectra S(ω) (m² s/rad) discretised with
  a_j = sqrt(2 S(ω_j) Δω_j) and seeded uniform phases. Frequencies:
  * with `repeat_period` T_R (Stansby & Li 2024 §5): every multiple of 2π/T_R inside `omega_range`
    (Δω_j = 2π/T_R), or, if `n_components` is also given, that many multiples of 2π/T_R spread
    evenly over the range (Δω_j = the spacing between neighbours). The elevation then repeats
    exactly with period T_R.
  * without: `n_components` equal bins of width Δω over `omega_range`; ω_j is the bin centre moved
    by a seeded uniform offset of ±`frequency_jitter`·Δω/2, which breaks the 2π/Δω periodicity of an
    equally spaced comb while keeping neighbours at least (1 − jitter)·Δω apart.
- `MeasuredElevation(t, eta)`: a measured record at the origin decomposed by FFT; it reproduces the
  record (minus its mean) at the sample times and repeats with the record length.

Directional spreading (`Spreading`) uses the random-directional method of Stansby & Li 2024 §5: every
frequency component gets one direction drawn from the spreading distribution, so no two components
share a frequency and the field is ergodic.

Random numbers: one `numpy.random.SeedSequence(seed)` spawns three independent streams (frequency
jitter, phases, directions), so switching spreading on or off leaves the phases unchanged.
"""
from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field

import numpy as np

# scipy (integrate, special) is imported where used, not here: it was ~0.5 s of every process's
# import of mfm, and only a JONSWAP's normalisation and a directional spread need it

__all__ = [
    "WaveComponents",
    "Regular",
    "Jonswap",
    "PiersonMoskowitz",
    "UserSpectrum",
    "MeasuredElevation",
    "Spreading",
    "check_heading",
    "wavenumber",
    "elevation",
    "ramp",
    "jonswap_normalisation",
    "jonswap_spectrum",
]

G_STANDARD = 9.81  # m/s², the project default (databases carry their own g in attrs)
DEFAULT_N_COMPONENTS = 200
# Default band of the parametric spectra, in multiples of the peak frequency ωp. Below 0.5 ωp the
# spectrum is < 1e-7 of its peak; above 5 ωp the ω⁻⁵ tail holds (5/4)/5⁴ = 0.2 % of m0 for
# Pierson–Moskowitz (less for γ > 1), i.e. 4√m0 is 0.1 % below Hs. Pass omega_range to change it
# (e.g. to stay inside a hydrodynamic database's frequency grid).
DEFAULT_BAND = (0.5, 5.0)
# The least fraction of a spectrum's variance a sea's band may keep without a SeaStateWarning:
# 0.9, i.e. the sea's Hs within 5 % (√0.9 = 0.949) of the stated one. The default band keeps
# 0.998; the cut bands of the shipped studies keep >= 0.95 (M4's (1, 25) rad/s for Tp 0.8–1.8 s,
# Stansby & Li's (0.2, 2) for Tp 8–16 s, Hallak's (0.35, 2) for Tp 7 s).
BAND_ENERGY_MIN = 0.9


class SeaStateWarning(UserWarning):
    """A sea state that is valid but not the sea its arguments state (e.g. an omega_range that
    cuts off much of the spectrum's energy): the message gives the measure and the fix."""

# Chunk size of the time loop: at most this many complex entries (16 bytes each) are held at once.
_CHUNK_ENTRIES = 1 << 20


# ----------------------------------------------------------------------------------------------
# validation helpers


def _positive(name: str, value, fix: str = "") -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be finite and > 0, got {value!r}{fix}")
    return v


def _finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


def check_heading(value, name: str = "heading") -> float:
    """A wave heading in radians: finite; beyond ±2π it warns (:class:`SeaStateWarning`). The one
    check of every sea's heading (Regular, Jonswap, PiersonMoskowitz, UserSpectrum,
    MeasuredElevation: their mean heading, which a Spreading spreads about). A value beyond 2π is
    most likely a heading in degrees given where radians are meant (``heading=30`` runs at 30 rad =
    1718.9°): the warning names the value and the fix (``math.radians(30)``). It still runs, taken
    modulo 2π (β + 2π is the same heading: the excitation wraps it)."""
    v = _finite(name, value)
    if abs(v) > 2.0 * math.pi * (1.0 + 1e-12):
        warnings.warn(
            f"{name} = {value!r} rad ({math.degrees(v):.6g}°) is beyond ±2π: headings are in "
            f"radians (0 = waves travelling towards +x). If {value!r} is in degrees, give "
            f"{name}=math.radians({value!r}) (= {math.radians(v):.6g} rad); the command line's "
            "--heading takes degrees.", SeaStateWarning, stacklevel=4)
    return v


def _seed(value) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"seed must be a non-negative integer (reproducible phases), got {value!r}")
    return int(value)


def _n_components(value) -> int | None:
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"n_components must be an integer >= 1 (or None), got {value!r}")
    return int(value)


def _omega_range(value) -> tuple[float, float] | None:
    if value is None:
        return None
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"omega_range must be a pair (omega_min, omega_max) in rad/s, got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(
            f"omega_range must satisfy 0 < omega_min < omega_max (rad/s, finite), got {value!r}"
        )
    return (lo, hi)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


def _readonly_float(name: str, value) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (no NaN/inf)")
    return _readonly(a)


def _water_depth(value) -> float:
    try:
        h = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"water_depth must be a real number or inf, got {value!r}") from None
    if math.isnan(h) or h <= 0.0:
        raise ValueError(f"water_depth must be > 0 (m) or inf for deep water, got {value!r}")
    return h


# ----------------------------------------------------------------------------------------------
# dispersion


def wavenumber(omega, water_depth: float = math.inf, g: float = G_STANDARD) -> np.ndarray:
    """Wavenumber k (rad/m) solving the linear dispersion relation ω² = g k tanh(k h).

    omega: rad/s, array (any shape) of values >= 0. water_depth h: m, > 0, `inf` for deep water
    (k = ω²/g). Vectorised Newton iteration on x = k h for y = ω² h / g (x tanh x = y), started from
    Eckart's approximation x₀ = y / sqrt(tanh y); converges to machine precision in a few steps.
    """
    w = np.asarray(omega, dtype=np.float64)
    g = _positive("g", g)
    h = _water_depth(water_depth)
    if np.any(~np.isfinite(w)) or np.any(w < 0.0):
        raise ValueError("omega must be finite and >= 0 (rad/s) to compute a wavenumber")
    k_deep = w * w / g
    if math.isinf(h):
        return k_deep
    y = (k_deep * h).reshape(-1)
    x = np.zeros_like(y)
    pos = y > 0.0
    x[pos] = y[pos] / np.sqrt(np.tanh(y[pos]))
    # tanh(x) == 1 in float64 beyond x ≈ 19.1, so there x = y exactly (deep water within rounding).
    x[y >= 20.0] = y[y >= 20.0]
    act = np.flatnonzero(pos & (y < 20.0))
    for _ in range(40):
        if act.size == 0:
            break
        xa, ya = x[act], y[act]
        th = np.tanh(xa)
        dx = (xa * th - ya) / (th + xa * (1.0 - th * th))
        x[act] = xa - dx
        act = act[np.abs(dx) > 1e-14 * np.abs(xa)]
    if act.size:  # pragma: no cover - Newton from Eckart's guess converges in < 10 steps
        raise RuntimeError(f"wavenumber: Newton iteration did not converge for omega² h / g = {y[act][:3]}")
    x = x.reshape(w.shape)
    return x / h


# ----------------------------------------------------------------------------------------------
# components


@dataclass(frozen=True, eq=False)
class WaveComponents:
    """Discretised linear sea: n components, arrays of shape (n,), read-only, float64.

    omega (rad/s, > 0), amplitude (m), phase (rad), heading (rad, 0 = towards +x), wavenumber
    (rad/m, from ω² = g k tanh(k h) with `water_depth` h). `repeat_period` (s) is set when every ω_j
    is a multiple of 2π/repeat_period (the elevation then repeats exactly), else None.
    """

    omega: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    heading: np.ndarray
    wavenumber: np.ndarray
    water_depth: float = math.inf
    g: float = G_STANDARD
    repeat_period: float | None = None

    def __post_init__(self):
        arrays = {}
        for name in ("omega", "amplitude", "phase", "heading", "wavenumber"):
            arrays[name] = _readonly_float(name, getattr(self, name))
        n = arrays["omega"].shape[0]
        for name, a in arrays.items():
            if a.shape != (n,):
                raise ValueError(f"{name} has shape {a.shape}; all component arrays must be ({n},)")
            object.__setattr__(self, name, a)
        if n and np.any(arrays["omega"] <= 0.0):
            raise ValueError("omega must be > 0 (rad/s) for every wave component")
        if np.any(arrays["amplitude"] < 0.0):
            raise ValueError("amplitude must be >= 0 (m) for every wave component")
        object.__setattr__(self, "water_depth", _water_depth(self.water_depth))
        object.__setattr__(self, "g", _positive("g", self.g))
        if self.repeat_period is not None:
            object.__setattr__(self, "repeat_period", _positive("repeat_period", self.repeat_period))

    @classmethod
    def _made(cls, *, omega, amplitude, phase, heading, wavenumber, water_depth, g,
              repeat_period):
        """Components from arrays this package made and checked (:func:`hydro.seabatch.
        components_many`): the fields set as given, read-only, without the constructor's checks
        (~0.1 ms a sea, as much as the rest of a batch's discretisation)."""
        out = object.__new__(cls)
        for name, a in (("omega", omega), ("amplitude", amplitude), ("phase", phase),
                        ("heading", heading), ("wavenumber", wavenumber)):
            a = np.ascontiguousarray(a, dtype=np.float64)
            a.setflags(write=False)
            object.__setattr__(out, name, a)
        for name, v in (("water_depth", water_depth), ("g", g), ("repeat_period", repeat_period)):
            object.__setattr__(out, name, v)
        return out

    def __len__(self) -> int:
        return int(self.omega.shape[0])

    @property
    def complex_amplitude(self) -> np.ndarray:
        """a_j e^{iφ_j} (m), complex (n,): the complex elevation amplitude at the origin."""
        return self.amplitude * np.exp(1j * self.phase)

    @property
    def m0(self) -> float:
        """Zeroth moment of the discretised spectrum, Σ a_j²/2 (m²) = variance of η."""
        return float(0.5 * np.sum(self.amplitude**2))

    @property
    def hs(self) -> float:
        """Significant wave height of the discretised sea, 4 sqrt(m0) (m)."""
        return 4.0 * math.sqrt(self.m0)

    def select(self, mask) -> "WaveComponents":
        """A new WaveComponents with only the components where `mask` (bool, (n,)) is True."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (len(self),):
            raise ValueError(f"mask must have shape ({len(self)},), got {mask.shape}")
        return WaveComponents(
            omega=self.omega[mask], amplitude=self.amplitude[mask], phase=self.phase[mask],
            heading=self.heading[mask], wavenumber=self.wavenumber[mask],
            water_depth=self.water_depth, g=self.g, repeat_period=self.repeat_period,
        )

    def band(self, omega_min: float, omega_max: float) -> "WaveComponents":
        """The components with omega_min <= ω <= omega_max (rad/s), e.g. a database's grid."""
        return self.select((self.omega >= omega_min) & (self.omega <= omega_max))


def _make_components(omega, amplitude, phase, heading, water_depth, g, repeat_period):
    return WaveComponents(
        omega=omega, amplitude=amplitude, phase=phase, heading=heading,
        wavenumber=wavenumber(omega, water_depth, g), water_depth=water_depth, g=g,
        repeat_period=repeat_period,
    )


# ----------------------------------------------------------------------------------------------
# directional spreading


@dataclass(frozen=True)
class Spreading:
    """Directional spreading G(β) = α cos^{2s}(β/2) on −π < β ≤ π (Stansby & Li 2024 eq. 34), β relative to
    the mean heading, α = Γ(s+1) / (2 sqrt(π) Γ(s+½)) so that ∫G dβ = 1.

    Its first circular moment is E[cos β] = s/(s+1), hence the directional spread
    σ² = 2(1 − E[cos β]) = 2/(1+s) (`sigma`).

    method:
    - "cos2s" (default): directions drawn exactly from G: sin²(β/2) ~ Beta(½, s+½) with a random sign.
    - "normal": Stansby & Li's (2024) approximation, β = σ·N(0, 1) with σ² = 2/(1+s), wrapped to (−π, π].
    """

    s: float
    method: str = "cos2s"

    def __post_init__(self):
        s = _finite("s (spreading parameter)", self.s)
        if s < 0.0:
            raise ValueError(f"s (spreading parameter) must be >= 0 (0 = uniform over all directions), got {self.s!r}")
        object.__setattr__(self, "s", s)
        if self.method not in ("cos2s", "normal"):
            raise ValueError(f"method must be 'cos2s' (exact) or 'normal' (Stansby & Li 2024), got {self.method!r}")

    @property
    def sigma(self) -> float:
        """Directional spread σ = sqrt(2/(1+s)) (rad)."""
        return math.sqrt(2.0 / (1.0 + self.s))

    def density(self, beta) -> np.ndarray:
        """G(β) (1/rad) of the cos^{2s}(β/2) distribution, β in rad relative to the mean heading."""
        from scipy import special

        b = np.asarray(beta, dtype=np.float64)
        log_alpha = special.gammaln(self.s + 1.0) - special.gammaln(self.s + 0.5) - math.log(2.0 * math.sqrt(math.pi))
        c = np.abs(np.cos(0.5 * b))
        with np.errstate(divide="ignore"):
            return np.where(np.abs(b) <= math.pi, np.exp(log_alpha + 2.0 * self.s * np.log(c)), 0.0)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n direction offsets (rad, in (−π, π]) drawn with `rng` by the chosen method."""
        if self.method == "normal":
            d = self.sigma * rng.standard_normal(n)
            return np.pi - np.mod(np.pi - d, 2.0 * np.pi)
        x = rng.beta(0.5, self.s + 0.5, size=n)
        sign = np.where(rng.random(n) < 0.5, -1.0, 1.0)
        return sign * 2.0 * np.arcsin(np.sqrt(x))


def _spreading(value) -> Spreading | None:
    if value is None or isinstance(value, Spreading):
        return value
    raise TypeError(f"spreading must be a Spreading(s=...) or None, got {value!r}")


# ----------------------------------------------------------------------------------------------
# regular wave


def _heading_label(heading) -> str:
    """", heading 30°" for a heading in rad; nothing for head seas (0)."""
    return "" if heading == 0 else f", heading {math.degrees(heading):g}°"


# Miche's limit: the highest periodic wave of length L in water of depth h is 0.142 L tanh(kh)
# (Stokes' 1/7 of the length in deep water; about 0.88 h in shallow water)
BREAKING_STEEPNESS = 0.142


def breaking_height(period, water_depth: float = math.inf, g: float = G_STANDARD):
    """The highest wave (m, crest to trough) of ``period`` (s) in water of ``water_depth`` (m):
    H_b = 0.142 L tanh(k h) (Miche), L = 2π/k from ω² = g k tanh(k h); past it the wave breaks
    and linear (Airy) theory, the BEM excitation and the elevation stand for nothing real.
    ``period`` a number (a float back) or an array (elementwise: many seas' peaks at once)."""
    k = wavenumber(2.0 * math.pi / np.asarray(period, dtype=np.float64), water_depth, g)
    h = _water_depth(water_depth)
    out = BREAKING_STEEPNESS * (2.0 * math.pi / k) * (np.tanh(k * h) if math.isfinite(h) else 1.0)
    return float(out) if np.ndim(out) == 0 else out


def _check_breaking(what: str, height: float, period: float, water_depth, g):
    limit = breaking_height(period, water_depth, g)
    if height > limit:
        depth = "deep water" if not math.isfinite(_water_depth(water_depth)) else \
            f"water {float(water_depth):g} m deep"
        raise ValueError(
            f"{what} {height:g} m at a period of {period:g} s is past breaking: the highest wave of "
            f"that period in {depth} is {limit:.3g} m (Miche: 0.142 L tanh(kh), L = "
            f"{2.0 * math.pi / float(wavenumber(2.0 * math.pi / period, water_depth, g)):.3g} m); "
            f"linear waves and the BEM excitation do not hold there. Give a height below "
            f"{limit:.3g} m or a longer period")


@dataclass(frozen=True)
class Regular:
    """Regular (monochromatic) wave: height H (m, crest to trough), period T (s), heading β (rad,
    0 = towards +x) and phase φ (rad): η = (H/2) cos(k(x cos β + y sin β) − 2πt/T + φ)."""

    height: float
    period: float
    heading: float = 0.0
    phase: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "height", _positive("height", self.height))
        object.__setattr__(self, "period", _positive("period", self.period))
        object.__setattr__(self, "heading", check_heading(self.heading))
        object.__setattr__(self, "phase", _finite("phase", self.phase))

    def __str__(self):
        return f"regular wave H {self.height:g} m, T {self.period:g} s" + _heading_label(self.heading)

    @property
    def omega(self) -> float:
        return 2.0 * math.pi / self.period

    def components(self, water_depth: float = math.inf, g: float = G_STANDARD) -> WaveComponents:
        """The one component (ω = 2π/T, a = H/2); a wave past breaking
        (:func:`breaking_height`) is refused."""
        _check_breaking("regular wave: height", self.height, self.period, water_depth, g)
        return _make_components(
            np.array([self.omega]), np.array([0.5 * self.height]), np.array([self.phase]),
            np.array([self.heading]), water_depth, g, self.period,
        )


# ----------------------------------------------------------------------------------------------
# spectra


def _sea_streams(seed: int):
    jitter, phases, directions = np.random.SeedSequence(seed).spawn(3)
    return np.random.default_rng(jitter), np.random.default_rng(phases), np.random.default_rng(directions)


def _frequencies(omega_range, n_components, repeat_period, jitter, rng):
    """Component frequencies ω_j and their bandwidths Δω_j (rad/s), see the module docstring."""
    lo, hi = omega_range
    if repeat_period is not None:
        d = 2.0 * math.pi / repeat_period
        m_lo = max(1, math.ceil(lo / d - 1e-9))
        m_hi = math.floor(hi / d + 1e-9)
        count = m_hi - m_lo + 1
        if count < 1:
            raise ValueError(
                f"repeat_period={repeat_period} s gives the frequency grid 2π/T_R = {d:.6g} rad/s, "
                f"which has no point inside omega_range=({lo:.6g}, {hi:.6g}) rad/s: widen omega_range "
                "or lengthen repeat_period"
            )
        if n_components is None:
            m = np.arange(m_lo, m_hi + 1)
            return m * d, np.full(count, d)
        if n_components > count:
            raise ValueError(
                f"n_components={n_components} exceeds the {count} multiples of 2π/repeat_period "
                f"({d:.6g} rad/s) inside omega_range=({lo:.6g}, {hi:.6g}) rad/s: use n_components <= "
                f"{count}, n_components=None (all of them), or a longer repeat_period"
            )
        # linspace steps >= 1, so rounding keeps the integers distinct
        m = np.round(np.linspace(m_lo, m_hi, n_components)).astype(np.int64)
        w = m * d
        if n_components == 1:
            return w, np.array([hi - lo])
        dw = np.empty_like(w)
        dw[1:-1] = 0.5 * (w[2:] - w[:-2])
        dw[0] = w[1] - w[0]
        dw[-1] = w[-1] - w[-2]
        return w, dw
    n = DEFAULT_N_COMPONENTS if n_components is None else n_components
    d = (hi - lo) / n
    centres = lo + (np.arange(n) + 0.5) * d
    offsets = jitter * d * (rng.random(n) - 0.5)
    return centres + offsets, np.full(n, d)


@dataclass(frozen=True, kw_only=True, eq=False)
class _SpectralSea:
    """Discretisation shared by the spectral seas: the keyword fields seed, heading, spreading,
    n_components, omega_range, repeat_period, frequency_jitter; subclasses give spectrum(ω) and
    _default_range()."""

    seed: int = 0
    heading: float = 0.0
    spreading: Spreading | None = None
    n_components: int | None = None
    omega_range: tuple[float, float] | None = None
    repeat_period: float | None = None
    frequency_jitter: float = 0.5

    def _check_common(self):
        object.__setattr__(self, "seed", _seed(self.seed))
        object.__setattr__(self, "heading", check_heading(self.heading))
        object.__setattr__(self, "spreading", _spreading(self.spreading))
        object.__setattr__(self, "n_components", _n_components(self.n_components))
        object.__setattr__(self, "omega_range", _omega_range(self.omega_range))
        if self.repeat_period is not None:
            object.__setattr__(self, "repeat_period", _positive("repeat_period", self.repeat_period))
        j = _finite("frequency_jitter", self.frequency_jitter)
        if not 0.0 <= j <= 1.0:
            raise ValueError(f"frequency_jitter must lie in [0, 1] (fraction of the bin width), got {self.frequency_jitter!r}")
        object.__setattr__(self, "frequency_jitter", j)

    @property
    def band(self) -> tuple[float, float]:
        """The discretised frequency band (rad/s): omega_range, or the class default."""
        return self.omega_range if self.omega_range is not None else self._default_range()

    def band_energy_fraction(self) -> float:
        """∫ S dω over :attr:`band` / ∫₀^∞ S dω: the fraction of the spectrum's variance that the
        discretisation keeps (the sea's Hs is √ of it times the stated one)."""
        lo, hi = self.band
        total = self._total_variance()
        return self._variance(lo, hi) / total if total > 0.0 else 1.0

    def _total_variance(self) -> float:
        """∫₀^∞ S dω (m²): by quadrature here; where it is Hs²/16 by construction, that."""
        return self._variance(0.0, math.inf)

    def _variance(self, lo: float, hi: float) -> float:
        """∫_lo^hi S dω (m²) of a peaked spectrum: the trapezoid rule on 4001 points spaced
        geometrically over [lo, hi] ∩ [0.2 ωp, 200 ωp] (below 0.2 ωp, S < e^{−780} of its peak;
        above 200 ωp the ω⁻⁵ tail holds 4e-10 of the variance; 4001 points: within 1e-6 of
        scipy's quad for PM and JONSWAP γ 1–7, in 0.5 ms where quad takes 20 ms). A spectrum
        without a peak (UserSpectrum) overrides it."""
        wp = self.omega_peak
        a, b = max(lo, 0.2 * wp), min(hi, 200.0 * wp)
        if b <= a:
            return 0.0
        w = np.geomspace(a, b, 4001)
        return float(np.trapezoid(self.spectrum(w), w))

    def components(self, water_depth: float = math.inf, g: float = G_STANDARD) -> WaveComponents:
        """Discretise: a_j = sqrt(2 S(ω_j) Δω_j), φ_j ~ U[0, 2π) (seeded), β_j = heading (+ spread).

        A band that keeps less than BAND_ENERGY_MIN of the spectrum's variance (its sea is then
        more than 5 % lower than the stated Hs) warns with a :class:`SeaStateWarning`."""
        self._warn_band(self.band_energy_fraction(), stacklevel=3)
        w, dw, phase, heading = self._draws()
        amp = np.sqrt(2.0 * np.maximum(self.spectrum(w), 0.0) * dw)
        return _make_components(w, amp, phase, heading, water_depth, g, self.repeat_period)

    def _warn_band(self, frac: float, stacklevel: int):
        """The :class:`SeaStateWarning` of :meth:`components` where the band keeps a fraction
        ``frac`` < BAND_ENERGY_MIN of the variance (``stacklevel``: from this method)."""
        if frac < BAND_ENERGY_MIN:
            lo, hi = self.band
            peak = getattr(self, "omega_peak", None)
            where = f" (its peak {peak:.4g} rad/s)" if peak is not None else ""
            warnings.warn(
                f"{type(self).__name__}: omega_range=({lo:.4g}, {hi:.4g}) rad/s keeps a fraction "
                f"{frac:.3g} of the spectrum's variance{where}, so the sea has "
                f"Hs = {math.sqrt(frac):.3g} × the stated one; accepted without this warning: a band "
                f"keeping >= {BAND_ENERGY_MIN:g} (Hs within 5 %). Widen omega_range to cover the "
                "spectrum (the default band does), or, if the cut is meant, restate the sea so that "
                "the band holds its energy", SeaStateWarning, stacklevel=stacklevel)

    def _draws(self):
        """What the sea's seed decides: ω_j, Δω_j, φ_j ~ U[0, 2π), β_j = heading (+ spread)."""
        rng_jitter, rng_phase, rng_dir = _sea_streams(self.seed)
        w, dw = _frequencies(self.band, self.n_components, self.repeat_period, self.frequency_jitter, rng_jitter)
        phase = rng_phase.uniform(0.0, 2.0 * math.pi, size=w.shape[0])
        heading = np.full(w.shape[0], self.heading)
        if self.spreading is not None:
            heading = heading + self.spreading.sample(rng_dir, w.shape[0])
        return w, dw, phase, heading


def pierson_moskowitz_spectrum(omega, hs, tp) -> np.ndarray:
    """S_PM(ω) = (5/16) Hs² ωp⁴ ω⁻⁵ exp(−(5/4)(ωp/ω)⁴), m² s/rad, ωp = 2π/Tp; ∫S dω = Hs²/16 exactly.
    hs (m) and tp (s): numbers, or arrays that broadcast against omega (many seas at once, the
    same numbers as each sea's own call)."""
    w = np.asarray(omega, dtype=np.float64)
    out = np.zeros_like(w)
    pos = w > 0.0
    # elementwise, so a number and an array of it give the same bits
    hs, tp = (np.broadcast_to(np.asarray(a, dtype=np.float64), w.shape)[pos] for a in (hs, tp))
    wp = 2.0 * math.pi / tp
    r = wp / w[pos]
    out[pos] = (5.0 / 16.0) * hs * hs / wp * r**5 * np.exp(-1.25 * r**4)
    return out


def jonswap_spectrum(omega, hs, tp, gamma, a_gamma) -> np.ndarray:
    """S_J(ω) = A_γ S_PM(ω; Hs, Tp) γ^{exp(−(ω−ωp)²/(2σ²ωp²))} (m² s/rad, :class:`Jonswap`), with
    its normalisation A_γ (``a_gamma``) given; hs, tp, gamma, a_gamma numbers or arrays that
    broadcast against omega."""
    w = np.asarray(omega, dtype=np.float64)
    enh = gamma ** _peak_enhancement_exponent(w / (2.0 * math.pi / tp))
    return a_gamma * pierson_moskowitz_spectrum(w, hs, tp) * enh


def _peak_enhancement_exponent(x):
    """exp(−(x−1)² / (2σ²)) with x = ω/ωp, σ = 0.07 (x <= 1) or 0.09 (x > 1) (DNV-RP-C205 3.5.5)."""
    sigma = np.where(x <= 1.0, 0.07, 0.09)
    return np.exp(-0.5 * ((x - 1.0) / sigma) ** 2)


@functools.lru_cache(maxsize=256)
def jonswap_normalisation(gamma: float, method: str = "exact") -> float:
    """A_γ such that S_J = A_γ · S_PM · γ^{exp(−(ω−ωp)²/(2σ²ωp²))} has ∫S_J dω = Hs²/16.

    "exact": 1 / ∫₀^∞ 5 x⁻⁵ e^{−1.25 x⁻⁴} γ^{r(x)} dx (adaptive quadrature, split at the peak x = 1;
    the PM shape 5x⁻⁵e^{−1.25x⁻⁴} integrates to 1). "dnv": the DNV-RP-C205 approximation
    1 − 0.287 ln γ (within about 1 % for 1 <= γ <= 7). Kept per (γ, method): a study's thousands
    of seas of one γ paid the two quadratures each (~1 ms of a sea's construction).
    """
    if method == "dnv":
        return 1.0 - 0.287 * math.log(gamma)
    if method != "exact":
        raise ValueError(f"normalisation must be 'exact' or 'dnv', got {method!r}")
    if gamma == 1.0:
        return 1.0

    def f(x):
        return 5.0 * x**-5 * math.exp(-1.25 * x**-4) * gamma ** float(_peak_enhancement_exponent(x))

    from scipy import integrate

    below, _ = integrate.quad(f, 1e-3, 1.0, epsabs=0.0, epsrel=1e-12, limit=200, points=[0.8])
    above, _ = integrate.quad(f, 1.0, math.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return 1.0 / (below + above)


@dataclass(frozen=True, eq=False)
class _PeakSea(_SpectralSea):
    """Seas given by significant wave height hs (m) and peak period tp (s)."""

    hs: float
    tp: float

    def _check_hs_tp(self):
        object.__setattr__(self, "hs", _positive("hs (significant wave height, m)", self.hs))
        object.__setattr__(self, "tp", _positive("tp (peak period, s)", self.tp))

    def __str__(self):
        name = type(self).__name__.replace("Jonswap", "JONSWAP").replace("PiersonMoskowitz", "PM")
        gamma = f", γ {self.gamma:g}" if hasattr(self, "gamma") else ""
        return (f"{name} Hs {self.hs:g} m, Tp {self.tp:g} s{gamma}" + _heading_label(self.heading)
                + f", seed {self.seed}")

    @property
    def omega_peak(self) -> float:
        return 2.0 * math.pi / self.tp

    def components(self, water_depth: float = math.inf, g: float = G_STANDARD) -> WaveComponents:
        """As :meth:`_SpectralSea.components`; a sea whose significant height would break as a
        regular wave of its peak period (:func:`breaking_height`; realistic seas stay below about
        half of it, a significant steepness 2π Hs/(g Tp²) of 1/15, DNV-RP-C205 §3.5.5) is refused."""
        self._refuse_breaking(water_depth, g)
        return super().components(water_depth=water_depth, g=g)

    def _refuse_breaking(self, water_depth, g):
        _check_breaking(f"{type(self).__name__}: hs", self.hs, self.tp, water_depth, g)

    def _default_range(self):
        return (DEFAULT_BAND[0] * self.omega_peak, DEFAULT_BAND[1] * self.omega_peak)


@dataclass(frozen=True)
class Jonswap(_PeakSea):
    """JONSWAP sea (DNV-RP-C205 form): S(ω) = A_γ S_PM(ω; Hs, Tp) γ^{exp(−(ω−ωp)²/(2σ²ωp²))},
    σ = 0.07 for ω <= ωp and 0.09 above, ωp = 2π/Tp. S in m² s/rad, one-sided.

    normalisation "exact" (default): A_γ from a numeric integral so that 4 sqrt(∫₀^∞ S dω) = Hs
    exactly; "dnv": A_γ = 1 − 0.287 ln γ. gamma >= 1 (1 = Pierson–Moskowitz). Default band
    omega_range = (0.5 ωp, 5 ωp). See the module docstring for the discretisation.
    """

    gamma: float = 3.3
    normalisation: str = "exact"
    _a_gamma: float = field(init=False, repr=False, compare=False, default=1.0)

    def __post_init__(self):
        self._check_hs_tp()
        gamma = _finite("gamma", self.gamma)
        if gamma < 1.0:
            raise ValueError(f"gamma (peak enhancement) must be >= 1 (1 = Pierson–Moskowitz, 3.3 typical), got {self.gamma!r}")
        object.__setattr__(self, "gamma", gamma)
        self._check_common()
        object.__setattr__(self, "_a_gamma", jonswap_normalisation(gamma, self.normalisation))

    def _total_variance(self) -> float:
        # A_γ is made so (to scipy quad's 1e-12), so a batch of seas skips one quadrature each
        return self.hs**2 / 16.0 if self.normalisation == "exact" else super()._total_variance()

    def spectrum(self, omega) -> np.ndarray:
        """S(ω) in m² s/rad for ω in rad/s (any shape; 0 for ω <= 0)."""
        return jonswap_spectrum(omega, self.hs, self.tp, self.gamma, self._a_gamma)


@dataclass(frozen=True)
class PiersonMoskowitz(_PeakSea):
    """Pierson–Moskowitz sea in the Hs–Tp form: S(ω) = (5/16) Hs² ωp⁴ ω⁻⁵ exp(−(5/4)(ωp/ω)⁴),
    m² s/rad; ∫₀^∞ S dω = Hs²/16 analytically. Default band omega_range = (0.5 ωp, 5 ωp)."""

    def __post_init__(self):
        self._check_hs_tp()
        self._check_common()

    def _total_variance(self) -> float:
        return self.hs**2 / 16.0

    def spectrum(self, omega) -> np.ndarray:
        """S(ω) in m² s/rad for ω in rad/s (any shape; 0 for ω <= 0)."""
        return pierson_moskowitz_spectrum(omega, self.hs, self.tp)


@dataclass(frozen=True, eq=False)
class UserSpectrum(_SpectralSea):
    """A tabulated one-sided spectrum (e.g. measured): S(ω) (m² s/rad) at ascending ω > 0 (rad/s),
    linearly interpolated between the points and 0 outside them. Default band: the table's range."""

    omega: np.ndarray
    S: np.ndarray

    def __post_init__(self):
        w = _readonly_float("omega", self.omega)
        S = _readonly_float("S", self.S)
        if w.shape[0] < 2 or S.shape != w.shape:
            raise ValueError(f"omega and S must be 1-D of equal length >= 2, got {w.shape} and {S.shape}")
        if np.any(w <= 0.0) or np.any(np.diff(w) <= 0.0):
            raise ValueError("omega must be > 0 and strictly ascending (rad/s)")
        if np.any(S < 0.0):
            raise ValueError(f"S must be >= 0 (m² s/rad); smallest value {S.min()!r} at omega={w[np.argmin(S)]!r} rad/s")
        object.__setattr__(self, "omega", w)
        object.__setattr__(self, "S", S)
        self._check_common()

    @property
    def hs(self) -> float:
        """4 sqrt(∫S dω) of the table (trapezoid rule), m."""
        return 4.0 * math.sqrt(float(np.trapezoid(self.S, self.omega)))

    def _default_range(self):
        return (float(self.omega[0]), float(self.omega[-1]))

    def _variance(self, lo: float, hi: float) -> float:
        """∫_lo^hi S dω of the piecewise-linear table (exact: the trapezoid rule on its points)."""
        lo, hi = max(lo, float(self.omega[0])), min(hi, float(self.omega[-1]))
        if hi <= lo:
            return 0.0
        w = np.unique(np.concatenate([[lo, hi], self.omega[(self.omega > lo) & (self.omega < hi)]]))
        return float(np.trapezoid(self.spectrum(w), w))

    def spectrum(self, omega) -> np.ndarray:
        return np.interp(np.asarray(omega, dtype=np.float64), self.omega, self.S, left=0.0, right=0.0)


# ----------------------------------------------------------------------------------------------
# measured elevation


@dataclass(frozen=True, eq=False)
class MeasuredElevation:
    """A measured elevation record η(t) (m) at the origin, uniformly sampled at t (s), decomposed by
    FFT into components ω_m = 2π m/(N Δt), m = 1 … ⌊N/2⌋ (N samples):

        η(t) − mean(η) = Σ_m a_m cos(ω_m (t − t₀) − arg X_m),  a_m = 2|X_m|/N (|X_m|/N at Nyquist),

    with X = rfft(η − mean η). It reproduces the record at its sample times and repeats with period
    N Δt. The mean is removed (a mean level is no wave); a warning is given if it exceeds 1 % of
    the standard deviation. `omega_range` keeps only components inside it; `spreading` gives each
    component a direction (random-directional method, seeded); `heading` is the mean direction.
    """

    t: np.ndarray
    eta: np.ndarray
    heading: float = 0.0
    spreading: Spreading | None = None
    seed: int = 0
    omega_range: tuple[float, float] | None = None

    def __post_init__(self):
        t = _readonly_float("t", self.t)
        eta = _readonly_float("eta", self.eta)
        if t.shape[0] < 2 or eta.shape != t.shape:
            raise ValueError(f"t and eta must be 1-D of equal length >= 2, got {t.shape} and {eta.shape}")
        dt = np.diff(t)
        if np.any(dt <= 0.0) or np.max(np.abs(dt - dt.mean())) > 1e-6 * dt.mean():
            raise ValueError("t must be uniformly spaced and ascending (resample the record first)")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "heading", check_heading(self.heading))
        object.__setattr__(self, "spreading", _spreading(self.spreading))
        object.__setattr__(self, "seed", _seed(self.seed))
        object.__setattr__(self, "omega_range", _omega_range(self.omega_range))

    @property
    def dt(self) -> float:
        return float((self.t[-1] - self.t[0]) / (self.t.shape[0] - 1))

    @property
    def duration(self) -> float:
        """Repeat period N Δt (s) of the decomposition."""
        return self.t.shape[0] * self.dt

    def components(self, water_depth: float = math.inf, g: float = G_STANDARD) -> WaveComponents:
        n = self.eta.shape[0]
        mean = float(self.eta.mean())
        std = float(self.eta.std())
        if abs(mean) > 0.01 * std:
            warnings.warn(f"MeasuredElevation: removed the record's mean {mean:.4g} m "
                          f"({abs(mean) / std:.1%} of its standard deviation)", stacklevel=2)
        X = np.fft.rfft(self.eta - mean)
        m = np.arange(1, X.shape[0])
        X = X[1:]
        amp = 2.0 * np.abs(X) / n
        if n % 2 == 0:
            amp[-1] *= 0.5  # the Nyquist term has no conjugate partner
        w = 2.0 * math.pi * m / self.duration
        phase = np.mod(-np.angle(X) + w * self.t[0], 2.0 * math.pi)
        keep = np.ones(w.shape[0], dtype=bool)
        if self.omega_range is not None:
            keep = (w >= self.omega_range[0]) & (w <= self.omega_range[1])
        w, amp, phase = w[keep], amp[keep], phase[keep]
        heading = np.full(w.shape[0], self.heading)
        if self.spreading is not None:
            heading = heading + self.spreading.sample(_sea_streams(self.seed)[2], w.shape[0])
        return _make_components(w, amp, phase, heading, water_depth, g, self.duration)


# ----------------------------------------------------------------------------------------------
# time series


def ramp(t, duration: float) -> np.ndarray:
    """Start-up ramp r(t) = ½(1 − cos(π t / T_ramp)) for 0 <= t < T_ramp, 1 after, 0 before t = 0.

    Its value and slope are continuous at both ends (no impulse at start-up). duration = 0 gives 1
    for t >= 0. t: s, any shape; returns float64 of the same shape.
    """
    t = np.asarray(t, dtype=np.float64)
    T = _finite("ramp duration", duration)
    if T < 0.0:
        raise ValueError(f"ramp duration must be >= 0 (s), got {duration!r}")
    if T == 0.0:
        return np.where(t >= 0.0, 1.0, 0.0)
    r = 0.5 * (1.0 - np.cos(np.pi * np.clip(t, 0.0, T) / T))
    return np.where(t < 0.0, 0.0, r)


def _check_components(components) -> WaveComponents:
    if not isinstance(components, WaveComponents):
        raise TypeError(
            f"components must be a WaveComponents, got {type(components).__name__}; "
            "call sea.components(water_depth=..., g=...) first"
        )
    return components


def _uniform_step(t: np.ndarray):
    """h when t[k] = t[0] + k h for every k to round-off (|deviation| ≤ 16 ε max|t|), else None."""
    n = t.shape[0]
    h = (t[-1] - t[0]) / (n - 1)
    if not (np.isfinite(h) and h > 0.0):
        return None
    scale = max(float(np.max(np.abs(t))), abs(float(h)))
    if np.max(np.abs(t - (t[0] + h * np.arange(n)))) > 16.0 * np.finfo(np.float64).eps * scale:
        return None
    return float(h)


# Rows of one block of the uniform-grid harmonic sum: the K × n phase table is made once.
_BLOCK = 256


def _harmonic_sum(omega: np.ndarray, coeff: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Re Σ_j coeff[j, :] e^{−iω_j t} for every t: (n_t, m) float64, chunked over t.

    Uses Re[(cos ωt − i sin ωt)(C_r + i C_i)] = cos(ωt)·C_r + sin(ωt)·C_i: two real matrix
    products, with at most _CHUNK_ENTRIES phases held at once.

    On a uniform grid t_k = t_0 + k h (a time-step table), block b of K rows has
    e^{−iω(t_0 + (bK + k) h)} = e^{−iωkh} · e^{−iω(t_0 + bKh)}: the K × n phase table e^{−iωkh}
    is made once and each block's second factor is folded into its coefficients, so the
    sines and cosines cost K·n instead of n_t·n (they were ~80 % of building a 20,000-step
    excitation table). Both phases are made from their own products ω·(time), not by recursion,
    so the result equals the direct sum to round-off.
    """
    n_t = t.shape[0]
    out = np.empty((n_t, coeff.shape[1]), dtype=np.float64)
    if omega.shape[0] == 0:
        out[:] = 0.0
        return out
    h = _uniform_step(t) if n_t >= 4 * _BLOCK else None
    if h is not None:
        k = h * np.arange(_BLOCK)
        wk = np.multiply.outer(k, omega)
        cos_k, sin_k = np.cos(wk), np.sin(wk)
        for i in range(0, n_t, _BLOCK):
            rows = min(_BLOCK, n_t - i)
            cb = coeff * np.exp(-1j * omega * (t[0] + i * h))[:, None]
            out[i:i + rows] = cos_k[:rows] @ cb.real + sin_k[:rows] @ cb.imag
        return out
    cr = np.ascontiguousarray(coeff.real)
    ci = np.ascontiguousarray(coeff.imag)
    step = max(1, _CHUNK_ENTRIES // omega.shape[0])
    for i in range(0, n_t, step):
        wt = np.multiply.outer(t[i:i + step], omega)
        out[i:i + step] = np.cos(wt) @ cr + np.sin(wt) @ ci
    return out


def elevation(components: WaveComponents, t, x=0.0, y=0.0, *, ramp_duration: float = 0.0) -> np.ndarray:
    """Free-surface elevation η (m) = r(t) Σ_j a_j cos(k_j (x cos β_j + y sin β_j) − ω_j t + φ_j).

    t: s, shape T (scalar or array). x, y: m, broadcast together to shape P (the points).
    Returns shape T + P. r is `ramp(t, ramp_duration)` (1 when ramp_duration = 0).
    """
    c = _check_components(components)
    t_arr = np.asarray(t, dtype=np.float64)
    xb, yb = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    pts_shape = xb.shape
    xp, yp = xb.reshape(-1), yb.reshape(-1)
    # complex amplitude at each point: a e^{iφ} e^{ik(x cosβ + y sinβ)}, shape (n, P)
    kx = np.multiply.outer(c.wavenumber * np.cos(c.heading), xp) + np.multiply.outer(c.wavenumber * np.sin(c.heading), yp)
    coeff = c.complex_amplitude[:, None] * np.exp(1j * kx)
    eta = _harmonic_sum(c.omega, coeff, t_arr.reshape(-1))
    if ramp_duration:
        eta *= ramp(t_arr.reshape(-1), ramp_duration)[:, None]
    return eta.reshape(t_arr.shape + pts_shape)
