"""Old import paths of mfm, kept working: one table of what moved where.

mfm's modules were one flat folder until the package was laid out by concern (README,
Architecture). Code written against the old paths keeps running: ``from mfm.simulate import
model_loads``, ``mfm.stability.largest_stable_dt``, ``from mfm.water import HydroSpec``. Each old
module is a stand-in in ``sys.modules`` whose attributes are looked up, on first use, in the
modules that hold them now; the first use of each old path warns once (:class:`MovedWarning`,
a ``FutureWarning``, so that it shows outside tests too) with the new name.

Nothing in the package imports through these paths; they are a table of names (strings), read
with ``importlib`` only when old code asks.
"""
from __future__ import annotations

import importlib
import sys
import types
import warnings


class MovedWarning(FutureWarning):
    """An old import path of mfm was used: the message gives the new one."""


# old module -> the modules that hold its names now, searched in order
MOVED_MODULES = {
    "mfm.simulate": ("mfm.timedomain.simulation", "mfm.timedomain.batch",
                     "mfm.timedomain.rollout", "mfm.timedomain.record",
                     "mfm.timedomain.progress", "mfm.timedomain.setup", "mfm.timedomain.checks",
                     "mfm.loads.assembly", "mfm.frequency.rest", "mfm.validation", "mfm.errors"),
    "mfm.se3": ("mfm.mechanics.se3",),
    "mfm.tree": ("mfm.mechanics.tree", "mfm.errors"),
    "mfm.model": ("mfm.mechanics.model",),
    "mfm.compile": ("mfm.mechanics.compile",),
    "mfm.kinematics": ("mfm.mechanics.kinematics",),
    "mfm.dynamics": ("mfm.mechanics.dynamics",),
    "mfm.points": ("mfm.mechanics.points",),
    "mfm.spectral": ("mfm.frequency.spectral",),
    "mfm.linear": ("mfm.frequency.linear",),
    "mfm.stability": ("mfm.studies.stability", "mfm.studies.floquet"),
    "mfm.sweep": ("mfm.studies.sweep", "mfm.errors"),
    "mfm.fidelity": ("mfm.studies.fidelity",),
    "mfm.wec": ("mfm.studies.wec",),
    "mfm.config": ("mfm.io.config",),
    "mfm.parsing": ("mfm.validation",),
    "mfm.build": ("mfm.io.build",),
    # mfm.cli is a module of its own (mfm/cli.py), so that `python -m mfm.cli` runs: a stand-in
    # in sys.modules has no spec for runpy ("mfm.cli.__spec__ is None")
    "mfm.plotting": ("mfm.io.plotting",),
    "mfm.bemgen": ("mfm.io.bemgen",),
    "mfm.water": ("mfm.loads.water", "hydro.prepare"),
    "mfm.ptos": ("mfm.loads.hydraulic_pto",),
}

# names renamed on the way (private helpers that other modules used: public in their new place)
RENAMED = {"_rollout_jit": "rollout_jit", "_as_loads": "as_loads", "_initial_vector": "initial_vector",
           "_number": "finite_number", "_state_offsets": "state_offsets", "_sea_labels": "sea_labels",
           "_stage_offsets": "stage_offsets", "_check_sea": "check_sea", "_init_memories": "init_memories",
           "_update_memories": "update_memories", "_progress_options": "progress_options",
           "_water": "water_of", "_record": "sample_outputs"}

# names that left a module that is still there: module -> {name: the module that holds it now}
MOVED_NAMES = {"mfm.loads.catenary": {"linearise_lines": "mfm.frequency.rest"}}

# front-door names that are the same modules under a shorter name: no warning
ALIASES = {"mfm.integrators": "mfm.timedomain.integrators"}

# attributes of the package itself that were modules (``mfm.stability``): their stand-ins
# (``mfm.simulate`` is the function)
MOVED_ATTRIBUTES = tuple(old.rpartition(".")[2] for old in MOVED_MODULES if old != "mfm.simulate")

_warned: set[str] = set()


def _warn_once(old: str, new: str, stacklevel: int = 3):
    if old in _warned:
        return
    _warned.add(old)
    warnings.warn(f"{old} has moved to {new}; the old name keeps working for now, but use the new "
                  "one", MovedWarning, stacklevel=stacklevel)


class _Moved(types.ModuleType):
    """The stand-in for an old module: its names come from the modules that hold them now."""

    def __init__(self, old: str, targets: tuple[str, ...]):
        super().__init__(old, f"Moved: see {', '.join(targets)}.")
        self.__targets = targets

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        new = RENAMED.get(name, name)
        for target in self.__targets:
            try:
                module = importlib.import_module(target)
            except ImportError:
                continue
            if hasattr(module, new):
                value = getattr(module, new)
                # name the module that defines it where that is known (a function, a class)
                home = getattr(value, "__module__", None)
                if not (isinstance(home, str) and home.startswith(("mfm.", "hydro."))
                        and getattr(sys.modules.get(home), new, None) is value):
                    home = target
                _warn_once(f"{self.__name__}.{name}", f"{home}.{new}")
                return value
        raise AttributeError(f"module {self.__name__!r} has no attribute {name!r} (it moved: "
                             f"look in {', '.join(self.__targets)})")

    def __dir__(self):
        names = set()
        for target in self.__targets:
            try:
                names.update(dir(importlib.import_module(target)))
            except ImportError:
                pass
        return sorted(names)


def install():
    """Put the stand-ins of the old modules in ``sys.modules`` (where an import finds them before
    any file: ``from mfm.simulate import model_loads`` keeps the function ``mfm.simulate``)."""
    for old, targets in MOVED_MODULES.items():
        sys.modules.setdefault(old, _Moved(old, targets))
    for old, new in ALIASES.items():
        sys.modules.setdefault(old, importlib.import_module(new))
    for module, names in MOVED_NAMES.items():
        _forward_names(importlib.import_module(module), names)


def _forward_names(module, names: dict):
    """Give ``module`` a module-level ``__getattr__`` that finds ``names`` where they are now."""
    def __getattr__(name):
        if name in names:
            _warn_once(f"{module.__name__}.{name}", f"{names[name]}.{name}")
            return getattr(importlib.import_module(names[name]), name)
        raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")

    module.__getattr__ = __getattr__


def package_attribute(name: str):
    """``mfm.<name>`` for a module that moved (``mfm.stability``): its stand-in, whose names warn
    once each with where they are now; AttributeError for any other name."""
    if name not in MOVED_ATTRIBUTES:
        raise AttributeError(f"module 'mfm' has no attribute {name!r}")
    return sys.modules[f"mfm.{name}"]
