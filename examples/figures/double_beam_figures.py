"""Draw the double-beam figures of examples/double_beam.md from two results files.

    .venv/bin/python examples/figures/double_beam_figures.py LOW/results.h5 HIGH/results.h5

Reads the results of ``fretwork run examples/double_beam_low_slip.toml`` and ``..._high_slip.toml``
(fields recorded at the last COF cycle, i.e. ``record_every`` divides ``cof_cycles``) and writes
next to this script, per scene (paper Figs. 8, 9, 11, 12, 13):

* ``double_beam_<case>_cof_phase.png``: stabilised COF, dissipation in the last COF cycle
  (the dissipation rate per cycle) and max utilised COF |τ|/p, maps after the COF phase;
* ``double_beam_<case>_wear.png``: contact pressure and wear depth maps at the end;
* ``double_beam_<case>_path.png``: pressure and slip range after the COF phase and at the end,
  and the wear depth, along the path y = 0 through the bolt hole and along the parallel line
  through the point of most dissipation (interpolated on the interface triangles);
* ``double_beam_<case>_cycles.png``: bolt force, stick / sliding / worn areas versus cycles.
"""

from __future__ import annotations

import sys
from pathlib import Path

import h5py
import matplotlib
import matplotlib.tri

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

HERE = Path(__file__).resolve().parent


def _mesh(file):
    coordinates = file["points/coordinates"][()]
    facets = file["points/facets"][()]
    triangles = np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]])
    return coordinates, matplotlib.tri.Triangulation(coordinates[:, 0], coordinates[:, 1], triangles)


def _last_cof_row(file) -> int:
    """Row of /cycles/fields that holds the last COF-phase cycle."""
    phases = file["cycles/phase"][()]
    last_cof = int(file["cycles/cycle"][()][np.flatnonzero(phases == 1)[-1]])
    rows = np.flatnonzero(file["cycles/fields/cycle"][()] == last_cof)
    if not rows.size:
        raise SystemExit(f"{file.filename}: cycle {last_cof} (last COF cycle) has no recorded fields; "
                         "choose record_every dividing cof_cycles")
    return int(rows[0])


def _map(ax, mesh, value, label, title, cmap="viridis", levels=None):
    # extend: values on or just beyond the top level (μ at μ_max) are drawn, not left blank
    mappable = ax.tricontourf(mesh, value, levels=levels if levels is not None else 24, cmap=cmap,
                              extend="both" if levels is not None else "neither")
    plt.colorbar(mappable, ax=ax, label=label, shrink=0.85)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm] (clamp ← → beam tips)")
    ax.set_ylabel("y [mm]")
    ax.set_title(title, fontsize=9)


def _along(mesh, values, x, y_line):
    """``values`` interpolated linearly on the interface triangles along y = y_line; NaN in the hole."""
    sampled = matplotlib.tri.LinearTriInterpolator(mesh, values)(x, np.full_like(x, y_line))
    return np.ma.filled(sampled.astype(float), np.nan)


def _slip_line(coordinates, dissipation):
    """y (> 0) of the point that dissipated most: a path through the middle of the slip zones."""
    upper = coordinates[:, 1] > 0.0
    return float(np.round(coordinates[upper, 1][np.argmax(dissipation[upper])], 1))


def _plot_line(ax, x, values, **style):
    ax.plot(x, values, "-", lw=1.4, **style)


def draw(path: Path, case: str) -> list[Path]:
    written = []
    with h5py.File(path, "r") as file:
        name = file.attrs["scene_name"]
        coordinates, mesh = _mesh(file)
        fields = file["cycles/fields"]
        row = _last_cof_row(file)
        cof_cycle = int(fields["cycle"][row])
        cof_max = float(np.max(fields["cof"][()]))

        fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
        _map(axes[0], mesh, fields["cof"][row], "COF μ [-]", f"stabilised COF after {cof_cycle} cycles",
             levels=np.linspace(0.2, max(0.7, cof_max), 26))
        _map(axes[1], mesh, fields["dissipation_in_cycle"][row], "dissipation in cycle [mJ/mm²]",
             f"frictional dissipation in cycle {cof_cycle}", cmap="inferno")
        _map(axes[2], mesh, fields["max_utilised_cof"][row], "max utilised COF |τ|/p [-]",
             f"max utilised COF in cycle {cof_cycle}", levels=np.linspace(0.0, 0.7, 29))
        fig.suptitle(f"{name}: end of the COF phase (paper Fig. 8)")
        fig.tight_layout()
        written.append(HERE / f"double_beam_{case}_cof_phase.png")
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)

        final = file["final"]
        wear = final["wear_depth"][()].sum(axis=0) * 1e3
        equivalent = float(file["cycles/equivalent_cycles"][-1])
        fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.6))
        _map(axes[0], mesh, final["pressure"][()], "contact pressure p [MPa]", "pressure at the end (load zero)",
             cmap="plasma")
        _map(axes[1], mesh, wear, "wear depth, both bodies [µm]", f"wear depth after {equivalent:.3g} cycles",
             cmap="cividis")
        fig.suptitle(f"{name}: after the wear phase (paper Fig. 11)")
        fig.tight_layout()
        written.append(HERE / f"double_beam_{case}_wear.png")
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)

        slip_y = _slip_line(coordinates, fields["dissipation_in_cycle"][row])
        fig, axes = plt.subplots(3, 2, figsize=(11, 7.2), sharex=True, sharey="row")
        x = np.linspace(coordinates[:, 0].min(), coordinates[:, 0].max(), 241)
        for column, y_line in enumerate((0.0, slip_y)):
            top, middle, bottom = axes[:, column]
            for values, target, label in (
                    (fields["pressure"][row], top, f"after COF phase (cycle {cof_cycle})"),
                    (final["pressure"][()], top, "end of wear phase"),
                    (fields["slip_range"][row] * 1e3, middle, f"cycle {cof_cycle}"),
                    (final["slip_range"][()] * 1e3, middle, "last cycle")):
                _plot_line(target, x, _along(mesh, values, x, y_line), label=label)
            _plot_line(bottom, x, _along(mesh, wear, x, y_line), color="C3")
            top.set_title("y = 0: through the bolt hole" if column == 0 else
                          f"y = {y_line:.3g} mm: through the slip zones beside the hole (most dissipation)", fontsize=9)
            bottom.set_xlabel("x [mm] (clamp ← → beam tips)")
            for ax in axes[:, column]:
                ax.grid(alpha=0.3)
        axes[0, 0].set_ylabel("pressure p [MPa]")
        axes[1, 0].set_ylabel("slip range in cycle [µm]")
        axes[2, 0].set_ylabel("wear depth [µm]")
        axes[0, 0].legend(fontsize=7)
        axes[1, 0].legend(fontsize=7)
        fig.suptitle(f"{name}: paths along the beam (paper Figs. 9 and 12)")
        fig.tight_layout()
        written.append(HERE / f"double_beam_{case}_path.png")
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)

        cycles = file["cycles"]
        figures = cycles["figures"]
        n = cycles["cycle"][()]
        phase = cycles["phase"][()]
        fig, axes = plt.subplots(2, 1, figsize=(7, 5.6), sharex=True)
        axes[0].plot(n, figures["clamp_force_N"][()] / 1e3, color="k")
        axes[0].set_ylabel("bolt force [kN]")
        for key, label in (("stick_area_fraction", "stick (status)"),
                           ("active_slip_area_fraction", "sliding (verdict measure)"),
                           ("slip_area_fraction", "slip (status, any slip)"),
                           ("worn_area_fraction", "worn")):
            if key in figures:
                axes[1].plot(n, figures[key][()], label=label)
        axes[1].set_ylabel("area / nominal area")
        axes[1].legend(fontsize=7)
        start = n[np.flatnonzero(phase == 2)[0]] - 0.5 if np.any(phase == 2) else None
        for ax in axes:
            ax.grid(alpha=0.3)
            if start is not None:
                ax.axvline(start, color="grey", ls="--", lw=0.8)
        jump = (equivalent - cof_cycle) / max(int(np.sum(phase == 2)), 1)
        axes[1].set_xlabel(f"simulated cycle (after the dashed line each stands for {jump:g} real cycles; "
                           f"{equivalent:.3g} in all)", fontsize=8)
        verdict = file["summary"].attrs["verdict"]
        fig.suptitle(f"{name}: bolt force and contact areas (paper Fig. 13)\nverdict: {verdict}", fontsize=11)
        fig.tight_layout()
        written.append(HERE / f"double_beam_{case}_cycles.png")
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)
    return written


def main(argv: list[str]) -> None:
    if len(argv) != 2:
        raise SystemExit(__doc__)
    for path, case in zip(argv, ("low_slip", "high_slip")):
        for target in draw(Path(path), case):
            print(target)


if __name__ == "__main__":
    main(sys.argv[1:])
