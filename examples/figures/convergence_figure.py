"""The README's mesh-convergence figures of the extreme case, from the runs' results files.

    python examples/figures/convergence_figure.py OUT.png 10=DIR 5=DIR 2.5=DIR
    python examples/figures/convergence_figure.py OUT.png "θ 0.05=DIR" "θ 0.0125=DIR" ...

A numeric label is a contact element size (mm); any other names the run as it stands.

OUT.png: clamp-force loss, worn area and stick area against real cycles at each contact
element size. OUT_joint_diagram.png beside it: the clamp force lost against the area-mean
wear depth (both bodies), with the joint diagram's line for uniform wear, h·k_b·k_m/(k_b+k_m)
summed over the screws, k_b from examples/counterweight.toml and k_m = F/approach of head and
thread under the pretension, read from each run's preload. DIR holds results.h5 (or
results.h5.part of a run stopped early). Units: cycles, per cent, µm, kN.
"""

import sys
import tomllib
from pathlib import Path

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt

SCENE = Path(__file__).resolve().parents[1] / "counterweight.toml"


def _name(label: str) -> str:
    """A size in mm, or the label as it is."""
    try:
        return f"{float(label):g} mm"
    except ValueError:
        return label


def _results(folder: Path) -> Path:
    """A run's results file: results.h5, or results.h5.part of a run stopped early."""
    path = folder / "results.h5"
    return path if path.exists() else folder / "results.h5.part"


def history(folder: Path) -> dict:
    """Real cycles and the per-cycle figures of a run (its wear blocks and the COF phase before)."""
    path = _results(folder)
    with h5py.File(path, "r", locking=False) as results:
        table = results["cycles"]
        clamp = table["figures/clamp_force_N"][()]
        return {"cycles": table["equivalent_cycles"][()], "loss": 100.0 * (1.0 - clamp / clamp[0]),
                "worn": 100.0 * table["figures/worn_area_fraction"][()],
                "stick": 100.0 * table["figures/stick_area_fraction"][()],
                "complete": path.name == "results.h5"}


def joint(folder: Path) -> dict:
    """Area-mean wear depth (mm) and clamp force lost (N) at the recorded cycles, and the joint
    diagram's stiffness (N/mm) from the preload: k_b·k_m/(k_b + k_m) summed over the screws."""
    path = _results(folder)
    bolts = tomllib.loads(SCENE.read_text())["bolts"]
    with h5py.File(path, "r", locking=False) as results:
        area = results["points/area"][()]
        recorded = results["cycles/fields/cycle"][()]
        wear = results["cycles/fields/wear_depth"][()].sum(axis=1) @ area / area.sum()
        cycles = results["cycles/cycle"][()]
        clamp = results["cycles/figures/clamp_force_N"][()]
        loss = clamp[0] - clamp[np.searchsorted(cycles, recorded)]
        increments = results["increments"]
        names = increments["control"].attrs["dofs"].split(",")
        order = increments["bolt_forces"].attrs["bolts"].split(",")
        locked = int((increments["phase"][()] == 0).sum()) // 2 - 1  # the last pretension step
        displacement = increments["control/displacement"][locked]
        stiffness = 0.0
        for k, name in enumerate(order):
            bolt = bolts[name]
            axis = np.asarray(bolt["axis"], dtype=float)
            at = {end: np.array([displacement[names.index(f"{bolt[end]}.u{c}")] for c in "xyz"])
                  for end in ("head", "nut")}
            approach = -float((at["nut"] - at["head"]) @ axis)
            members = increments["bolt_forces"][locked, k] / approach
            stiffness += bolt["stiffness"] * members / (bolt["stiffness"] + members)
    return {"wear": wear, "loss": loss, "stiffness": stiffness}


def joint_figure(out: Path, levels: list[tuple[str, Path]]) -> None:
    """Clamp force lost against area-mean wear, with each level's uniform-wear line."""
    figure, ax = plt.subplots(figsize=(6.5, 4.2))
    top = 0.0
    for size, folder in levels:
        run = joint(folder)
        line, = ax.plot(1e3 * run["wear"], 1e-3 * run["loss"], "o-", ms=2.5, lw=1.0,
                        label=f"{_name(size)}: run")
        top = max(top, float(run["wear"].max()))
        h = np.array([0.0, top])
        ax.plot(1e3 * h, 1e-3 * run["stiffness"] * h, "--", lw=0.9, color=line.get_color(),
                label=f"{_name(size)}: joint diagram, uniform wear ({run['stiffness']:.3g} N/mm)")
    ax.set_xlabel("area-mean wear depth, both bodies [µm]")
    ax.set_ylabel("clamp force lost [kN]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("counterweight_extreme (300 µm): clamp force lost to wear", fontsize=10)
    figure.tight_layout()
    figure.savefig(out, dpi=120)
    plt.close(figure)


def main(out: str, *levels: str) -> None:
    figure, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    for level in levels:
        size, folder = level.split("=", 1)
        run = history(Path(folder))
        label = _name(size) + ("" if run["complete"] else " (stopped early)")
        for ax, name in zip(axes, ("loss", "worn", "stick")):
            ax.plot(run["cycles"], run[name], label=label)
    axes[0].set_ylabel("clamp-force loss (%)")
    axes[1].set_ylabel("worn area (% of nominal)")
    axes[2].set_ylabel("stick area (% of nominal)")
    axes[2].set_xlabel("real load cycles (wing vibration)")
    axes[2].set_xscale("log")
    axes[2].set_xlim(left=100.0)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    sizes = all(_name(level.split("=", 1)[0]).endswith(" mm") for level in levels)
    figure.suptitle("counterweight_extreme (300 µm)" + (" at several contact element sizes" if sizes else ""),
                    fontsize=10)
    figure.tight_layout()
    figure.savefig(out, dpi=120)
    plt.close(figure)
    pairs = [(size, Path(folder)) for size, folder in (level.split("=", 1) for level in levels)]
    if all("dofs" in _control_attributes(folder) for _, folder in pairs):  # finished runs' files
        joint_figure(Path(out).with_name(Path(out).stem + "_joint_diagram.png"), pairs)


def _control_attributes(folder: Path) -> dict:
    with h5py.File(_results(folder), "r", locking=False) as results:
        return dict(results["increments/control"].attrs)


if __name__ == "__main__":
    main(*sys.argv[1:])
