"""Config → tree → model: the one place that assembles a :class:`~mfm.mechanics.model.Model`.

:func:`load` reads and checks a TOML config (:mod:`mfm.io.config`), compiles the body tree
(:func:`compile_tree`), attaches the water's :class:`~hydro.prepare.HydroSpec` when the config has
a ``[hydro]`` table, and adds the loads of its other tables through the registry
(:mod:`mfm.loads.registry`): data flow one way, and the model type knows nothing of how it is made.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import warnings
from pathlib import Path

from hydro import phases
from hydro.database import HydroDatabaseWarning

from ..errors import ConfigError
from ..frequency.modes import resolve_damping_ratios
from ..loads.registry import TABLES, load_class
from ..loads.water import load_hydro_spec
from ..mechanics.compile import compile_tree
from ..mechanics.model import Model
from ..runner import xla
from .bemgen import database_is_stale
from .config import read_config, read_config_data


def load(path, hydro: bool = True, body_coupling: bool | None = None,
         progress: bool | dict = False, *, base: str | Path | None = None) -> Model:
    """Load a float-tree config and compile it.

    path: the config: the path of a TOML file (a str or a pathlib.Path, e.g. "configs/rm3.toml"),
        its TOML text (a str of more than one line), or a dict of its tables (what TOML parses
        to: ``{"model": {...}, "bodies": [...], "hydro": {...}}``), so that code builds models
        without writing files.
    base: the folder that relative paths in the config (``[hydro] database``, mesh files) are
        read from: by default the config file's folder, or the working directory for a TOML text
        or a dict.
    hydro: with True (default) and a ``[hydro]`` table in the config, the model carries its water
        (database, reference points, drag; see :mod:`mfm.loads.water`); False gives the
        mechanics-only model (bodies, joints, joint spring–dampers, the config's other loads).
    body_coupling: overrides ``hydro.body_coupling`` (hydrodynamic interaction between bodies: the
        cross-body blocks of A∞, A(ω), B(ω) and K); True, False or None (the config's value).
    progress: False (default), True or a dict of tqdm options, as :func:`mfm.simulate`'s: a line
        on stderr that says what the load is doing (reading the hydro database, finding the dofs
        its joints move, making MoorPy's mooring tables and how far): seconds where a cache is
        empty (Wu & Yuan's mooring table, 2,511 MoorPy solves: ~7 s on 2 cores). ``mfm simulate``
        shows it with its run's bar options (``--progress``).

    The model's provenance (``source``, ``source_sha256``) is the file and the sha256 of its bytes,
    or ``<dict>`` / ``<toml text>`` and the sha256 of the text (of the dict as sorted JSON).
    """
    # jax's compilation cache on before the first compilation of the session (the runner's, at
    # its first use, not at import: a session starts with a model, whatever it runs next)
    xla.compilation_cache()
    if isinstance(path, Model):
        raise TypeError(f"path: got a Model ({path.name!r}), already loaded; pass it on as it is, "
                        "or give mfm.load the path of its config TOML file")
    text = isinstance(path, str) and "\n" in path
    if not (isinstance(path, (str, Path, dict)) or hasattr(path, "__fspath__")):
        raise TypeError(f"path: {path!r} ({type(path).__name__}); give the path of a config TOML "
                        "file (a str or a pathlib.Path, e.g. 'configs/rm3.toml'), its TOML text or "
                        "a dict of its tables")
    if base is not None and not Path(base).is_dir():
        raise ValueError(f"base: {str(base)!r} is not a folder; give the folder the config's "
                         "relative paths ([hydro] database, mesh files) are read from")
    if not isinstance(hydro, bool):
        raise ValueError(f"hydro: {hydro!r}; accepted: True (with the config's [hydro] table) or False")
    if body_coupling is not None and not isinstance(body_coupling, bool):
        raise ValueError(f"body_coupling: {body_coupling!r}; accepted: True, False or None (the "
                         "config's hydro.body_coupling)")
    from ..runner.progress import phase, progress_bar, progress_options

    progress = progress_options(progress)
    if isinstance(path, dict) or text:
        label = "<dict>" if isinstance(path, dict) else "<toml text>"
        raw, options, bodies = read_config_data(path, label)
        content = (path if text else json.dumps(path, sort_keys=True, default=str)).encode()
        # relative paths from `base`: a stand-in file name in that folder (never read) carries
        # it through the code that resolves paths from a config file's folder
        path = Path(base if base is not None else os.getcwd()) / label
    else:
        raw, options, bodies = read_config(path)
        content = Path(path).read_bytes()
        if base is not None:
            path = Path(base) / Path(path).name
    bar = progress_bar(dict({"bar_format": "{desc}: {elapsed}{postfix}"}, **(progress or {})),
                       None, f"loading {options['name']}") if progress is not None else None
    try:
        with phases.reporting(None if bar is None else (lambda what: phase(bar, what))):
            try:
                model = _assemble(path, hydro, body_coupling, raw, options, bodies, content)
            except FileNotFoundError as e:
                if not (isinstance(raw, dict) and options["source"].startswith("<")) or base:
                    raise
                raise FileNotFoundError(
                    f"{str(e).rstrip('.')}. A config given as {options['source']} reads its relative paths from "
                    f"`base` (default the working directory, {os.getcwd()!r}): give "
                    "mfm.load(..., base=<the folder they are relative to>)") from None
        if bar is not None:
            phase(bar, "done")      # the bar keeps its line: "done" says the load ended there
    finally:
        if bar is not None:
            bar.close()             # after an error: its message follows the phase it stopped in
    return model


def _assemble(path, hydro, body_coupling, raw, options, bodies, content: bytes) -> Model:
    """:func:`load`'s work once the config is read: the tree, its water, its loads (``path``:
    the config file, or a stand-in name in the folder relative paths are read from)."""
    model = compile_tree(bodies, name=options["name"], gravity=options["gravity"])
    model = dataclasses.replace(model, source=options.get("source", str(path)),
                                source_sha256=hashlib.sha256(content).hexdigest())
    if hydro and "hydro" in options:
        # a database made from other hulls or BEM settings than the config has now (a config
        # given as a dict or text has no file for `mfm hydro` to remake it from: not checked)
        try:
            stale, why = (database_is_stale(path, parsed=(raw, options, bodies))
                          if not options["source"].startswith("<") else (False, ""))
        except (ConfigError, ValueError, OSError):
            # a config whose [hydro.bem] table cannot make a database has nothing to compare
            stale, why = False, ""
        if stale:
            warnings.warn(why, HydroDatabaseWarning, stacklevel=3)     # the caller of load
        try:
            spec = load_hydro_spec(model, bodies, options["hydro"], Path(path).parent,
                                   body_coupling)
        except FileNotFoundError as e:
            if not any("geometry" in b for b in raw.get("bodies", [])):
                raise
            # the config describes its hulls: the database is made from it
            raise FileNotFoundError(
                f"{str(e).rstrip('.')}. This config describes its hulls ([bodies.geometry]): make "
                f"its database with `mfm hydro {path}` (capytaine: pip install -e \".[bem]\"), "
                "or point [hydro] database at an existing one") from None
        model = dataclasses.replace(model, hydro=spec)
    # loads in registry order; each sees the model with the loads before it (a damping ratio is
    # set from the linearisation of the model as built so far)
    for table in TABLES:
        parsed = options.get("loads", {}).get(table)
        if parsed:
            load = resolve_damping_ratios(model, load_class(table).from_parsed(parsed, model))
            model = dataclasses.replace(model, loads=model.loads + (load,))
    return model
