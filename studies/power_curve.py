"""The power curve of a turbine of today: the NREL 5 MW reference turbine (its OpenFAST deck, read
by openfast-io) run by NREL's ROSCO controller (the compiled libdiscon.so with the shipped
DISCON.IN) in steady uniform wind at every whole m/s from cut-in (3) to cut-out (25).

Each case is :func:`gearmodal.turbine.nrel5mw.controlled_run`: the BEM rotor on the 5 MW blade,
the drivetrain (rotor, ElastoDyn's drivetrain spring and damper, generator) advanced by the
stepping API, ROSCO setting the generator torque and the collective pitch at its sample time;
the settled values are the means over the last 10 s. Written: ``power_curve.csv`` (columns
``wind_speed_mps, rotor_speed_rpm, pitch_deg, power_kW, tsr, cp``, also as ``summary.csv``),
``power_curve.png`` against NREL's Cp table's optimum, ``report.html``; the cases go to
``store/`` as they finish (a rerun resumes). Run: ``gearmodal study power-curve nrel5mw --out
runs/power_curve``.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import gearmodal as gm  # noqa: E402
from gearmodal.report import write_study_report  # noqa: E402
from gearmodal.turbine import nrel5mw  # noqa: E402

WINDS = list(range(3, 26))  # m/s: cut-in to cut-out
COLUMNS = ["wind_speed_mps", "rotor_speed_rpm", "pitch_deg", "power_kW", "tsr", "cp"]
TURBINES = ("nrel5mw",)


def _case(wind_speed, t_end):
    return nrel5mw.controlled_run(float(wind_speed), t_end)


def _row(result: dict) -> dict:
    return dict(result)


def figure(curve: pd.DataFrame, cp_opt: float):
    fig, (a, b) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5))
    a.plot(curve.wind_speed_mps, curve.power_kW, "o-")
    a.axhline(5000.0, color="grey", lw=0.8, ls="--")
    a.set_ylabel("electrical power [kW]")
    b.plot(curve.wind_speed_mps, curve.cp, "o-", label="settled Cp")
    b.axhline(cp_opt, color="C1", ls="--", label=f"NREL's Cp table, optimum {cp_opt:.3f}")
    b.set_ylabel("power coefficient")
    b.set_xlabel("wind speed [m/s]")
    b.legend()
    fig.tight_layout()
    return fig


def run(out, *, turbine: str = "nrel5mw", duration: float | None = None,
        max_workers: int | None = None, progress: bool = True) -> pd.DataFrame:
    """The power curve of ``turbine`` (``"nrel5mw"``), each case ``duration`` s (default 90:
    the controller settles in under a minute); returns the table (module docstring)."""
    if turbine not in TURBINES:
        raise gm.ModelError("turbine", f"= {turbine!r}: one of {', '.join(TURBINES)}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t_end = 90.0 if duration is None else float(duration)
    table = gm.sweep(functools.partial(_case, t_end=t_end), {"wind_speed": WINDS},
                     store=out / "store", metrics=_row, max_workers=max_workers,
                     progress=progress)
    curve = table[COLUMNS].sort_values("wind_speed_mps").reset_index(drop=True)
    curve.to_csv(out / "power_curve.csv", index=False)
    curve.to_csv(out / "summary.csv", index=False)
    pitch, tsr, cp = nrel5mw.cp_table()
    i, j = np.unravel_index(cp.argmax(), cp.shape)
    deck = nrel5mw.read_deck()
    tb, table_wind = nrel5mw.table_conditions(deck)  # the turbine and wind of the table
    alpha = table_wind.shear_exponent
    ours = tb.power_coefficient(table_wind, tsr[i] * 11.4 / deck.tip_radius, pitch[j])[0]
    above = curve[curve.wind_speed_mps >= 16]
    write_study_report(out, "NREL 5 MW power curve with ROSCO", [
        f"The NREL 5 MW turbine from its OpenFAST deck, NREL's ROSCO controller in the loop, "
        f"steady uniform wind, {t_end:g} s per wind speed (means over the last 10 s). NREL's "
        f"Cp table peaks at {cp.max():.3f} (tip-speed ratio {tsr[i]:g}, pitch "
        f"{np.degrees(pitch[j]):g} deg); gearmodal's BEM on the same blade, coned and "
        f"tilted as the deck, gives {ours:.3f} there in the table's wind (shear {alpha:g}; "
        "docs/guide/turbine.md). Above rated the controller holds "
        f"{above.rotor_speed_rpm.mean():.2f} rpm and {above.power_kW.mean():.0f} kW.",
        curve.round(4), ("power_curve.png", figure(curve, float(cp.max())))])
    return curve


if __name__ == "__main__":
    print(run(sys.argv[1] if len(sys.argv) > 1 else "runs/power_curve"))
