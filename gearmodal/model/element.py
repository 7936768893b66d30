"""What every element kind answers a :class:`~gearmodal.Model` (meshes, bearings, registered
kinds): its references to other components, a copy renamed into a drivetrain, and the checks
that need the model. :class:`Element` gives the answers from the kind's ``SCHEMA`` (every field
of type ``name`` other than ``name`` is a body); a kind with more to say overrides them
(:class:`~gearmodal.model.mesh.Mesh`, :class:`~gearmodal.model.bearing.Bearing`).
:func:`gearmodal.register_element` gives a registered class that does not derive from
:class:`Element` these answers, so the model treats every kind alike.
"""

from __future__ import annotations

import copy
from collections.abc import Callable

__all__ = ["Element", "PROTOCOL"]

#: the element protocol's methods (:func:`gearmodal.register_element` adds the missing ones)
PROTOCOL = ("references", "renamed", "check_in")


class Element:
    """Base of the element kinds: the protocol the model relies on, from ``SCHEMA``."""

    def references(self) -> list[tuple[str, str, str]]:
        """``(field, name, table)`` for each component this element names: ``table`` is the
        model's table it must be in (``"bodies"`` or ``"frames"``)."""
        return [(f.key, getattr(self, f.key), "bodies") for f in self.SCHEMA.fields
                if f.type == "name" and f.key != "name" and getattr(self, f.key, None)]

    def renamed(self, p: Callable[[str], str], prefix: str, ground: str | None = None):
        """A copy for a model merged under ``prefix`` (:meth:`gearmodal.Model.merge`): each
        name ``n`` it holds becomes ``p(n)`` (``prefix.n``), its ``stage`` the prefixed one (or
        ``prefix``); ``ground``: the body a reference to the ground now names (kinds that can
        name the ground)."""
        new = copy.copy(self)
        keys = self.SCHEMA.by_key()
        for key, f in keys.items():
            if f.type == "name" and key != "stage" and getattr(self, key, None):
                setattr(new, key, p(getattr(self, key)))
        if hasattr(new, "stage"):  # (a kind's structure field, listed in its schema or not)
            new.stage = p(self.stage) if self.stage else prefix
        return new

    def check_in(self, model) -> None:
        """Checks that need the model beyond :meth:`references` (none by default)."""
