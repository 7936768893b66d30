"""Views without reference counts (gearmodal/integrate/borrow.py): the same data as their
arrays, through bundles too; the kernel that uses them gives the same runs (the rest of the
suite: every exact run goes through it)."""

from collections import namedtuple

import numba
import numpy as np

from gearmodal.integrate.borrow import alive, borrowed

Pair = namedtuple("Pair", ["a", "b", "x"])


@numba.njit(cache=False)
def _write_through(n):
    a = np.zeros(n)
    b = np.arange(n * 2.0).reshape((n, 2))
    owners = (Pair(a, b, 2.5), np.ones(3))
    (p, c) = borrowed(owners)
    for i in range(n):
        p.a[i] = p.x * i  # written through the view
        p.b[i, 1] = -1.0
    s = c[0] + c[2] + p.b[1:, 0].sum()  # a slice of a view reads the array's data
    alive(owners)
    return owners[0].a.copy(), owners[0].b.copy(), s


def test_a_borrowed_view_is_its_array():
    a, b, s = _write_through(5)
    np.testing.assert_array_equal(a, 2.5 * np.arange(5))
    np.testing.assert_array_equal(b[:, 1], -1.0)
    np.testing.assert_array_equal(b[:, 0], 2.0 * np.arange(5))
    assert s == 2.0 + (2.0 + 4.0 + 6.0 + 8.0)


@numba.njit(cache=False)
def _with_a_list(n):
    owners = (np.zeros(2), [1.0] * n, "gear")
    arr, values, name = borrowed(owners)  # the list and the string keep their references
    arr[0] = values[n - 1] + len(name)
    alive(owners)
    return owners[0][0], sum(owners[1])


def test_what_is_not_an_array_is_passed_on_counted():
    """A bundle member numba counts references on that is not an array (a list, a string)
    comes back as itself with its reference taken (without it, one decref too many freed the
    list twice: the heap's check aborted)."""
    assert _with_a_list(50) == (5.0, 50.0)


def test_a_kernel_elsewhere_uses_alive_after_a_test_bundle(tmp_path):
    """``alive`` is generic: called above with this module's ``Pair``, a cached index of it
    would hold that type, and a process that cannot import this module (a user's script, a
    benchmark) failed to load it ("No module named 'test_borrow'") when it compiled a kernel.
    It is not cached."""
    import subprocess
    import sys

    code = ("import numba, numpy as np\n"
            "from gearmodal.integrate.borrow import alive, borrowed\n"
            "@numba.njit\n"
            "def f(a):\n"
            "    b = borrowed(a)\n"
            "    t = b.sum()\n"
            "    alive(a)\n"
            "    return t\n"
            "print(f(np.ones(3)))\n")
    _write_through(2)  # alive compiled with Pair in this process
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-400:]
    assert r.stdout.strip() == "3.0"
