"""The mooring tables of :mod:`mfm.loads.catenary`: MoorPy's quasi-static line solved on a grid of
(span, height) about a line's rest position, and the nodal data of its tensor-product cubic
spline, made on the host (the compiled time loop cannot call MoorPy).

Host code only (numpy, scipy, MoorPy): the load that interpolates the tables inside jax is
:class:`mfm.loads.catenary.CatenaryLines`, which asks its host for each table
(:meth:`mfm.host.Host.mooring_table`). Where a table is kept between calls and processes (in the
process, in the database file where ``mfm fits`` stores a config's tables, on disk) is the
runner's business: :mod:`mfm.runner.tables`. This module gives what keys a kept table: the code
that makes it (:func:`table_source`) and its packed form (:func:`packed`).
"""
from __future__ import annotations

import functools

import numpy as np

from hydro import phases

MOORPY_TOL = 1e-10      # m: MoorPy's catenary convergence tolerance for the tables

# m: the table's centre is the rest span and height rounded to this (a table reaches tens of
# metres about it, its nodes a metre apart: a shift of half a millimetre changes nothing it
# covers), so that lines of one geometry share a table
CENTRE_QUANTUM = 1e-3


def moorpy_version() -> str:
    from importlib.metadata import version

    return version("moorpy")


def catenary_forces(x, z, length, EA, weight, seabed_friction=0.0):
    """MoorPy's quasi-static line at horizontal span x and height z (fairlead above anchor):
    (H, V) the fairlead's horizontal and vertical tensions, N (the force on the fairlead is
    −H ê_h − V ẑ). Raises ValueError when MoorPy reports no solution."""
    from moorpy.Catenary import catenary

    out = catenary(float(x), float(z), float(length), float(EA), float(weight),
                   CB=float(seabed_friction), Tol=MOORPY_TOL, MaxIter=500)
    if out[4].get("error"):
        raise ValueError(f"MoorPy's catenary found no solution at span {x:.6g} m, height {z:.6g} m "
                         f"(L {length:.6g} m, EA {EA:.6g} N, w {weight:.6g} N/m): "
                         f"{out[4].get('message', '')}")
    return -out[2], -out[3]


def _axis(centre, half, step):
    n = int(np.ceil(2 * half / step - 1e-9)) + 1
    return np.linspace(centre - half, centre + half, max(n, 4))


def table_centre(x0, z0):
    """The centre of a line's table: its rest span and height rounded to :data:`CENTRE_QUANTUM`,
    so that lines of one geometry share one table, although their spans, computed from fairlead
    and anchor positions a config gives to 1e-6 m, differ in the last digits (Wu & Yuan's six
    lines: three spans 775.4999997–775.5000010 m)."""
    return tuple(round(float(v) / CENTRE_QUANTUM) * CENTRE_QUANTUM for v in (x0, z0))


def make_table(x0, z0, extent, step, length, EA, weight, seabed_friction):
    """:func:`build_table`'s table made: MoorPy's line (:func:`catenary_forces`) at every node of
    the grid of half-widths ``extent`` and spacing ``step`` about (x0, z0), and the spline's
    nodal derivatives."""
    from scipy.interpolate import CubicSpline

    xs, zs = _axis(x0, extent[0], step[0]), _axis(z0, extent[1], step[1])
    # seconds (Wu & Yuan: 2,511 solves, ~7 s on 2 cores): a display that shows them hears how far
    n, rows, every = len(xs) * len(zs), [], phases.every(len(xs))
    for i, x in enumerate(xs):
        if i % every == 0:
            phases.say(f"mooring table (MoorPy): {i * len(zs):,} of {n:,} solves")
        rows.append([catenary_forces(x, z, length, EA, weight, seabed_friction) for z in zs])
    F = np.array(rows)                                              # (nx, nz, 2)
    Fx = CubicSpline(xs, F, axis=0)(xs, 1)
    Fz = CubicSpline(zs, F, axis=1)(zs, 1)
    Fxz = CubicSpline(zs, Fx, axis=1)(zs, 1)
    hx, hz = xs[1] - xs[0], zs[1] - zs[0]
    coef = np.stack([F, hx * Fx, hz * Fz, hx * hz * Fxz], axis=2)
    return xs, zs, coef


@functools.cache
def table_source() -> str:
    """sha256 of the code that makes a table (:func:`make_table`, :func:`catenary_forces`,
    :func:`_axis`) and of MoorPy's tolerance: a stored table made by other code is not read, and
    ``mfm fits`` drops it (not MoorPy's version: a stored table is a product of the config, the
    same numbers wherever it is read, as a stored fit is)."""
    import hashlib
    import inspect

    h = hashlib.sha256(repr(MOORPY_TOL).encode())
    for f in (make_table, catenary_forces, _axis):
        h.update(inspect.getsource(f).encode())
    return h.hexdigest()


def stored_table_key(key) -> str:
    """The key of the table of ``key`` (:func:`mfm.runner.tables.mooring_table`'s parameters) in a database file."""
    import hashlib

    h = hashlib.sha256(repr(("mooring table", key)).encode())
    h.update(table_source().encode())
    return h.hexdigest()


def packed(table):
    """(xs, zs, coef) as one float vector: [nx, nz, xs, zs, coef (nx, nz, 4, 2) flat]."""
    xs, zs, coef = table
    return np.concatenate([[len(xs), len(zs)], xs, zs, np.ravel(coef)])


def unpacked(a):
    nx, nz = int(a[0]), int(a[1])
    xs, zs = a[2:2 + nx], a[2 + nx:2 + nx + nz]
    return xs, zs, a[2 + nx + nz:].reshape(nx, nz, 4, 2)
