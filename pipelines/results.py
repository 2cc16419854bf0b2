"""The results file: one HDF5 file per run, readable with h5py alone.

Layout (format_version 1; every dataset carries a ``units`` attribute):

    /                      attrs: fretwork_format="fretwork-results", format_version,
                           scene_name, scene_toml, complete (False until the run ends)
    /points/               coordinates (n, dim) mm, area (n,) mm² (mm in 2D), normal (n, dim),
                           initial_overclosure (n,) mm
    /increments/           one row per converged increment: time (cycles), cycle, phase
                           (0 preload, 1 cof, 2 wear), iterations, cutbacks,
                           external_work, stored_energy, dissipation (mJ), bolt_forces
                           (rows, n_bolts) N with the bolt names in its ``bolts`` attribute,
                           control/<dof>/displacement (mm) and control/<dof>/force (N)
    /cycles/               one row per recorded cycle: cycle, phase, equivalent_cycles and one
                           dataset per global figure (figures/<name>); fields/<name> (rows, n[, k])
    /final/                the final per-point fields
    /summary               attrs: verdict, stationary, figures (JSON)

The file is written as ``results.h5.part`` and renamed when the run completes, so a
``results.h5`` is never half-written; the part file is flushed every cycle and can be read
after an interruption.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from contact.energy import EnergyMeter
from contact.procedure import PHASES, CycleSummary, IncrementRecord, Observer

FORMAT = "fretwork-results"
FORMAT_VERSION = 1
FIELD_UNITS = {
    "pressure": "MPa", "shear": "MPa", "cof": "1", "max_utilised_cof": "1", "status": "code",
    "slip_range": "mm", "dissipation_in_cycle": "mJ/mm^2", "wear_depth": "mm",
    "accumulated_slip": "mm", "dissipation": "mJ/mm^2",
}
STATUS_NAMES = "0 open, 1 stick, 2 slip, 3 slip at cof_max"


def _append(group: h5py.Group, name: str, row, units: str) -> None:
    row = np.asarray(row, dtype=float if np.asarray(row).dtype.kind in "fc" else np.asarray(row).dtype)
    if name not in group:
        group.create_dataset(name, data=row[None], maxshape=(None,) + row.shape,
                             chunks=(64,) + row.shape if row.size < 4096 else (1,) + row.shape,
                             compression="gzip" if row.size > 64 else None)
        group[name].attrs["units"] = units
    else:
        dataset = group[name]
        dataset.resize(dataset.shape[0] + 1, axis=0)
        dataset[-1] = row


class ResultsWriter(Observer):
    """Observer that writes increments and cycles to HDF5 and reports progress."""

    def __init__(self, path: Path, model, space, *, record_every: int = 1, progress=None,
                 track_energy: bool = True):
        self.final_path = Path(path)
        self.part_path = self.final_path.with_suffix(".h5.part")
        self.file = h5py.File(self.part_path, "w")
        self.model = model
        self.record_every = record_every
        self.progress = progress
        self.meter = EnergyMeter(space, model.law) if track_energy else None
        self.labels = model.assembly.structure.labels
        root = self.file
        root.attrs.update(fretwork_format=FORMAT, format_version=FORMAT_VERSION,
                          scene_name=model.scene.name, complete=False,
                          scene_toml=model.scene.path.read_text() if model.scene.path else "")
        pairing = model.assembly.pairing
        points = root.create_group("points")
        for name, data, units in (("coordinates", pairing.slave.coordinates, "mm"),
                                  ("area", pairing.area, "mm^2 (mm per unit thickness in 2D)"),
                                  ("normal", pairing.normal, "1"),
                                  ("initial_overclosure", pairing.initial_overclosure, "mm")):
            points.create_dataset(name, data=data).attrs["units"] = units
        root.create_group("increments")
        root.create_group("cycles")

    def phase(self, name, n_cycles):
        if self.progress is not None:
            self.progress.phase(name, n_cycles)

    def increment(self, record: IncrementRecord) -> None:
        group = self.file["increments"]
        _append(group, "time", record.time, "cycles")
        _append(group, "cycle", record.cycle, "1")
        _append(group, "phase", PHASES.index(record.phase), "0 preload, 1 cof, 2 wear")
        _append(group, "iterations", record.iterations, "1")
        _append(group, "cutbacks", record.cutbacks, "1")
        area = self.model.assembly.structure.area
        _append(group, "dissipation", float(np.sum(record.state.dissipation * area)), "mJ")
        if self.meter is not None:
            work, stored = self.meter.update(record.equilibrium, record.state)
            _append(group, "external_work", work, "mJ")
            _append(group, "stored_energy", stored, "mJ")
            _append(group, "wear_release", self.meter.wear_release, "mJ")
            displacement = self.meter._displacement
            forces = self.meter._forces
            for label, dof in self.labels.items():
                _append(group, f"control/{label}/displacement", displacement[dof], "mm")
                _append(group, f"control/{label}/force", forces[dof], "N")
        if record.bolt_forces is not None:
            _append(group, "bolt_forces", record.bolt_forces, "N")
            group["bolt_forces"].attrs["bolts"] = ",".join(self.model.assembly.structure.bolts.names)
        if self.progress is not None:
            self.progress.increment(record)

    def cycle(self, summary: CycleSummary) -> None:
        group = self.file["cycles"]
        recorded = summary.cycle % self.record_every == 0 or summary.cycle == 1
        _append(group, "cycle", summary.cycle, "1")
        _append(group, "phase", PHASES.index(summary.phase), "0 preload, 1 cof, 2 wear")
        _append(group, "equivalent_cycles", summary.equivalent_cycles, "cycles")
        for name, value in summary.figures.items():
            _append(group, f"figures/{name}", np.nan if value is None else value, "see README")
        if recorded:
            _append(group, "fields/cycle", summary.cycle, "1")
            for name, value in self._fields(summary).items():
                _append(group, f"fields/{name}", value, FIELD_UNITS[name])
        self.file.flush()
        if self.progress is not None:
            self.progress.cycle(summary)

    @staticmethod
    def _fields(summary: CycleSummary) -> dict:
        state = summary.state
        fields = {
            "pressure": summary.pressure, "shear": summary.shear, "cof": summary.cof,
            "max_utilised_cof": summary.max_utilised_cof, "status": summary.status,
            "slip_range": summary.slip_range, "dissipation_in_cycle": summary.dissipation_in_cycle,
            "accumulated_slip": state.accumulated_slip, "dissipation": state.dissipation,
        }
        if state.wear_depth is not None:
            fields["wear_depth"] = state.wear_depth
        return fields

    def finish(self, result) -> Path:
        """Write the final fields and the summary, close, and move the file into place."""
        final = self.file.create_group("final")
        last = result.cycles[-1]
        for name, value in self._fields(last).items():
            final.create_dataset(name, data=value).attrs["units"] = FIELD_UNITS[name]
        final["status"].attrs["codes"] = STATUS_NAMES
        summary = self.file.create_group("summary")
        summary.attrs.update(verdict=result.verdict, stationary=result.stationary,
                             figures=json.dumps(result.figures))
        self.file.attrs["complete"] = True
        self.file.close()
        self.part_path.replace(self.final_path)
        return self.final_path

    def abort(self) -> None:
        """Close the file after a failure; the part file stays for inspection."""
        if self.file.id.valid:
            self.file.close()


def read_summary(path: str | Path) -> dict:
    """Verdict and figures of a finished results file."""
    with h5py.File(path, "r") as file:
        if file.attrs.get("fretwork_format") != FORMAT:
            raise ValueError(f"{path} is not a fretwork results file")
        summary = file["summary"].attrs
        return {"verdict": summary["verdict"], **json.loads(summary["figures"])}
