"""What the reference methods' energy audit costs (gearmodal/integrate/energy.py).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/energy_audit.py [--rounds 3]

Runs the shipped double-contact scene (0.1 s) with Newmark at 2.5e-5 s and scipy RK45 at
``rtol`` 1e-8, each with the audit and with it replaced by a no-op, in alternation, ``--rounds``
times, and prints the minimum process CPU of each and the ratio audited / unaudited (the
audit's share). Both runs finish (neither is stopped), so they do the same work but the audit.
"""

from __future__ import annotations

import argparse
import time

import gearmodal.integrate.energy as energy
import gearmodal.integrate.newmark as newmark
import gearmodal.integrate.scipy_ref as scipy_ref
from gearmodal.scene import load_scene, settings

SCENE = "studies/scenes/planetary_double_contact.toml"


class _Silent(energy.EnergyAudit):
    """An audit that keeps nothing: the run without its cost."""

    def step(self, *args, **kwargs):  # noqa: D102
        return None


def _run(setting: list[str], audited: bool) -> float:
    real_of, real_rows = energy.EnergyAudit.__dict__["of"], scipy_ref.audit_rows
    if not audited:  # newmark.EnergyAudit is energy.EnergyAudit: its `of` hands out silence
        newmark.EnergyAudit.of = classmethod(lambda cls, st, m, h: _Silent(
            st.system, st.x0, st.azimuth0, m, h))
        scipy_ref.audit_rows = lambda *a, **k: None
    try:
        sc = load_scene(SCENE, overrides=settings(["t_end=0.1", *setting]))
        t0 = time.process_time()
        sc.simulate()
        return time.process_time() - t0
    finally:
        energy.EnergyAudit.of = real_of
        scipy_ref.audit_rows = real_rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    cases = {"newmark dt 2.5e-5 s": ["method=newmark", "dt=2.5e-5"],
             "scipy RK45 rtol 1e-8": ["method=scipy", "options.rtol=1e-8"]}
    for name, setting in cases.items():
        _run(setting, True)  # compile and warm
        best = {True: float("inf"), False: float("inf")}
        for _ in range(args.rounds):
            for audited in (True, False):
                best[audited] = min(best[audited], _run(setting, audited))
        print(f"{name}: audited {best[True]:.3f} s, unaudited {best[False]:.3f} s, "
              f"ratio {best[True] / best[False]:.3f}")


if __name__ == "__main__":
    main()
