"""Field checks shared by the API and the TOML loader.

Each check raises :class:`gearmodal.errors.ModelError` naming the field, the value given and the
allowed range, e.g. ``stage1.sun.mass = -3.0: must be > 0 kg``.
"""

from __future__ import annotations

import math
from numbers import Real

from ..errors import ModelError


def _is_number(value) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def number(field: str, value, unit: str = "", *, minimum: float | None = None,
           strict: bool = False, maximum: float | None = None,
           max_strict: bool = False) -> float:
    """Return ``value`` as float after checking its type and range.

    ``strict`` makes the lower bound exclusive (``> minimum``), else inclusive (``>= minimum``).
    """
    if not _is_number(value):
        raise ModelError(field, f"expected a number{f' in {unit}' if unit else ''}, "
                                f"got {type(value).__name__} {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ModelError(field, f"= {v!r}: must be finite")
    u = f" {unit}" if unit else ""
    if minimum is not None and (v <= minimum if strict else v < minimum):
        op = ">" if strict else ">="
        raise ModelError(field, f"= {v!r}: must be {op} {minimum:g}{u}")
    if maximum is not None and (v >= maximum if max_strict else v > maximum):
        op = "<" if max_strict else "<="
        raise ModelError(field, f"= {v!r}: must be {op} {maximum:g}{u}")
    return v


#: The range of each kind of input the solvers are made for (a margin around the integrator's
#: stability map, benchmarks/stability_map.py: masses 0.1..1e5 kg, mesh stiffness 1e6..1e11
#: N/m, exact at every one of them). Outside it the double precision the eigen-solvers and the
#: exact method need runs out (a 1e-300 kg ring gives NaN modes, a 1e300 N s/m damper a
#: 1e119 Hz mode) or the input is a typo (teeth = 1e300). kind -> (low, high, unit) of |value|.
LIMITS = {
    "mass": (1e-6, 1e8, "kg"),
    "inertia": (1e-12, 1e10, "kg m^2"),
    "stiffness": (0.0, 1e16, "N/m or N m/rad"),
    "damping": (0.0, 1e10, "N s/m or N m s/rad"),
    "gap": (0.0, 0.1, "m or rad"),
    "length": (0.0, 1e3, "m"),
    "module": (1e-4, 1.0, "m"),
    "teeth": (3, 10_000, ""),
    "speed_rpm": (0.0, 1e5, "rpm"),
    "load": (0.0, 1e12, "N or N m"),
    "displacement": (0.0, 10.0, "m or rad"),
    "velocity": (0.0, 1e4, "m/s or rad/s"),
    "time": (1e-12, 1e6, "s"),
    # a load's frequency: above the highest mesh frequency the other limits allow (10 000
    # teeth at 1e5 rpm: 1.7e7 Hz); a 1e300 Hz wave is a typo, its phase has no digits left
    "frequency": (0.0, 1e8, "Hz"),
}


def plausible(field: str, value: float, kind: str) -> float:
    """``value`` unless ``|value|`` lies outside ``LIMITS[kind]`` (zero always allowed where
    the range starts at 0): :class:`ModelError` naming the field, the value and the range."""
    lo, hi, unit = LIMITS[kind]
    a = abs(value)
    if (a == 0.0 and lo == 0.0) or lo <= a <= hi:
        return value
    u = f" {unit}" if unit else ""
    raise ModelError(field, f"= {value!r}: outside the range gearmodal's solvers handle, "
                            f"|value| in [{lo:g}, {hi:g}]{u}")


def positive(field: str, value, unit: str = "") -> float:
    """A number > 0 (masses, inertias, modules, radii)."""
    return number(field, value, unit, minimum=0.0, strict=True)


def nonnegative(field: str, value, unit: str = "") -> float:
    """A number >= 0 (stiffness, damping, clearance, backlash)."""
    return number(field, value, unit, minimum=0.0)


#: the most planets a stage may have: wind-turbine gearboxes have 3 to 7, special designs up
#: to about 12; a larger number is a typo (10 000 planets allocated until memory ran out)
MAX_PLANETS = 32


def planets(field: str, value) -> int:
    """A planet count: an integer from 1 to :data:`MAX_PLANETS`."""
    n = integer(field, value, minimum=1)
    if n > MAX_PLANETS:
        raise ModelError(field, f"= {n}: at most {MAX_PLANETS} planets (wind-turbine gearboxes "
                         "have 3 to 7)")
    return n


def integer(field: str, value, *, minimum: int) -> int:
    """An integer >= ``minimum`` (tooth and planet counts)."""
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise ModelError(field, f"expected an integer, got {type(value).__name__} {value!r}")
    if value < minimum:
        raise ModelError(field, f"= {value}: must be an integer >= {minimum}")
    return int(value)


def angle(field: str, value, *, low: float, high: float, high_strict: bool = True) -> float:
    """An angle in radians in [low, high) with a hint when degrees were given by mistake."""
    v = number(field, value, "rad")
    if v < low or (v >= high if high_strict else v > high):
        hint = ""
        if v > high and math.radians(v) < high + 1e-12 and math.radians(v) >= low:
            hint = f" (angles are in radians; did you mean {math.radians(v):.6g} = radians({v:g})?)"
        rng = f"[{low:g}, {high:.6g}{')' if high_strict else ']'}"
        raise ModelError(field, f"= {v!r} rad: must lie in {rng} rad{hint}")
    return v


def choice(field: str, value, allowed) -> str:
    """One of a fixed set of strings."""
    if value not in allowed:
        raise ModelError(field, f"= {value!r}: must be one of {', '.join(map(repr, allowed))}")
    return value


def name(field: str, value) -> str:
    """A component name: non-empty, no dots (dots separate name parts in DOF names)."""
    if not isinstance(value, str) or not value or "." in value or value.strip() != value:
        raise ModelError(field, f"= {value!r}: must be a non-empty string without dots or "
                                "surrounding spaces")
    return value
