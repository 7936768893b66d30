"""A new element kind is one class with its schema (issue 20): a torsional end stop, defined
here as a contributor would, assembles, solves, simulates and round-trips through model files
with no change to gearmodal."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.model.schema import NAME, REQUIRED, Field, Table

K_SHAFT, K_STOP, PLAY = 1e3, 1e5, 0.01  # N m/rad, N m/rad, rad


@gm.register_element
@dataclass(eq=False)
class EndStop:
    """Bodies ``a`` and ``b`` turn freely against each other by +-``play`` (rad), then hit a
    stop of ``stiffness`` (N m/rad) on either side."""

    name: str
    a: str
    b: str
    stiffness: float
    play: float

    TABLE: ClassVar[str] = "end_stops"
    SCHEMA: ClassVar[Table] = Table("end_stops", (
        NAME,
        Field("a", "name", default=REQUIRED, doc="first body"),
        Field("b", "name", default=REQUIRED, doc="second body"),
        Field("stiffness", "number", "N m/rad", low=0.0, default=REQUIRED, doc="stop"),
        Field("play", "number", "rad", low=0.0, default=REQUIRED, doc="free play per side")),
        "A torsional end stop.")

    def contribute(self, ctx) -> None:
        a, b = ctx.model.bodies[self.a], ctx.model.bodies[self.b]
        rz = np.eye(6)[5]  # the rotation about z of a body centre
        w = ctx.row([(a, rz), (b, -rz)])
        for side, sign in (("+", 1.0), ("-", -1.0)):
            ctx.contact(sign * w, self.play, self.stiffness, 0.0, False, self, side, "stop",
                        columns=[(f"{self.name}.theta", sign)])


def _model():
    m = gm.Model("stop", input="a")
    m.add(gm.RigidBody(name="a", mass=1.0, inertia=0.01))
    m.add(gm.RigidBody(name="b", mass=1.0, inertia=0.02))
    m.add(gm.Shaft("shaft", "a", "b", K_SHAFT))
    m.add(gm.Bearing("hold", "b", None, stiffness={"theta": 1e9}))
    m.add(EndStop("stop", "a", "b", K_STOP, PLAY))
    return m


def test_the_new_kind_assembles_its_rows():
    asm = _model().assemble()
    c = asm.contacts
    assert list(zip(c.element, c.contact, c.kind, strict=True)) == [
        ("stop", "+", "stop"), ("stop", "-", "stop")]
    np.testing.assert_array_equal(c.W, [[1.0, -1.0], [-1.0, 1.0]])
    np.testing.assert_array_equal(c.offset, [PLAY, PLAY])


def test_the_new_kind_engages_at_the_closed_form_torque():
    """Torque T on a: below K_SHAFT * PLAY the stop is open (angle T / K_SHAFT); above,
    T = K_SHAFT d + K_STOP (d - PLAY)."""
    for torque in (5.0, 50.0, -50.0):
        eq = gm.equilibrium(_model(), {"a.torque": torque})
        d = eq.q["a.theta"] - eq.q["b.theta"]
        if abs(torque) < K_SHAFT * PLAY:
            expect = torque / K_SHAFT
        else:
            expect = math.copysign((abs(torque) + K_STOP * PLAY) / (K_SHAFT + K_STOP), torque)
        assert d == pytest.approx(expect, rel=1e-9), torque
        assert eq.q["b.theta"] == pytest.approx(torque / 1e9, rel=1e-6)  # b's bearing holds T


def test_the_new_kind_simulates_with_events_and_its_force_column():
    m = _model()
    sim = gm.simulate(m, 0.05, dt=1e-4, loads={"a.torque": 50.0})
    assert set(sim.events.element) == {"stop"}
    assert "stop.theta" in sim.forces.columns
    closed = sim.contact_state["stop:+"]
    d = sim.q["a.theta"] - sim.q["b.theta"]
    force = np.where(closed, K_STOP * (d - PLAY), 0.0)
    np.testing.assert_allclose(sim.forces["stop.theta"], force, rtol=1e-9, atol=1e-9)


def test_the_new_kind_round_trips_through_a_model_file():
    m = _model()
    text = gm.dumps(m)
    assert "[[end_stops]]" in text
    again = gm.loads(text)
    np.testing.assert_array_equal(again.assemble().contacts.W, m.assemble().contacts.W)
    with pytest.raises(gm.ModelError, match=r"end_stops\[0\]\.play = -1\.0: must be >= 0 rad"):
        gm.loads(text.replace(f"play = {PLAY!r}", "play = -1.0"))


def test_the_new_kind_is_prefixed_when_a_stage_is_merged():
    outer = gm.Model("outer")
    outer.merge(_model(), "s1")
    stop = outer.elements_of(EndStop)["s1.stop"]
    assert (stop.a, stop.b) == ("s1.a", "s1.b")
    assert outer.assemble().contacts.element == ["s1.stop", "s1.stop"]
