"""Small checks shared by every config table parser (the body tree and the load tables): each
raises :class:`~mfm.mechanics.tree.ConfigError` naming the key path, the value and what is accepted."""
from __future__ import annotations

import numpy as np

from .mechanics.tree import ConfigError


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
