"""The README's mesh-convergence figure of the extreme case: clamp-force loss, worn area and
stick area against real cycles at each contact element size, from the runs' results files.

    python examples/figures/convergence_figure.py OUT.png 10=DIR 5=DIR 2.5=DIR

DIR holds results.h5 (or results.h5.part of a run stopped early). Units: cycles, per cent.
"""

import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def history(folder: Path) -> dict:
    """Real cycles and the per-cycle figures of a run (its wear blocks and the COF phase before)."""
    path = folder / "results.h5"
    if not path.exists():
        path = folder / "results.h5.part"
    with h5py.File(path, "r", locking=False) as results:
        table = results["cycles"]
        clamp = table["figures/clamp_force_N"][()]
        return {"cycles": table["equivalent_cycles"][()], "loss": 100.0 * (1.0 - clamp / clamp[0]),
                "worn": 100.0 * table["figures/worn_area_fraction"][()],
                "stick": 100.0 * table["figures/stick_area_fraction"][()],
                "complete": path.name == "results.h5"}


def main(out: str, *levels: str) -> None:
    figure, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    for level in levels:
        size, folder = level.split("=", 1)
        run = history(Path(folder))
        label = f"{size} mm" + ("" if run["complete"] else " (stopped early)")
        for ax, name in zip(axes, ("loss", "worn", "stick")):
            ax.plot(run["cycles"], run[name], label=label)
    axes[0].set_ylabel("clamp-force loss (%)")
    axes[1].set_ylabel("worn area (% of nominal)")
    axes[2].set_ylabel("stick area (% of nominal)")
    axes[2].set_xlabel("real load cycles (wing vibration, 337 Hz)")
    axes[2].set_xscale("log")
    axes[2].set_xlim(left=100.0)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.suptitle("counterweight_extreme (300 µm) at three contact element sizes", fontsize=10)
    figure.tight_layout()
    figure.savefig(out, dpi=120)
    plt.close(figure)


if __name__ == "__main__":
    main(*sys.argv[1:])
