"""Radiation strategies as objects, the ``radiation=`` of every front door (in the sense of
diffrax's solvers: each a small immutable object on an abstract base, its options its own fields).

    mfm.simulate(model, sea, ..., radiation=mfm.radiation.StateSpace(update="exact"))
    mfm.simulate(model, sea, ..., radiation=mfm.radiation.Convolution(memory_length=20.0))
    mfm.frequency_response(model, omega, radiation=mfm.radiation.Database())

The strings of before stay as aliases of these objects ("auto", "convolution", "state_space",
"state_space_exact", "none", "database"): :func:`resolve` turns either into what the loads are
built from, (name, memory, state-space options), and refuses options given twice or to a strategy
that has none. Each strategy says what it does to the Cummins radiation force

    F_r(t) = −∫₀^{T_K} K(τ) ξ̇(t − τ) dτ     (K from the database's B(ω))

and which domains it serves (:attr:`AbstractRadiation.time_domain`, ``frequency_domain``).
"""
from __future__ import annotations

import abc
import dataclasses
from types import MappingProxyType
from typing import ClassVar

UPDATES = ("integrated", "exact")


class AbstractRadiation(abc.ABC):
    """A radiation strategy. ``name``: its alias (the string of before); ``time_domain`` and
    ``frequency_domain``: where it serves. Subclasses are frozen dataclasses; :meth:`parts` gives
    (name, memory (s) or None, state-space options or None)."""
    name: ClassVar[str]
    time_domain: ClassVar[bool] = True
    frequency_domain: ClassVar[bool] = True

    @abc.abstractmethod
    def parts(self) -> tuple[str, float | None, dict | None]:
        """(the strategy's name for the loads, its memory length or None, its fit options or
        None)."""


@dataclasses.dataclass(frozen=True)
class Auto(AbstractRadiation):
    """Time domain: the convolution or the state space, whichever costs less for the run, the
    fit's states integrated where the integrator does that as well as exactly, and the fit judged
    on the model's modes (:func:`mfm.runner.choices.choose_radiation`). ``fit_options``: those of
    the fit where one is taken (:func:`hydro.statespace.fit_state_space`)."""
    fit_options: dict | None = None
    name: ClassVar[str] = "auto"
    frequency_domain: ClassVar[bool] = False

    def parts(self):
        return "auto", None, _options(self.fit_options)


@dataclasses.dataclass(frozen=True)
class Convolution(AbstractRadiation):
    """The Cummins integral evaluated directly over the memory ``memory_length`` (s; None: T_K
    from the decay of K). No fit. Frequency domain: its A(ω), B(ω) by Ogilvie from the same K."""
    memory_length: float | None = None
    name: ClassVar[str] = "convolution"

    def __post_init__(self):
        m = self.memory_length
        if m is not None and not (isinstance(m, (int, float)) and not isinstance(m, bool)
                                  and m > 0 and m < float("inf")):
            raise ValueError(f"Convolution(memory_length={m!r}): give a positive, finite number "
                             "of seconds, or None for T_K from the decay of K")

    def parts(self):
        return "convolution", None if self.memory_length is None else float(self.memory_length), None


@dataclasses.dataclass(frozen=True)
class StateSpace(AbstractRadiation):
    """The passive state-space fit of K (:mod:`hydro.statespace`, ``fit_options`` its options),
    its states ``update``\\ d by the integrator ("integrated": the integrator's order) or advanced
    exactly over each step for a velocity linear within it ("exact": stable at any dt, second
    order in the radiation). Frequency domain: the fit's A(ω), B(ω)."""
    update: str = "integrated"
    fit_options: dict | None = None
    name: ClassVar[str] = "state_space"

    def __post_init__(self):
        if self.update not in UPDATES:
            raise ValueError(f"StateSpace(update={self.update!r}); accepted: {list(UPDATES)}")

    def parts(self):
        name = "state_space" if self.update == "integrated" else "state_space_exact"
        return name, None, _options(self.fit_options)


@dataclasses.dataclass(frozen=True)
class NoMemory(AbstractRadiation):
    """A∞ alone: no radiation memory (A(ω) = A∞, B = 0)."""
    name: ClassVar[str] = "none"

    def parts(self):
        return "none", None, None


@dataclasses.dataclass(frozen=True)
class Database(AbstractRadiation):
    """The BEM's A(ω), B(ω) as given: frequency domain only (a database whose A and B are not
    Kramers–Kronig consistent has no exact time-domain counterpart)."""
    name: ClassVar[str] = "database"
    time_domain: ClassVar[bool] = False

    def parts(self):
        return "database", None, None


ALIASES = {"auto": Auto(), "convolution": Convolution(), "state_space": StateSpace(),
           "state_space_exact": StateSpace(update="exact"), "none": NoMemory(),
           "database": Database()}


def _options(options):
    if options is None:
        return None
    if not isinstance(options, (dict, MappingProxyType)):
        raise ValueError(f"fit_options: {options!r}; give a dict of options of "
                         "hydro.statespace.fit_state_space")
    return dict(options)


def as_strategy(radiation) -> AbstractRadiation:
    """The strategy object of ``radiation``: an :class:`AbstractRadiation` as it is, or the
    object of a string alias (:data:`ALIASES`)."""
    if isinstance(radiation, AbstractRadiation):
        return radiation
    if isinstance(radiation, str) and radiation in ALIASES:
        return ALIASES[radiation]
    raise ValueError(f"radiation={radiation!r}; accepted: "
                     + ", ".join(repr(a) for a in ALIASES)
                     + " or a strategy of mfm.radiation (Auto(), Convolution(memory_length=...), "
                     "StateSpace(update='integrated'|'exact'), NoMemory(), Database())")


def label(radiation) -> str:
    """How a result's attributes name ``radiation``: the string alias as given, else the object's
    repr (``StateSpace(update='exact', fit_options=None)``)."""
    return radiation if isinstance(radiation, str) else repr(as_strategy(radiation))


def resolve(radiation, memory=None, state_space_options=None, *, domain: str = "time"):
    """(name, memory, state_space_options) of ``radiation`` (an object or a string alias) for
    the loads, merged with the front door's own ``memory`` and ``state_space_options`` arguments
    (the string API's side options): an option given both ways with different values, or given to
    a strategy that has none, is refused naming both. ``domain``: "time" or "frequency" (a
    strategy that does not serve it is refused)."""
    strategy = as_strategy(radiation)
    if domain == "time" and not strategy.time_domain:
        raise ValueError(f"radiation={radiation!r} exists in the frequency domain only (the BEM's "
                         "A(ω), B(ω) as given); in the time domain use 'auto', 'convolution', "
                         "'state_space', 'state_space_exact' or 'none'")
    if domain == "frequency" and not strategy.frequency_domain:
        raise ValueError(f"radiation={radiation!r} chooses per run, in the time domain; in the "
                         "frequency domain use 'database', 'convolution', 'state_space' or 'none'")
    name, own_memory, own_options = strategy.parts()
    if memory is not None and own_memory is not None and float(memory) != own_memory:
        raise ValueError(f"memory={memory!r} and {strategy!r}: two memory lengths; give one")
    if state_space_options is not None and own_options is not None \
            and dict(state_space_options) != own_options:
        raise ValueError(f"state_space_options={state_space_options!r} and {strategy!r}: two sets "
                         "of fit options; give one")
    if memory is not None and name not in ("convolution", "auto"):
        raise ValueError(f"memory={memory!r} with radiation={radiation!r}: only the convolution "
                         "has a memory length (Convolution(memory_length=...))")
    return (name, own_memory if own_memory is not None else memory,
            own_options if own_options is not None else state_space_options)
