#!/usr/bin/python3
"""Compare runs of the gas models (docs/verification_gas.md, "3D"): a table of explosive work,
vented mass, gas in cracks, fracture degree and top-surface uplift, and a PNG with the top's
vertical velocity at the monitors, the deck pressures and the work over time.

    gas_models_3d.py DIR        DIR holds one run directory per model (cracks, cavity, literal)
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
import numpy as np  # noqa: E402
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from cdemblast.run import Run  # noqa: E402

MODELS = ("cracks", "cavity", "literal")


def deck_sum(run, column, t_end=None):
    """Sum over every hole and deck of a charges.csv column at its last sample."""
    total = 0.0
    for cols in run.charges.values():
        if column in cols and cols[column].size:
            for deck in np.unique(cols["deck"]):
                sel = cols["deck"] == deck
                total += float(cols[column][sel][-1])
    return total


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = argv[1]
    runs = {m: Run(os.path.join(root, m), m) for m in MODELS if os.path.isdir(os.path.join(root, m))}
    if not runs:
        print(f"{root}: no run directory of {', '.join(MODELS)}", file=sys.stderr)
        return 2
    print("| gas | explosive work (MJ) | vented (kg) | in cracks (kg) | fracture degree | "
          "peak top vz at r = 0.05 m (m/s) | max uplift (m) | energy error | loop time (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for m, r in runs.items():
        mon = r.monitors.get("r0.05", {})
        vz = float(np.max(mon["vz"])) if "vz" in mon and mon["vz"].size else float("nan")
        print(f"| {m} | {r.value('explosive_work') / 1e6:.3g} | {deck_sum(r, 'vented_mass'):.3g} | "
              f"{deck_sum(r, 'gas_mass_cracks'):.3g} | {r.value('fracture_degree'):.3f} | {vz:.3g} | "
              f"{r.value('max_up_displacement_m'):.3g} | {r.value('energy_error'):.1e} | "
              f"{r.value('loop_time_s'):.0f} |")
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    colors = {"cracks": "C3", "cavity": "C0", "literal": "C2"}
    for m, r in runs.items():
        c = colors[m]
        for name, ls in (("r0.05", "-"), ("r0.50", "--")):
            mon = r.monitors.get(name)
            if mon is not None and "vz" in mon:
                ax[0, 0].plot(1e3 * mon["time"], mon["vz"], ls, color=c, label=f"{m}, r = {name[1:]} m")
        for hole, ls in (("c1", "-"), ("e1", "--")):
            cols = r.charges.get(hole)
            if cols is not None:
                ax[0, 1].semilogy(1e3 * cols["time"], np.maximum(cols["pressure"], 1e3), ls, color=c,
                                  label=f"{m}, hole {hole}")
        if r.energy is not None and "explosive_work" in r.energy:
            ax[1, 0].plot(1e3 * r.energy["time"], r.energy["explosive_work"] / 1e6, color=c, label=m)
        if r.fracture is not None:
            ax[1, 1].plot(1e3 * r.fracture["time"], r.fracture["degree_area"], color=c, label=m)
    ax[0, 0].set(xlabel="time (ms)", ylabel="top vertical velocity v_z (m/s)",
                 title="top surface, monitors at r = 0.05 and 0.50 m")
    ax[0, 1].set(xlabel="time (ms)", ylabel="deck pressure (Pa)", title="gas pressure: cut hole c1, expansion hole e1")
    ax[1, 0].set(xlabel="time (ms)", ylabel="explosive work (MJ)", title="work of the products on the rock")
    ax[1, 1].set(xlabel="time (ms)", ylabel="fracture degree (area)", title="fracture degree")
    for a in ax.flat:
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle("SPEC 5.3 scheme A, coarse mesh (8 380 tets): the three gas models over 5 ms")
    fig.tight_layout()
    out = os.path.join(root, "gas_models_3d.png")
    fig.savefig(out, dpi=110)
    print(f"picture: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
