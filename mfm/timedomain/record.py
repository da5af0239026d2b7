"""What a run records of each saved state: the state itself, and with ``record`` the outputs
(poses, joint reactions, energies, the loads' diagnostics), computed inside the time loop or, for
a small load memory, after it in one vmapped pass over the saved samples."""
from __future__ import annotations

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


def saved(model, loads, s, mem, record):
    """The outputs kept of one saved state. ``record``: False (the state), True (the state and
    every per-sample output), or a tuple of output names: a batch's form, the state without the
    loads' own states z (a radiation fit has thousands per sample: a 36-case sweep of one hour
    would hold gigabytes of them) and a dict of the named outputs only (the compiler drops the
    work of the others)."""
    if isinstance(record, tuple):
        rec = sample_outputs(model, loads, s, mem) if record else {}
        return (s.t, s.q, s.qd, s.qdd, jnp.zeros(0), s.iterations, {k: rec[k] for k in record})
    out = (s.t, s.q, s.qd, s.qdd, s.z, s.iterations)
    return out + ((sample_outputs(model, loads, s, mem),) if record else ())


# per-sample memory (floats) up to which the outputs of a recorded run are computed after the
# time loop, vmapped over the saved samples (matrix–matrix work) instead of inside it
DEFERRED_RECORD_MEMORY = 10_000


DEFERRED_RECORD_WIDTH = 32


def deferred(carry, record) -> bool:
    """Whether a recorded run evaluates its outputs after the time loop (:func:`rollout_blocks`):
    ``record is True`` and a memory of at most :data:`DEFERRED_RECORD_MEMORY` floats."""
    mem_size = sum(int(np.prod(np.shape(a))) for a in jax.tree_util.tree_leaves(carry[1]))
    return record is True and mem_size <= DEFERRED_RECORD_MEMORY


def outputs_after(model, loads, carries):
    """The outputs (:func:`saved`, ``record=True``) of stacked carries, in groups of a fixed
    width: every sample is computed by the same vmapped program whatever their number, so a run
    in chunks (progress bar) gives the same bits."""
    return map_in_groups(lambda sm: saved(model, loads, *sm, True), carries,
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
