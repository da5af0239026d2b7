"""What a run records of each saved state (:class:`Recording`): the state itself, and the
outputs (poses, joint reactions, energies, the loads' diagnostics), every one or those named,
computed inside the time loop or, for a small load memory, after it in one vmapped pass over the
saved samples (which :func:`~mfm.simulate` makes chunk by chunk beside the loop:
:mod:`mfm.runner.pipeline`)."""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..loads.assembly import applied_loads, state_offsets
from ..loads.base import Context
from ..mechanics import se3
from ..mechanics.dynamics import energies, evaluate, reaction_loads
from ..mechanics.kinematics import kinematics


def sample_outputs(model, loads, s, mem):
    """What the dataset keeps of one saved state: poses, reactions, energies, load diagnostics."""
    kin = kinematics(model, s.q, s.qd)
    body, tau, mass, _, outs = applied_loads(model, loads, s.t, s.q, s.qd, s.z, kin, mem,
                                             with_outputs=True, qdd_guess=s.qdd)
    ev = evaluate(model, s.q, s.qd, tau=tau, body_loads=body, extra_mass=mass, kin=kin)
    offs = state_offsets(loads)
    # the joints carry every load on the bodies, acceleration-proportional ones included
    F = None
    diag = {}
    for k, (ld, out) in enumerate(zip(loads, outs)):
        ctx = Context(model, s.t, s.q, s.qd, s.z[offs[k]:offs[k + 1]], kin, mem[k], s.qdd, ev.qdd)
        Fk = ld.reaction_loads(ctx, out)
        if Fk is not None:
            F = Fk if F is None else F + Fk
        diag.update(ld.diagnostics(ctx, out))
    ev_r = ev._replace(F=ev.F - (0.0 if body is None else body) + (0.0 if F is None else F))
    f_j, m_j = reaction_loads(model, ev_r)
    T, V = energies(model, s.q, s.qd, kin)
    angles = jax.vmap(se3.euler_zyx)(kin.E[:, :3, :3])
    return dict(body_position=kin.E[:, :3, 3], body_rotation=angles, joint_force=f_j,
                joint_moment=m_j, kinetic_energy=T, potential_energy=V, qdd=ev.qdd, **diag)


@dataclasses.dataclass(frozen=True)
class Recording:
    """What a run keeps of each saved state: a static option (part of the compiled function's
    key), like diffrax's ``SaveAt``.

    outputs: None for every per-sample output (:func:`sample_outputs`), or a tuple of the names to
        keep (the compiler drops the work of the others; () none).
    states: whether the loads' own states z are kept per sample (a batch drops them: a radiation
        fit has thousands per sample, and a 36-case sweep of one hour would hold gigabytes).

    A rollout gives ``(t, q, qd, qdd, z, iterations)`` per sample, and a dict of the outputs as a
    7th item unless it keeps none and the states (:attr:`STATE`).
    """
    outputs: tuple | None = ()
    states: bool = True

    @classmethod
    def of(cls, record) -> "Recording":
        """The recording of ``rollout``'s ``record=``: False (the state, :attr:`STATE`), True
        (the state and every output, :attr:`EVERY`), a tuple of output names (the batch form:
        those outputs, no z), or a Recording."""
        if isinstance(record, Recording):
            return record
        if record is False:
            return STATE
        if record is True:
            return EVERY
        if isinstance(record, tuple) and all(isinstance(n, str) for n in record):
            return cls(outputs=record, states=False)
        raise ValueError(f"record: {record!r}; give False (the state), True (every output), a "
                         "tuple of output names (those only, without the loads' states) or a "
                         "mfm.timedomain.record.Recording")

    @property
    def every(self) -> bool:
        return self.outputs is None

    @property
    def with_outputs(self) -> bool:
        """Whether a sample carries a dict of outputs (a 7th item)."""
        return self.outputs is None or bool(self.outputs) or not self.states


STATE = Recording((), True)
EVERY = Recording(None, True)
# every output without the loads' states per sample: what simulate keeps (its dataset has no z;
# an integrated state-space fit has ~10³ states a sample, M4 134's 20,000 steps 161 MB)
OUTPUTS = Recording(None, False)


def output_names(outputs) -> tuple:
    if isinstance(outputs, str):
        outputs = (outputs,)
    try:
        names = tuple(outputs)
    except TypeError:
        raise ValueError(f"outputs: {outputs!r}; give a sequence of output names") from None
    if not all(isinstance(n, str) for n in names):
        raise ValueError(f"outputs: {outputs!r}; give a sequence of output names (strings)")
    return tuple(dict.fromkeys(names))


def saved(model, loads, s, mem, recording: Recording):
    """What ``recording`` keeps of one saved state: (t, q, q̇, q̈, z or an empty z, iterations)
    and, where it has outputs, their dict."""
    out = (s.t, s.q, s.qd, s.qdd, s.z if recording.states else jnp.zeros(0), s.iterations)
    if not recording.with_outputs:
        return out
    rec = sample_outputs(model, loads, s, mem) if (recording.every or recording.outputs) else {}
    return out + (rec if recording.every else {k: rec[k] for k in recording.outputs},)


# per-sample memory (floats) up to which the outputs of a recorded run are computed after the
# time loop, vmapped over the saved samples (matrix–matrix work) instead of inside it
DEFERRED_RECORD_MEMORY = 10_000


DEFERRED_RECORD_WIDTH = 32


def deferred(carry, recording: Recording) -> bool:
    """Whether a recorded run evaluates its outputs after the time loop
    (:func:`~mfm.timedomain.rollout.rollout_blocks`): every output is recorded (:data:`EVERY`,
    :data:`OUTPUTS`) and the loads' memory is at most :data:`DEFERRED_RECORD_MEMORY` floats."""
    mem_size = sum(int(np.prod(np.shape(a))) for a in jax.tree_util.tree_leaves(carry[1]))
    return recording.every and mem_size <= DEFERRED_RECORD_MEMORY


def outputs_after(model, loads, carries, recording: Recording = EVERY):
    """What ``recording`` (:data:`EVERY` or :data:`OUTPUTS`) keeps (:func:`saved`) of stacked
    carries, in groups of a fixed width: every sample is computed by the same vmapped program
    whatever their number, so a run in chunks (the runner's) gives the same bits."""
    return map_in_groups(lambda sm: saved(model, loads, *sm, recording), carries,
                          DEFERRED_RECORD_WIDTH)


def map_in_groups(f, xs, width):
    """``f`` over the leading axis of the pytree ``xs``: ``jax.lax.map`` over groups of ``width``
    items that one ``jax.vmap`` evaluates together, the last group padded by repeating the last
    item (its results dropped). The shapes are written out, not inferred: items may be empty."""
    n = jax.tree_util.tree_leaves(xs)[0].shape[0]
    G = -(-n // width)
    pad = lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], G * width - n, 0)]).reshape(  # noqa: E731
        (G, width) + a.shape[1:])
    out = jax.lax.map(jax.vmap(f), jax.tree_util.tree_map(pad, xs))
    return jax.tree_util.tree_map(lambda a: a.reshape((G * width,) + a.shape[2:])[:n], out)
