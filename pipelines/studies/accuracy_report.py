"""The accuracy study for the engineer: the Pareto plot of error versus CPU time and the table."""

from __future__ import annotations

from pathlib import Path

from pipelines.studies.knobs import COST, QUANTITIES, SCALAR_QUANTITIES, Study, TOLERANCE, pareto_front


SHORT_NAMES = {"max_wear_depth_mm": "wear", "cof_map": "COF map", "slip_area_fraction": "slip area",
               "clamp_force_loss_fraction": "clamp loss", "wing_amplitude_mm": "wing amplitude"}


def plot_pareto(study: dict, path: str | Path) -> Path:
    """Worst decision-quantity error (%) versus cost (CPU time, s), one labelled point per run (PNG).

    ``study`` is :meth:`Study.to_dict` (or its JSON file read back); each label names the run's
    settings that differ from the reference and, in brackets, its worst quantity.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(10, 7))
    finished = [r for r in study["records"] if r["failure"] is None]
    front = {id(r) for r in pareto_front(finished)}
    notes = _plot_runs(ax, finished, front)
    rec = study["recommendation"]
    _plot_front_and_axes(ax, finished, front, rec)
    ax.set_title(_pareto_title(study), fontsize=9)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.grid(True, which="both", alpha=0.3)
    if rec:
        notes.append(f"recommended: {rec['label']}")
    fig.text(0.01, 0.01, "\n".join(notes), fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.02 + 0.025 * len(notes), 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _plot_runs(ax, finished: list[dict], front: set[int]) -> list[str]:
    """One labelled point per finished run; returns the notes that spell out numbered labels."""
    notes = []  # combinations carry long labels: numbered on the plot, spelled out below it
    for record in finished:
        error = 100 * record["worst_error"]
        marker = "o" if record["verdict_agrees"] else "x"
        colour = "tab:green" if record["within_tolerance"] else "tab:red"
        ax.scatter(record[COST], error, marker=marker, color=colour, s=40 if id(record) in front else 20,
                   zorder=3)
        worst = max(record["errors"], key=record["errors"].get, default=None)
        label = record["label"]
        if label.startswith("combined"):
            notes.append(f"C{len(notes) + 1} = {label}")
            label = f"C{len(notes)}"
        label += f" [{SHORT_NAMES[worst]}]" if worst and record["worst_error"] > 0 else ""
        ax.annotate(label, (record[COST], error), fontsize=7, xytext=(4, 3 + 9 * (label[0] == "C") * len(notes)),
                    textcoords="offset points")
    return notes


def _plot_front_and_axes(ax, finished: list[dict], front: set[int], rec: dict | None) -> None:
    """The Pareto front line, the recommended run, the tolerance line, the scales and axis labels."""
    line = sorted((r[COST], 100 * r["worst_error"]) for r in finished if id(r) in front)
    if line:
        ax.plot(*zip(*line), color="0.6", lw=1, zorder=2, label="Pareto front")
    if rec:
        ax.scatter(rec[COST], 100 * rec["worst_error"], s=180, facecolors="none", edgecolors="k",
                   zorder=4, label="recommended")
    ax.axhline(100 * TOLERANCE, color="k", ls="--", lw=0.8, label=f"{100 * TOLERANCE:g} % tolerance")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_ylim(bottom=0.0, top=3 * max([100 * r["worst_error"] for r in finished] + [100 * TOLERANCE]))
    ax.set_xlabel("CPU time of the run (build and solve, one BLAS thread) [s]")
    ax.set_ylabel("worst decision-quantity error [%]  (x: verdict differs)")


def _pareto_title(study: dict) -> str:
    """Scene, reference settings, overrides common to all runs, and the runs that did not converge."""
    reference = study["reference"]["settings"]
    title = (f"accuracy vs time: {study['scene']}\nreference: "
             + ", ".join(f"{k}={v:g}" for k, v in reference.items()))
    if study["base_overrides"]:
        title += "\nall runs: " + ", ".join(f"{k}={v}" for k, v in study["base_overrides"].items())
    failed = [r["label"] for r in study["records"] if r["failure"]]
    if failed:
        title += f"\nnot converged: {'; '.join(failed)}"
    return title


def table_lines(study: Study) -> list[str]:
    """The study as text: one line per run, then the recommendation."""
    names = [q for q in QUANTITIES if any(q in r["errors"] for r in study.records)]
    ref = study.reference
    lines = [f"scene {study.scene}: reference {ref.verdict or 'without verdict'}, CPU {ref.cpu_time_s:.1f} s "
             f"(wall {ref.wall_time_s:.1f} s); "
             + ", ".join(f"{q} {ref.values[q]:.6g}" for q in SCALAR_QUANTITIES if ref.values.get(q) is not None),
             f"  base overrides: {study.base_overrides or 'none'}",
             "  " + f"{'run':<44} {'CPU s':>7} {'wall s':>7} " + " ".join(f"{q[:14]:>14}" for q in names) + "  verdict"]
    for r in study.records:
        if r["failure"]:
            lines.append(f"  {r['label']:<44} {r['cpu_time_s']:>7.1f} {r['wall_time_s']:>7.1f}  did not converge")
            continue
        errs = " ".join(f"{100 * r['errors'][q]:>13.2f}%" if q in r["errors"] else f"{'-':>14}" for q in names)
        mark = "" if r["verdict_agrees"] else " (differs)"
        lines.append(f"  {r['label']:<44} {r['cpu_time_s']:>7.1f} {r['wall_time_s']:>7.1f} {errs}  "
                     f"{r['verdict'] or '-'}{mark}")
    for name, why in study.not_applicable.items():
        lines.append(f"  not applicable: {name}: {why}")
    rec = study.recommendation
    if rec:
        lines.append(f"  recommended (cheapest within {100 * TOLERANCE:g} %): {rec['label']} — "
                     f"CPU {rec['cpu_time_s']:.1f} s, {rec['speedup']:.1f}x cheaper than the reference, "
                     f"worst error {100 * rec['worst_error']:.2f} %; overrides {rec['overrides']}")
    else:
        lines.append(f"  no swept setting keeps every decision quantity within {100 * TOLERANCE:g} %")
    if study.plot:
        lines.append(f"  plot: {study.plot}")
    return lines
