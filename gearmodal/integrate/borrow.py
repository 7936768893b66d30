"""Views without a reference count, for the exact kernel's per-piece helpers.

numba takes and drops an atomic reference on every array a compiled function binds (its
arguments, a bundle's members, a slice) unless its reference pruning removes the pair, and in
:func:`gearmodal.integrate.taylor.taylor_run`'s per-piece helpers it mostly does not: about
1 200 ``lock``-prefixed increments and decrements per piece of the 600 kW turbine's gearbox
(counted with ``gdb``, development guide). :func:`borrowed` returns an array, or a bundle (a
tuple, named or not, of arrays, bundles and numbers), whose arrays have no meminfo: numba's
``NRT_incref``/``NRT_decref`` return at once on them.

A borrowed view does not keep its array alive. numba frees a local array after the last
statement that names it, so a kernel that borrows must name the owners at every exit
(:func:`alive`) and never return or store a borrowed view.
"""

from __future__ import annotations

import numba
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array

__all__ = ["borrowed", "alive"]


def _borrow(context, builder, ty, val):
    """``val`` of type ``ty`` as a new reference (numba's rule for an intrinsic's result) whose
    arrays own nothing."""
    if isinstance(ty, types.Array):
        out = make_array(ty)(context, builder, val)  # every field of the array, then
        out.meminfo = cgutils.get_null_value(out.meminfo.type)  # no owner to count
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()
    if isinstance(ty, types.BaseTuple):
        for i, member in enumerate(ty.types):
            part = _borrow(context, builder, member, builder.extract_value(val, i))
            val = builder.insert_value(val, part, i)
        return val
    # anything else (a number: nothing; a list, a string: its reference) as it is, counted
    context.nrt.incref(builder, ty, val)
    return val


@intrinsic
def borrowed(typingctx, x):
    """``x`` (an array or a bundle of them) with every array's meminfo and parent cleared."""

    def codegen(context, builder, sig, args):
        return _borrow(context, builder, sig.args[0], args[0])

    return x(x), codegen


@numba.njit(inline="never")
def alive(owners) -> None:
    """Names ``owners`` (the arrays or bundles borrowed from) where a kernel returns, so that
    numba keeps them until then. (Not cached: a cached index of this generic function would
    hold every type it was called with, a test module's too, and fail to load where that
    module is not importable; the kernels calling it are cached with it compiled in.)"""
    return None
