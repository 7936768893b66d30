"""Planet load sharing against torque: K_gamma with pinhole errors, gravity and the carrier
bearing's clearance (issue 21; NREL's GRC finding that load sharing is the combined effect of
gravity, bending moment, carrier-bearing clearance and torque).

The 600 kW planetary stage (studies/models/planetary_clearance.toml, three planets, a floating
sun on 1e7 N/m) in static equilibrium at every ``step_deg`` of carrier azimuth, for input
torques from 10 to 120 % of rated, each combination of:

- carrier bearing ``reference`` (1e9 N/m, no clearance) or ``clearance`` (1e8 N/m, 1 mm per
  axis, the paper's fault);
- gravity ``on`` (every body's weight and the rotor's weight at the shaft end, the front main
  bearing the pivot) or ``off``;
- a tangential pinhole position error on planet 1 of 0, 10, 25 or 50 um (tight to loose
  carrier tolerances).

Per case: K_gamma of the sun-planet and ring-planet meshes (the largest over the revolution;
:mod:`gearmodal.sharing`), the planet-bearing peak and the share of the revolution with double
contact. Run: ``gearmodal study load-sharing --out runs/load_sharing``. Writes cases.csv (every
azimuth), summary.csv, k_gamma.png and report.html.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import gearmodal as gm
from gearmodal.report import write_study_report
from gearmodal.sharing import ABS_K_GAMMA, k_gamma
from gearmodal.turbine import load_turbine

HERE = Path(__file__).resolve().parent
MODEL = HERE / "models" / "planetary_clearance.toml"
TURBINE = HERE / "turbines" / "600kw_turbine.toml"
TORQUE = 2.6e5  # N m: 600 kW at 22 rpm
FRACTIONS = tuple(round(0.1 * k, 1) for k in range(1, 13))  # 10 ... 120 % of rated
PIN_ERRORS_UM = (0.0, 10.0, 25.0, 50.0)
#: carrier bearing per case: the reference's, or (None) the model file's own clearance fault
BEARINGS = {"reference": 1.0e9, "clearance": None}


def model(bearing: str, pin_error_um: float) -> gm.Model:
    """The stage with ``bearing`` and a tangential pinhole error on planet 1."""
    over = {"planetary_stage.pin_errors": [[0.0, pin_error_um * 1e-6], [0.0, 0.0], [0.0, 0.0]]}
    if BEARINGS[bearing] is not None:
        over["planetary_stage.carrier_bearing"] = BEARINGS[bearing]
    return gm.load(MODEL, overrides=over)


def loads(gravity: bool) -> dict:
    """Gravity on every body and the rotor's weight at the shaft end (up at the gearbox: the
    front main bearing is the pivot), or nothing."""
    if not gravity:
        return {}
    tb = load_turbine(TURBINE)
    shaft_end = tb.rotor.mass * gm.G_STANDARD * tb.front_bearing / (
        tb.rear_bearing - tb.front_bearing)
    return {"gravity": gm.G_STANDARD, "carrier.force_y": shaft_end}


def revolution(m: gm.Model, base: dict, torque: float, azimuths_deg) -> pd.DataFrame:
    """Equilibrium at each carrier azimuth: K_gamma per mesh kind, the planet-bearing peak
    and double contact; one row per azimuth."""
    f = gm.balance(m, {**base, "carrier.torque": torque}, on="sun.torque")
    planets = m.groups["planets"]
    rows = []
    for az in azimuths_deg:
        asm = m.assemble(math.radians(az))
        eq = gm.equilibrium(asm, f)
        c = eq.contacts.set_index(["element", "contact"]).force_N
        sp = asm.springs
        force = sp.stiffness * (sp.W @ eq.q.to_numpy())
        el, ct = np.array(sp.element), np.array(sp.contact)
        bearing = max(math.hypot(force[(el == f"{p}_bearing") & (ct == "x")].sum(),
                                 force[(el == f"{p}_bearing") & (ct == "y")].sum())
                      for p in planets)
        row = {"azimuth_deg": float(az), "planet_bearing_max_N": bearing}
        double = False
        for kind in ("sun", "ring"):
            front = np.array([c.get((f"{kind}_{p}", "front"), 0.0) for p in planets])
            back = np.array([c.get((f"{kind}_{p}", "back"), 0.0) for p in planets])
            row[f"k_gamma_{kind}"] = k_gamma(front - back)
            double |= bool(((front > 0) & (back > 0)).any())
        row["double_contact"] = double
        rows.append(row)
    return pd.DataFrame(rows)


def figure(summary: pd.DataFrame):
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 2, sharex=True, sharey=True, figsize=(10, 6.5))
    for i, bearing in enumerate(BEARINGS):
        for j, gravity in enumerate(("off", "on")):
            ax = axs[i, j]
            d = summary[(summary.bearing == bearing) & (summary.gravity == gravity)]
            for k, (err, g) in enumerate(d.groupby("pin_error_um")):
                ax.plot(100 * g.torque_fraction, g.k_gamma_sun, marker="o", ms=3,
                        color=f"C{k}", label=f"{err:g} um")
            ax.axhline(ABS_K_GAMMA[3], color="0.5", ls=":", lw=1)
            ax.set_title(f"carrier bearing: {bearing}; gravity {gravity}", fontsize=9)
            ax.grid(alpha=0.3)
    for ax in axs[-1]:
        ax.set_xlabel("input torque [% of rated]")
    for ax in axs[:, 0]:
        ax.set_ylabel("K_gamma, sun-planet")
    axs[0, 0].legend(title="pinhole error, planet 1", fontsize=8)
    fig.tight_layout()
    return fig


def run(out, *, step_deg: float = 15.0, progress: bool = True) -> pd.DataFrame:
    """Every case over one revolution (every ``step_deg``); writes cases.csv, summary.csv,
    k_gamma.png and report.html. Returns the summary (one row per case)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    az = np.arange(0.0, 360.0, step_deg)
    grid = [(b, g, e) for b in BEARINGS for g in (False, True) for e in PIN_ERRORS_UM]
    parts = []
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(grid) * len(FRACTIONS), desc="load sharing", unit="case")
    for bearing, gravity, err in grid:
        m, base = model(bearing, err), loads(gravity)
        for frac in FRACTIONS:
            parts.append(revolution(m, base, frac * TORQUE, az).assign(
                bearing=bearing, gravity="on" if gravity else "off", pin_error_um=err,
                torque_fraction=frac, torque_Nm=frac * TORQUE))
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    table = pd.concat(parts, ignore_index=True)
    table.to_csv(out / "cases.csv", index=False)
    keys = ["bearing", "gravity", "pin_error_um", "torque_fraction", "torque_Nm"]
    summary = table.groupby(keys, sort=False).agg(
        k_gamma_sun=("k_gamma_sun", "max"), k_gamma_ring=("k_gamma_ring", "max"),
        planet_bearing_peak_N=("planet_bearing_max_N", "max"),
        double_contact_fraction=("double_contact", "mean")).reset_index()
    summary.to_csv(out / "summary.csv", index=False)
    rated = summary[summary.torque_fraction == 1.0].set_index(
        ["bearing", "gravity", "pin_error_um"])[["k_gamma_sun", "k_gamma_ring",
                                                 "planet_bearing_peak_N",
                                                 "double_contact_fraction"]]
    write_study_report(out, "Planet load sharing against torque (K_gamma)", [
        "Static equilibrium of the 600 kW planetary stage (three planets, floating sun) at "
        f"every {step_deg:g} deg of carrier azimuth, for torques from 10 to 120 % of rated "
        f"({TORQUE:.3g} N m), with a tangential pinhole error on planet 1, gravity (every "
        "body's weight and the rotor's weight at the shaft end) on or off, and the reference "
        "or the clearance carrier bearing. K_gamma is the largest planet's mesh load over "
        "the mean, the largest over the revolution (gearmodal.sharing); ABS tabulates 1.0 "
        "for three planets (dotted).",
        "At rated torque:", rated,
        ("k_gamma.png", figure(summary))])
    return summary


if __name__ == "__main__":
    print(run(sys.argv[1] if len(sys.argv) > 1 else "runs/load_sharing"))
