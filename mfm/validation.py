"""Every check of mfm's inputs, in one module.

Config tables (the body tree and every load table): :func:`unknown`, :func:`vector`,
:func:`number`, :func:`tables`, :func:`body_ref` raise :class:`~mfm.errors.ConfigError` naming the
key path, the value and what is accepted.

Arguments of the front doors (``simulate``, ``rollout``, ``simulate_batch``, the linear levels,
the stability and fidelity studies): :func:`finite_number`, :func:`positive`,
:func:`whole_number`, :func:`positive_seconds`, :func:`initial_vector`, :func:`square_matrix`,
:func:`check_sea` raise ValueError (:class:`~mfm.errors.SeaStateError`, also a TypeError, for
what is no sea state) naming the argument, the value and what is accepted.

Two checkers stay outside, by necessity: :mod:`hydro` never imports mfm (its sea states check
their own numbers), and the command line's parser (``mfm_cli``) must answer ``--help`` without
importing the package (and jax), so it checks its numbers as argparse types.
"""
from __future__ import annotations

import math
import numbers

import jax
import numpy as np

from .errors import ConfigError, SeaStateError

# ------------------------------------------------------------------------------- config tables


def unknown(keys, allowed, where):
    bad = sorted(set(keys) - set(allowed))
    if bad:
        raise ConfigError(f"{where}: unknown key(s) {bad}; accepted keys: {sorted(allowed)}")


def vector(value, n, where, what="numbers"):
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: {value!r} is not a list of {n} {what}") from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{where}: {value!r} is not a list of {n} finite {what}")
    return arr


def number(value, where):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ConfigError(f"{where}: {value!r} is not a finite number")
    return float(value)


def tables(raw, section, keys):
    """(where, table) for each table of an array of tables ``[[section]]``, keys checked."""
    if not isinstance(raw, list):
        raise ConfigError(f"{section}: expected [[{section}]] tables")
    for i, table in enumerate(raw):
        where = f"{section}[{i}]"
        if not isinstance(table, dict):
            raise ConfigError(f"{where}: expected a table")
        unknown(table, keys, where)
        yield where, table


def body_ref(table, key, where, names):
    if table.get(key) not in names:
        raise ConfigError(f"{where}.{key}: {table.get(key)!r} is not a body; known bodies: {names}")
    return table[key]


def element_name(table, where, default):
    """A config element's ``name`` (``default`` where it has none): a non-empty string, else a
    ConfigError naming the key and the value."""
    name = table.get("name", default)
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{where}.name: {name!r} is not a non-empty string")
    return name


def unique_names(items, kind):
    """Refuse two ``items`` (parsed elements with ``name`` and ``where``) of one name, naming the
    config table ``kind``."""
    seen = [t["name"] for t in items]
    for t in items:
        if seen.count(t["name"]) > 1:
            raise ConfigError(f"{t['where']}.name: {t['name']!r} names two [[{kind}]] entries; "
                              "names must be unique")


# ------------------------------------------------------------------------------- arguments
def finite_number(value, what, *, positive=False, nonnegative=False, allow_none=False):
    """A finite float, with a message naming the argument when it is not."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{what}: {value!r} is not a finite number")
    if positive and not value > 0:
        raise ValueError(f"{what}: {value!r} must be > 0")
    if nonnegative and not value >= 0:
        raise ValueError(f"{what}: {value!r} must be ≥ 0")
    return float(value)


def positive(value, what, *, allow_inf=False):
    """A positive float (finite, or also inf with ``allow_inf``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value > 0 \
            or (not allow_inf and not math.isfinite(value)):
        raise ValueError(f"{what}: {value!r}; give a positive finite number"
                         + (" (or inf)" if allow_inf else ""))
    return float(value)


def whole_number(value, minimum: int = 1) -> bool:
    """Whether ``value`` is a whole number (not a bool) ≥ ``minimum``; the caller's message says
    what the number is for."""
    return (not isinstance(value, bool) and isinstance(value, numbers.Integral)
            and value >= minimum)


def positive_seconds(value, what):
    """A positive finite number of seconds (or an array of them), where the value is known (a jax
    tracer is let through: it is checked where it was made)."""
    if isinstance(value, jax.core.Tracer):
        return
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: {value!r} is not a number; give a positive number of seconds") from None
    if v.size == 0 or not (np.all(np.isfinite(v)) and np.all(v > 0)):
        raise ValueError(f"{what}: {value!r}; give a positive, finite number of seconds")


def initial_vector(model, value, what: str) -> np.ndarray:
    """Initial coordinates or rates (n_q,) from None (zeros), an array or a dict by coordinate
    name (the others 0)."""
    n = model.n_coordinates
    if value is None:
        return np.zeros(n)
    if isinstance(value, dict):
        out = np.zeros(n)
        for k, v in value.items():
            try:
                out[model.coordinate_index(k)] = float(v)
            except KeyError:
                raise ValueError(f"{what}: {k!r} is not a coordinate of {model.name!r}; "
                                 f"coordinates: {list(model.coordinates)}") from None
            except (TypeError, ValueError):
                raise ValueError(f"{what}[{k!r}]: {v!r} is not a number") from None
    else:
        try:
            out = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{what}: {value!r} is not an array of numbers") from None
        if out.shape != (n,):
            raise ValueError(f"{what}: shape {out.shape} does not match the {n} coordinates "
                             f"{list(model.coordinates)}; give an array of shape ({n},) or a dict")
    bad = [model.coordinates[k] for k in np.flatnonzero(~np.isfinite(out))]
    if bad:
        raise ValueError(f"{what}: not finite for {bad}; give finite numbers (m, rad; m/s, rad/s)")
    return out


def square_matrix(a, what, n=None):
    """A square float64 matrix from a number or array (a number is a 1×1 matrix)."""
    try:
        m = np.atleast_2d(np.asarray(a, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"{what}: {a!r} is not a number or a square matrix of numbers") from None
    if m.ndim != 2 or m.shape[0] != m.shape[1] or (n is not None and m.shape[0] != n):
        raise ValueError(f"{what}: shape {m.shape}; give a square matrix"
                         + (f" of shape ({n}, {n}) like M" if n is not None else ""))
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{what}: {a!r} has non-finite entries; give finite numbers")
    return m


SEAS = ("hydro.Regular(height=, period=), hydro.Jonswap(hs=, tp=), hydro.PiersonMoskowitz(hs=, "
        "tp=), hydro.UserSpectrum, hydro.MeasuredElevation")


def check_sea(sea, what="sea", *, still_water=True):
    """A sea state of :mod:`hydro.waves` (anything with ``components``), or None for still water
    where ``still_water``; else :class:`~mfm.errors.SeaStateError` (a TypeError and a ValueError)."""
    if sea is None:
        if still_water:
            return
        raise SeaStateError(f"{what}: None; this needs a sea state: give one of {SEAS}")
    if not hasattr(sea, "components"):
        raise SeaStateError(f"{what}: {sea!r} is not a sea state; give one of {SEAS}"
                        + (", or None for still water" if still_water else ""))


def check_seas(seas) -> list:
    """``seas`` (one sea state or a sequence of them) as a non-empty list of sea states, each
    checked by :func:`check_sea` (no still water: these levels need waves)."""
    seas = list(seas) if isinstance(seas, (list, tuple)) else [seas]
    if not seas:
        raise ValueError("seas: an empty sequence; give at least one sea state of hydro.waves")
    for i, sea in enumerate(seas):
        check_sea(sea, f"seas[{i}]", still_water=False)
    return seas


def check_sea_in_grid(comps, sea, grid, what: str = "sea", *, rtol: float = 0.0):
    """The components ``comps`` (a hydro.waves.WaveComponents) of ``sea`` inside the database's
    frequency grid ``grid`` (rad/s, finite, ascending; an end within ``rtol`` of it counts as
    inside, as hydro.excitation.GRID_RTOL), else a ValueError naming ``what``, the sea, how many
    components and what fraction of its energy Σa² lie outside, and the fix. The frequency domain
    needs a RAO at every component, and the database has none beyond its grid."""
    w = np.asarray(comps.omega, dtype=float)
    lo, hi = float(grid[0]), float(grid[-1])
    out = (w < lo * (1.0 - rtol)) | (w > hi * (1.0 + rtol))
    if not out.any():
        return
    e = np.asarray(comps.amplitude, dtype=float) ** 2
    frac = float(e[out].sum() / e.sum()) if e.sum() > 0 else 1.0
    raise ValueError(
        f"{what}: {sea} has {int(out.sum())} of its {w.size} wave components (ω "
        f"{w[out].min():.4g}–{w[out].max():.4g} rad/s, a fraction {frac:.3g} of its energy Σa²) "
        f"outside the database's frequency grid [{lo:.6g}, {hi:.6g}] rad/s, where it has no "
        f"coefficients; accepted: every component inside the grid. Give the sea "
        f"omega_range=(ω_min, ω_max) inside [{lo:.6g}, {hi:.6g}], or regenerate the database over "
        f"a wider band")


def check_model(model, what: str = "model"):
    """``model`` is an :class:`mfm.Model`; else a TypeError that says what it got and how to make
    one (a config path given where its model is meant: ``mfm.load(path)`` first)."""
    from .mechanics.model import Model

    if isinstance(model, Model):
        return model
    if isinstance(model, (str, bytes)) or hasattr(model, "__fspath__"):
        raise TypeError(f"{what}: {str(model)!r} is a path, not a model; load it first: "
                        f"model = mfm.load({str(model)!r})")
    raise TypeError(f"{what}: got {type(model).__name__} {model!r:.80}; give an mfm.Model, made "
                    "by mfm.load(<config path>)")
