"""Traced programs kept on disk: a later process skips jax's tracing and lowering of a run's
programs as :mod:`mfm.runner.xla`'s persistent cache lets it skip XLA's compilation.

Why. With the compilation cache filled, a first :func:`mfm.simulate` still traces each of its
programs (Python walking the model, its loads and the integrator: about a second each for RM3's
start, chunk and the checks' linearisation) and lowers them to StableHLO (another half second):
about half of the wait for a cached first answer (benchmarks/RESULTS.md, "First answers"). jax's
own answer is :mod:`jax.export`: a traced and lowered function serialised (StableHLO bytecode),
called later without tracing it again; its compilation then hits the persistent cache.

How a program is found again. The file's name is a hash of everything that decides the
program: the function's name; the pytree structure of its arguments with every node's type and
static data (:func:`_fingerprint`: ints, strings, tuples, frozen dataclasses, numpy arrays by
their bytes); the shape, dtype and weak type of each array leaf; the static arguments; the source
of the mfm and hydro packages (every ``.py`` file and ``mfm/data``); the versions of jax, jaxlib
and equinox; the backend and its device kind; ``XLA_FLAGS`` and the jax settings that change a
trace; mfm's module-level settings as they are at the call (:func:`_settings`). A function is keyed by its name where it is a top-level function of mfm or hydro (its code is in the source hash). Anything the hash cannot key with certainty (any other function, a user's own Load class outside
mfm, an object of unknown type among the static data) makes the call take the ordinary path:
this is a cache, never a second meaning. The results are the same bits (the same program;
tests/test_first_call.py).

Where. Beside the compilation cache, in its folder ``mfm-programs`` (off with it, or alone with
``MFM_PROGRAM_CACHE=off``); at most :data:`FOLDER_BYTES`, the least recently used dropped first.
Each file is sealed with the sha256 of its content (:func:`hydro.fitcache.seal`) and put in
place whole; one that fails the check (a flipped bit, a torn file) is removed, warned about once
and made anew, never deserialised.
Serialisation needs the ``flatbuffers`` package (a dependency of mfm); without it, the ordinary
path.
"""
from __future__ import annotations

import dataclasses
import dis
import enum
import functools
import hashlib
import os
import pickle
import sys
import threading
import types
from pathlib import Path

import jax
import numpy as np

from hydro import fitcache

from . import xla as _xla

ENV = "MFM_PROGRAM_CACHE"
FOLDER_BYTES = 512 * 2**20
# modules whose types may appear in a keyed structure: their code is in the hash (mfm, hydro) or
# their version is (jax, equinox); builtins and numpy types are keyed by value
_KEYED_MODULES = ("mfm", "hydro", "jax", "jaxlib", "equinox", "builtins", "numpy", "collections")
# counts of what happened, for tests and benchmarks: "loaded", "saved", "ordinary" (not keyable
# or no cache), "failed" (export or serialisation refused; the ordinary path ran)
COUNTS: dict = {"loaded": 0, "saved": 0, "ordinary": 0, "failed": 0}


class _Unkeyable(Exception):
    """Something in a program's arguments that the hash cannot key with certainty."""


def folder() -> Path | None:
    """The programs' folder, or None when either cache is off."""
    cache = _xla.compilation_cache()
    if cache is None or jax.config.jax_disable_jit:
        return None
    if _xla.switched_off(os.environ.get(ENV)):
        return None
    return Path(cache) / "mfm-programs"


def _type_name(t: type) -> str:
    module = getattr(t, "__module__", "") or ""
    if module.split(".")[0] not in _KEYED_MODULES:
        raise _Unkeyable(f"type {module}.{t.__qualname__}")
    return f"{module}.{t.__qualname__}"


def _fingerprint(x, out: list) -> None:
    """Append to ``out`` strings that determine ``x`` (static data of a pytree, a static
    argument) or raise :class:`_Unkeyable`."""
    if x is None or isinstance(x, (bool, int, float, complex, str, bytes)):
        out.append(f"{type(x).__name__}:{x!r}")
    elif isinstance(x, jax.tree_util.PyTreeDef):
        _treedef(x, out)
    elif isinstance(x, np.ndarray):
        out.append(f"nd:{x.dtype.str}:{x.shape}:{hashlib.sha256(np.ascontiguousarray(x).tobytes()).hexdigest()}")
    elif isinstance(x, np.generic):
        out.append(f"np:{x.dtype.str}:{x.item()!r}")
    elif isinstance(x, type):
        out.append(f"type:{_type_name(x)}")
    elif isinstance(x, enum.Enum):
        out.append(f"enum:{_type_name(type(x))}.{x.name}")
    elif isinstance(x, (tuple, list)):
        out.append(f"{_type_name(type(x))}[{len(x)}")
        for item in x:
            _fingerprint(item, out)
        out.append("]")
    elif isinstance(x, dict):
        out.append(f"dict[{len(x)}")
        for k, v in x.items():
            _fingerprint(k, out)
            _fingerprint(v, out)
        out.append("]")
    elif isinstance(x, frozenset):
        parts = []
        for item in x:
            one: list = []
            _fingerprint(item, one)
            parts.append("|".join(one))
        out.append("frozenset{" + ",".join(sorted(parts)) + "}")
    elif dataclasses.is_dataclass(x) and type(x).__dataclass_params__.frozen:
        out.append(f"dc:{_type_name(type(x))}(")
        for f in dataclasses.fields(x):
            out.append(f.name)
            _fingerprint(getattr(x, f.name), out)
        out.append(")")
    elif type(x).__name__ == "_Missing" and type(x).__module__.startswith("equinox"):
        out.append("eqx-missing")
    elif _own_function(x):
        # a function of mfm or hydro at its module's top level (optimize's mean power): its code
        # is in the source hash, so its name determines it
        out.append(f"fn:{x.__module__}.{x.__qualname__}")
    else:
        raise _Unkeyable(f"{type(x).__module__}.{type(x).__qualname__}")


def _own_function(x) -> bool:
    """Whether ``x`` is a plain function defined at the top level of an mfm or hydro module
    (no closure, no defaults that could differ, the module's own object under its name): one
    whose source :func:`_source_hash` keys. A user's function, a lambda or a closure is not."""
    if not isinstance(x, types.FunctionType) or x.__closure__ or x.__defaults__ \
            or x.__kwdefaults__:
        return False
    module = getattr(x, "__module__", "") or ""
    if module.split(".")[0] not in ("mfm", "hydro") or "<" in x.__qualname__ \
            or "." in x.__qualname__:
        return False
    return getattr(sys.modules.get(module), x.__qualname__, None) is x


def _treedef(td, out: list) -> None:
    """A pytree structure, node by node: each node's type and static (auxiliary) data."""
    children = td.children()
    if td.num_nodes == 1 and td.num_leaves == 1:
        out.append("*")
        return
    data = td.node_data()
    if data is None:
        raise _Unkeyable("a pytree node without data")
    kind, aux = data
    out.append(f"<{_type_name(kind)}")
    _fingerprint(aux, out)
    out.append(f"#{len(children)}")
    for child in children:
        _treedef(child, out)
    out.append(">")


def _leaf(x) -> str:
    shape, dtype = np.shape(x), getattr(x, "dtype", None)
    weak = getattr(x, "weak_type", False)
    if dtype is None:       # a Python scalar: jax takes it as a weakly typed array
        dtype, weak = np.asarray(x).dtype, True
    return f"{np.dtype(dtype).str}{tuple(shape)}{'w' if weak else ''}"


_SOURCE: str | None = None


def _source_hash() -> str:
    """A hash of the code that traces the programs: every .py file of mfm and hydro, and
    mfm/data (module-level tables a trace may close over)."""
    global _SOURCE
    if _SOURCE is None:
        h = hashlib.sha256()
        here = Path(__file__).resolve().parent
        for root in (here, Path(fitcache.__file__).resolve().parent):    # mfm/, hydro/
            files = [p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                     and (p.suffix == ".py"
                          or root == here and p.relative_to(root).parts[0] == "data")]
            for p in sorted(files):
                h.update(str(p.relative_to(root.parent)).encode())
                h.update(p.read_bytes())
        _SOURCE = h.hexdigest()
    return _SOURCE


def _environment() -> list:
    import equinox
    import jaxlib

    device = jax.devices()[0]
    return [jax.__version__, jaxlib.__version__, equinox.__version__, device.platform,
            getattr(device, "device_kind", ""), os.environ.get("XLA_FLAGS", ""),
            str(jax.config.jax_enable_x64), str(jax.config.jax_default_matmul_precision),
            str(jax.config.jax_numpy_rank_promotion), str(jax.config.jax_numpy_dtype_promotion),
            _source_hash()]


def _settings() -> list:
    """mfm's and hydro's module-level settings as they are now (upper-case names holding
    numbers, strings or tuples of them, e.g. ``record.DEFERRED_RECORD_MEMORY``): a trace may read
    them, and a program made under other values is another program (a test that changes one
    must not be given the program made before).

    A module imported after this process's first key (the radiation fit's check, imported by
    the checks between two programs of one run) gives only the settings that differ from what its
    code assigns (:func:`_literal_defaults`; a default is in the source hash already): with all of
    them, the same program was keyed twice in one process, before the import and after it (the
    checks' linearisation of M4 134: traced and lowered twice)."""
    global _EARLY
    simple = (bool, int, float, str, type(None))
    out = []
    modules = [(n, m) for n, m in sorted(sys.modules.items())
               if m is not None and n.split(".")[0] in ("mfm", "hydro")]
    if _EARLY is None:
        _EARLY = frozenset(n for n, _ in modules)
    for mod_name, mod in modules:
        defaults = None if mod_name in _EARLY else _defaults_of(mod_name, mod)
        for attr, value in sorted(vars(mod).items()):
            if f"{mod_name}.{attr}" in _WHERE:
                continue
            if attr.isupper() and (isinstance(value, simple) or isinstance(value, tuple) and all(
                    isinstance(v, simple) for v in value)):
                if defaults is not None and attr in defaults and _same(defaults[attr], value):
                    continue
                out.append(f"{mod_name}.{attr}={value!r}")
    return out


_EARLY: frozenset | None = None      # the mfm and hydro modules imported at the first key
_DEFAULTS: dict = {}


def _same(a, b) -> bool:
    return type(a) is type(b) and a == b


def _defaults_of(mod_name: str, mod) -> dict:
    with _LOCK:
        found = _DEFAULTS.get(mod_name)
    if found is None:
        found = _literal_defaults(mod)
        with _LOCK:
            _DEFAULTS[mod_name] = found
    return found


def _literal_defaults(mod) -> dict:
    """``{NAME: value}`` of each upper-case name a module's top level assigns once, from a
    constant (``X = 0.05``, ``X = (0.5, 2.0)``, ``X = 2 * 2**30``: the compiler folds them into one
    constant), read from its code object (the ``.pyc``). A name assigned otherwise (an
    expression, a condition, an import, twice) is not a default here, and stays in the key."""
    try:
        code = mod.__spec__.loader.get_code(mod.__name__)
    except Exception:        # no loader, no source: every setting of the module stays keyed
        return {}
    if code is None:
        return {}
    stores, found, prev = {}, {}, None
    for ins in dis.get_instructions(code):
        if ins.opname in ("STORE_NAME", "STORE_GLOBAL") and ins.argval.isupper():
            stores[ins.argval] = stores.get(ins.argval, 0) + 1
            if (prev is not None and prev.opname in ("LOAD_CONST", "LOAD_SMALL_INT")
                    and not prev.is_jump_target and not ins.is_jump_target):
                found[ins.argval] = prev.argval
        prev = ins
    return {k: v for k, v in found.items() if stores[k] == 1}


# settings that say where the caches are, not what a program is: a warm cache copied to another
# folder keeps its keys (with the folder in the key, RM3's first run there took 38.7 s, not 5.5 s:
# every program traced and compiled again; issue 54, item 18)
_WHERE = frozenset({"mfm.runner.xla.COMPILATION_CACHE"})


def key(name: str, args: tuple, static: dict) -> str:
    """The hash naming a program (see the module's docstring); raises :class:`_Unkeyable`."""
    leaves, tree = jax.tree_util.tree_flatten(args)
    out = [name, *_environment(), *_settings()]
    _treedef(tree, out)
    out.extend(_leaf(x) for x in leaves)
    for k in sorted(static):
        out.append(k)
        _fingerprint(static[k], out)
    return hashlib.sha256("\n".join(out).encode()).hexdigest()


_MADE: dict = {}
_ORDINARY_ONCE: dict = {}     # the ordinary path's programs compiled with options (program())
_LOCK = threading.Lock()


def eval_shape(jitted, *args, **static):
    """``jax.eval_shape`` of the jitted function ``jitted(*args, **static)``, by the jit itself:
    its trace is kept by jax for arguments of that structure, so a later call (a warm
    ``simulate``) does not trace again (``jax.eval_shape`` of a new closure does: M4 134's load
    memories, 0.13 s of each warm run)."""
    if hasattr(jitted, "eval_shape"):
        return jitted.eval_shape(*args, **static)
    return jax.eval_shape(functools.partial(jitted, **static), *args)    # jax before the method


def program(jitted, name: str, args: tuple, static: dict | None = None, *,
            once: bool = False) -> "Program":
    """The :class:`Program` of ``jitted(*args, **static)``: the one this process made already
    for that key, else one from disk, else one traced now (and saved). ``once``: a program run
    once per call, compiled with :func:`mfm.runner.xla.once_options` (faster to compile, slower to
    run)."""
    static = dict(static or {})
    options = _xla.once_options() if once else None
    where = folder()
    try:
        if where is None:
            raise _Unkeyable("no cache")
        k = key(name, args, static)
    except _Unkeyable:
        COUNTS["ordinary"] += 1
        if not options:
            return Program(jitted, args, static, None)      # jax's own jit cache keeps it
        # compiled with its options by the Program itself, which jax's cache does not keep:
        # kept here, per structure, so that a later call (the equilibrium's next model, a
        # second linearisation) does not compile it again
        k = (name, _signature(args), tuple(sorted(static.items())))
        with _LOCK:
            made = _ORDINARY_ONCE.get(k)
        if made is None:
            made = Program(jitted, args, static, None, options)
            with _LOCK:
                made = _ORDINARY_ONCE.setdefault(k, made)
        return made
    k = (k, bool(options))         # the same program compiled at XLA's level 0 is another one
    with _LOCK:
        made = _MADE.get(k)
    if made is None:
        made = Program(jitted, args, static, where / f"{name}-{k[0]}.bin", options)
        with _LOCK:
            made = _MADE.setdefault(k, made)
    return made


class Program:
    """``jitted(*args, **static)`` for arguments of one structure (that of the ``args`` given
    when made: arrays or ``jax.ShapeDtypeStruct``s), from ``path`` where a process made it before
    (None: the ordinary path). Call it with arrays of that structure; :meth:`compile` compiles it
    ahead (from any thread). Made by :func:`program`."""

    def __init__(self, jitted, args: tuple, static: dict, path: Path | None,
                 options: dict | None = None):
        self._jitted, self._static = jitted, static
        self._options = options      # XLA's compiler options (None: its defaults)
        self._ordinary = lambda *a: jitted(*a, **static)
        self._lower = lambda *a: jitted.lower(*a, **static)
        self._tree = jax.tree_util.tree_structure(args)
        self._call = None
        # what compile() made, and for which arguments: called directly while they match (a
        # jit called afterwards with concrete arrays lowers them anew, with other sharding
        # annotations than the abstract ones compile() saw, and compiles the program again: RM3's
        # chunk, 5 s of a cold first run)
        self._compiled = None
        if path is None:
            return
        try:
            loaded = _load(path)
        except Exception:      # an unreadable file: made anew below (a damaged one: _load)
            loaded = None
        if loaded is not None:
            exported, self._out_tree = loaded
            COUNTS["loaded"] += 1
        else:
            try:
                exported, self._out_tree = _export(jitted, args, static, self._tree)
                _save(path, exported, self._out_tree)
                COUNTS["saved"] += 1
            except Exception:  # a program jax cannot export (a host callback): the ordinary path
                COUNTS["failed"] += 1
                return
        self._exported = exported
        self._call = jax.jit(exported.call)

    def _flat(self, args):
        leaves, tree = jax.tree_util.tree_flatten(args)
        if tree != self._tree:
            raise ValueError("a Program is called with arguments of another structure than it "
                             "was made for")
        return leaves

    def __call__(self, *args):
        compiled = self._compiled
        matches = compiled is not None and _signature(args) == compiled[0]
        if self._options and not matches:
            self.compile(*args)          # with its options: jax's own call would use the defaults
            compiled, matches = self._compiled, True
        if matches:
            out = compiled[1](*(args if self._call is None else self._flat(args)))
        elif self._call is None:
            return self._ordinary(*args)
        else:
            out = self._call(*self._flat(args))
        return out if self._call is None else jax.tree_util.tree_unflatten(self._out_tree, out)

    def shapes(self, *args):
        """The outputs' structure, shapes and dtypes (ShapeDtypeStructs) for arguments like
        ``args``: from the saved program where there is one, without tracing."""
        if self._call is None:
            return eval_shape(self._jitted, *args, **self._static)
        return jax.tree_util.tree_unflatten(self._out_tree, [
            jax.ShapeDtypeStruct(a.shape, a.dtype, weak_type=a.weak_type)
            for a in self._exported.out_avals])

    def compile(self, *args) -> None:
        """Compile for arguments like ``args`` (arrays or ShapeDtypeStructs), here and now; a
        later call with arguments of the same structure, shapes, dtypes and weak types runs
        that executable."""
        lowered = (self._lower(*args) if self._call is None
                   else self._call.lower(*self._flat(args)))
        compiled = lowered.compile(self._options) if self._options else lowered.compile()
        self._compiled = (_signature(args), compiled)


def _signature(args) -> tuple:
    """What an executable compiled for ``args`` requires of the arguments it is called with:
    their structure (static data included) and each leaf's shape, dtype and weak type."""
    leaves, tree = jax.tree_util.tree_flatten(args)
    return tree, tuple((np.shape(x), np.dtype(getattr(x, "dtype", type(x))),
                        bool(getattr(x, "weak_type", False))) for x in leaves)


def _export(jitted, args, static, tree):
    """jitted's program for ``args`` as a jax.export.Exported of the flat leaves, and the
    structure of its outputs."""
    got = {}

    def flat(*leaves):
        out = jitted(*jax.tree_util.tree_unflatten(tree, leaves), **static)
        values, got["tree"] = jax.tree_util.tree_flatten(out)
        return values

    leaves = [jax.ShapeDtypeStruct(np.shape(x), x.dtype, weak_type=getattr(x, "weak_type", False))
              if hasattr(x, "dtype") else x for x in jax.tree_util.tree_leaves(args)]
    exported = jax.export.export(jax.jit(flat))(*leaves)
    return exported, got["tree"]


def _load(path: Path):
    """The program saved at ``path`` and its outputs' structure, or None: no file, or a damaged
    one (it fails its sha256, or what it holds does not come back), which is removed with a
    warning (:func:`hydro.fitcache.discard`) and made anew by the caller."""
    payload = fitcache.read_sealed(path, _WHAT)
    if payload is None:
        return None
    try:
        n = int.from_bytes(payload[:8], "little")
        out_tree = pickle.loads(payload[8:8 + n])
        exported = jax.export.deserialize(bytearray(payload[8 + n:]))
    except Exception as e:     # sealed by another code: not this process's to read
        fitcache.discard(path, f"it cannot be read back ({type(e).__name__}: {e})", _WHAT)
        return None
    return exported, out_tree


_WHAT = "saved traced program"


def _save(path: Path, exported, out_tree) -> None:
    tree = pickle.dumps(out_tree)
    pickle.loads(tree)                 # a structure that does not come back is not saved
    # sealed with its sha256 (checked when read: a flipped bit is made anew, not deserialised),
    # whole or absent, whatever another process does; the least recently used dropped past
    # FOLDER_BYTES (the fit cache's helpers)
    blob = fitcache.seal(len(tree).to_bytes(8, "little") + tree + bytes(exported.serialize()))
    fitcache.write_whole(path, lambda f: f.write(blob))
    fitcache.trim(path.parent, FOLDER_BYTES, "*.bin")
