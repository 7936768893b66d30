"""Print SymPy expressions as numba kernels (DESIGN 4).

Every kernel is a ``@numba.njit(cache=True)`` function of float scalars and, for the
displacement vectors of a body, 1-D float64 arrays of length 6. The outputs are either a
scalar or float64 arrays allocated with ``np.zeros`` of which only the nonzero entries are
assigned. All outputs of one kernel share one common-subexpression elimination
(``sympy.cse``), printed with SymPy's Python code printer (``math.`` functions, which
numba compiles natively).

The printed text depends only on the expressions and the SymPy version (pinned in the
``dev`` extra): no timestamps, no set/dict iteration over unordered containers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

INDENT = "    "


@dataclass(frozen=True)
class ScalarArg:
    """A float scalar argument; ``symbol`` is the SymPy symbol it binds."""

    symbol: sp.Symbol
    doc: str = ""

    @property
    def name(self) -> str:
        return self.symbol.name


@dataclass(frozen=True)
class VectorArg:
    """A 1-D float64 array argument, unpacked element by element into ``symbols``."""

    name: str
    symbols: tuple[sp.Symbol, ...]
    doc: str = ""


Arg = ScalarArg | VectorArg
Output = sp.Expr | sp.MatrixBase


@dataclass
class Kernel:
    """One generated function: ``name(args) -> outputs`` (a tuple if several outputs)."""

    name: str
    args: Sequence[Arg]
    outputs: Sequence[Output]
    doc: str
    output_names: Sequence[str] = field(default_factory=list)


class _Printer(PythonCodePrinter):
    """Python printer with ``math.`` prefixes and plain float literals."""

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})

    def _print_Rational(self, expr: sp.Rational) -> str:
        # Print 1/2 as a float literal (0.5): exact for the small dyadic rationals we meet,
        # and avoids integer/float promotion questions inside numba.
        value = float(expr)
        if sp.Rational(value) == expr:
            return repr(value)
        return f"({expr.p}/{expr.q})"

    def _print_Half(self, expr: sp.Rational) -> str:
        return self._print_Rational(expr)


def _check_symbols(kernel: Kernel) -> None:
    """Fail early if an output uses a symbol that no argument binds."""
    bound: set[sp.Symbol] = set()
    for arg in kernel.args:
        if isinstance(arg, ScalarArg):
            bound.add(arg.symbol)
        else:
            bound.update(arg.symbols)
    for out in kernel.outputs:
        free = sp.sympify(out).free_symbols - bound
        if free:
            names = sorted(s.name for s in free)
            raise ValueError(f"{kernel.name}: unbound symbols {names}")


def _entries(out: Output) -> list[tuple[tuple[int, ...], sp.Expr]]:
    """Nonzero entries of an output with their numpy index, in row-major order."""
    if isinstance(out, sp.MatrixBase):
        rows, cols = out.shape
        vector = cols == 1
        items = []
        for i in range(rows):
            for j in range(cols):
                e = out[i, j]
                if e != 0:
                    items.append(((i,) if vector else (i, j), e))
        return items
    return [((), sp.sympify(out))]


def _shape(out: Output) -> tuple[int, ...] | None:
    if isinstance(out, sp.MatrixBase):
        rows, cols = out.shape
        return (rows,) if cols == 1 else (rows, cols)
    return None


def print_kernel(kernel: Kernel) -> str:
    """Return the Python source of one kernel."""
    _check_symbols(kernel)
    printer = _Printer()
    flat: list[sp.Expr] = []
    layout: list[list[tuple[int, ...]]] = []
    for out in kernel.outputs:
        entries = _entries(out)
        layout.append([idx for idx, _ in entries])
        flat.extend(e for _, e in entries)

    reserved = {a.name for a in kernel.args}
    for arg in kernel.args:
        if isinstance(arg, VectorArg):
            reserved.update(s.name for s in arg.symbols)
    prefix = "x"
    while any(n.startswith(prefix) and n[len(prefix) :].isdigit() for n in reserved):
        prefix = "_" + prefix
    replacements, reduced = sp.cse(flat, symbols=sp.numbered_symbols(prefix), order="canonical")

    lines = ["@numba.njit(cache=True)"]
    lines.append(f"def {kernel.name}({', '.join(a.name for a in kernel.args)}):")
    doc_lines = kernel.doc.strip("\n").splitlines()
    arg_lines = [f"{a.name}: {a.doc}" for a in kernel.args if a.doc]
    lines.append(f'{INDENT}"""{doc_lines[0]}')
    for dl in doc_lines[1:]:
        lines.append(f"{INDENT}{dl}".rstrip())
    if arg_lines:
        lines.append("")
        lines.append(f"{INDENT}Arguments:")
        for al in arg_lines:
            lines.append(f"{INDENT}    {al}")
    lines.append(f'{INDENT}"""')

    for arg in kernel.args:
        if isinstance(arg, VectorArg):
            for k, s in enumerate(arg.symbols):
                lines.append(f"{INDENT}{s.name} = {arg.name}[{k}]")
    for sym, expr in replacements:
        lines.append(f"{INDENT}{sym.name} = {printer.doprint(expr)}")

    names = list(kernel.output_names) or [
        "out" if len(kernel.outputs) == 1 else f"out{k}" for k in range(len(kernel.outputs))
    ]
    pos = 0
    results = []
    for out, idxs, name in zip(kernel.outputs, layout, names, strict=True):
        shape = _shape(out)
        if shape is None:
            lines.append(f"{INDENT}{name} = {printer.doprint(reduced[pos])}")
            pos += 1
        else:
            lines.append(f"{INDENT}{name} = np.zeros({shape!r})")
            for idx in idxs:
                index = ", ".join(str(i) for i in idx)
                lines.append(f"{INDENT}{name}[{index}] = {printer.doprint(reduced[pos])}")
                pos += 1
        results.append(name)
    lines.append(f"{INDENT}return {', '.join(results)}")
    return "\n".join(lines) + "\n"


def print_module(source: str, description: str, kernels: Sequence[Kernel]) -> str:
    """Return the text of a generated module: header, imports and all kernels."""
    header = [
        f"# GENERATED by 'python -m symbolic' from symbolic/{source}.py -- do not edit by hand.",
        f"# {description}",
        "# ruff: noqa",
        "",
        "import math",
        "",
        "import numba",
        "import numpy as np",
        "",
        "__all__ = [" + ", ".join(repr(k.name) for k in kernels) + "]",
    ]
    body = ["\n".join(header) + "\n"]
    body.extend(print_kernel(k) for k in kernels)
    return "\n\n".join(body)
