"""Errors raised by gearmodal.

Every input error names the offending field, the value given and what is allowed, so that the
CLI can print it without a traceback (``gearmodal`` exits with status 2 on a ``ModelError``).
"""

from __future__ import annotations


class ModelError(ValueError):
    """Invalid model input: the message names the field, the value and the allowed range."""

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


def unknown(kind: str, name: str, names) -> str:
    """The message for a name that is not there: ``no such <kind>``, the closest names
    (``did you mean ...?``, by :func:`difflib.get_close_matches`) and the names there are."""
    import difflib

    names = [str(n) for n in names]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.6)
    hint = f" (did you mean {', '.join(map(repr, close))}?)" if close else ""
    return f"no such {kind}{hint}; available: " + ", ".join(names)
