"""Strategies as objects (mfm.radiation; the integrators' abstract base): the objects run what
their string aliases run, to the bit; options given twice or where they do not belong are
refused, naming both."""
from pathlib import Path

import numpy as np
import pytest

import mfm
from mfm.radiation import Auto, Convolution, Database, NoMemory, StateSpace, resolve
from mfm.timedomain import integrators

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.fixture(scope="module")
def rm3():
    return mfm.load(CONFIGS / "rm3.toml")


def test_objects_run_what_their_aliases_run(rm3):
    run = dict(duration=10.0, dt=0.1, q0={"spar.heave": 0.2})
    a = mfm.simulate(rm3, radiation=StateSpace(update="exact"), **run)
    b = mfm.simulate(rm3, radiation="state_space_exact", **run)
    np.testing.assert_array_equal(a.q.values, b.q.values)
    c = mfm.simulate(rm3, radiation=Convolution(memory_length=20.0), **run)
    d = mfm.simulate(rm3, radiation="convolution", memory=20.0, **run)
    np.testing.assert_array_equal(c.q.values, d.q.values)
    assert c.attrs["memory_length_s"] == 20.0
    omega = np.array([0.5, 1.0])
    for obj, alias in ((Database(), "database"), (StateSpace(), "state_space"),
                       (NoMemory(), "none")):
        x = mfm.frequency_response(rm3, omega, radiation=obj, joint_reactions=False)
        y = mfm.frequency_response(rm3, omega, radiation=alias, joint_reactions=False)
        np.testing.assert_array_equal(x.rao.values, y.rao.values)
        assert x.attrs["radiation"] == repr(obj) and y.attrs["radiation"] == alias


def test_options_given_twice_or_out_of_place_are_refused():
    assert resolve("state_space_exact") == ("state_space_exact", None, None)
    assert resolve(StateSpace(fit_options={"order": 4})) == ("state_space", None, {"order": 4})
    assert resolve(Auto(), 30.0) == ("auto", 30.0, None)
    with pytest.raises(ValueError, match="two memory lengths"):
        resolve(Convolution(memory_length=20.0), 10.0)
    with pytest.raises(ValueError, match="two sets of fit options"):
        resolve(StateSpace(fit_options={"order": 4}), None, {"order": 6})
    with pytest.raises(ValueError, match="only the convolution has a memory length"):
        resolve("state_space", 10.0)
    with pytest.raises(ValueError, match=r"update='fast'.*accepted"):
        StateSpace(update="fast")
    with pytest.raises(ValueError, match="memory_length=-1"):
        Convolution(memory_length=-1)
    with pytest.raises(ValueError, match="frequency domain only"):
        resolve(Database())
    with pytest.raises(ValueError, match="chooses per run"):
        resolve(Auto(), domain="frequency")
    with pytest.raises(ValueError, match=r"radiation='fast'; accepted"):
        resolve("fast")


def test_integrators_declare_order_and_stage_offsets():
    for name, cls in integrators.INTEGRATORS.items():
        integ = cls()
        assert isinstance(integ, integrators.AbstractIntegrator)
        assert integ.name == name and integ.order >= 1 and integ.evaluations >= 1
        offs = tuple(integ.stage_offsets)
        assert offs and all(0.0 <= o <= 1.0 for o in offs)

    class Half(integrators.AbstractIntegrator):       # no step: cannot be made
        name = "half"

        def init(self, f, t0, q0, qd0, z0):
            return None

    with pytest.raises(TypeError, match="abstract"):
        Half()
