"""``python -m symbolic [OUTDIR]``: regenerate the numba kernels (default gearmodal/kernels)."""

from __future__ import annotations

import sys
import time

from . import KERNEL_DIR, generate


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    outdir = args[0] if args else KERNEL_DIR
    start = time.perf_counter()
    for path in generate(outdir):
        print(f"wrote {path}")
    print(f"generated in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
