"""Errors raised by gearmodal, by kind, so that a caller can tell bad input from a failed solve:

- :class:`ModelError` (a ``ValueError``): bad input. The message names the offending field, the
  value given and what is allowed; the CLI prints it on one line and exits with status 2.
- :class:`SolveError` (a ``RuntimeError``): the input was valid but the solve failed (a
  solution that is not finite, a method that diverged, more contact events in one step than
  allowed, a solver that gave up); the message names the setting to change. CLI status 4.
- :class:`StoreError`: a store of results (a sweep's, the fidelity ladder's) refused: written
  by another gearmodal, for another scene or metrics, or damaged. CLI status 5.

All three are :class:`GearmodalError`, which carries ``field`` and ``message``.
"""

from __future__ import annotations


class GearmodalError(Exception):
    """An error gearmodal reports on one line: ``field`` (what it is about) and ``message``."""

    def __init__(self, field: str, message: str):
        self.field = field
        self.message = message
        if not field:
            text = message
        elif message.startswith("= "):
            text = f"{field} {message}"  # "stage1.ring.teeth = 98: ..."
        else:
            text = f"{field}: {message}"
        super().__init__(text)

    def __reduce__(self):  # pickle by (field, message): errors cross process pools intact
        return (type(self), (self.field, self.message))


class ModelError(GearmodalError, ValueError):
    """Invalid input: the message names the field, the value and the allowed range."""


class SolveError(GearmodalError, RuntimeError):
    """A solve that failed on valid input: the message names the setting to change."""


class StoreError(GearmodalError):
    """A store of results that is refused (another version, scene or metrics; damaged)."""


def unknown(kind: str, name: str, names) -> str:
    """The message for a name that is not there: ``no such <kind>``, the closest names
    (``did you mean ...?``, by :func:`difflib.get_close_matches`) and the names there are."""
    import difflib

    names = [str(n) for n in names]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.6)
    hint = f" (did you mean {', '.join(map(repr, close))}?)" if close else ""
    return f"no such {kind}{hint}; available: " + ", ".join(names)
