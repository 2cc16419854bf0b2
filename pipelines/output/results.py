"""The results file: one HDF5 file per run, readable with h5py alone.

Layout (format_version 1; every dataset carries a ``units`` attribute):

    /                      attrs: fretwork_format="fretwork-results", format_version,
                           scene_name, scene_toml (the scene as run, resolved: its scene.base
                           chain merged, overrides applied, file paths absolute, written as TOML
                           that ``fretwork run`` reads from any folder; see
                           pipelines.scene.resolved_text. Files written before it was resolved
                           hold the top scene file's own text, its base not included),
                           complete (False until the run ends),
                           ending (contact.verdict.Ending: completed, shakedown, loosening, or
                           slid_off / wear_runaway / separated: the cycles so far, without /final
                           and /summary;
                           such a file's ending_message is the failed increment's error, in words)
    /points/               coordinates (n, dim) mm, area (n,) mm² (mm in 2D), normal (n, dim),
                           initial_overclosure (n,) mm, facets (m, k) point indices of the
                           contact surface's facets (lines in 2D, quads/triangles in 3D)
    /increments/           one row per converged increment: time (cycles), cycle, phase
                           (0 preload, 1 cof, 2 wear), iterations, cutbacks,
                           external_work, stored_energy, dissipation, wear_release and
                           stick_source (mJ: external_work + stick_source − stored_energy −
                           wear_release is the dissipation measured globally,
                           contact.energy), bolt_forces
                           (rows, n_bolts) N with the bolt names in its ``bolts`` attribute,
                           control/displacement and control/force (rows, n_dofs) mm and N (rad
                           and N*mm for rotations: per column in their ``units``), the DOF
                           labels in the ``dofs`` attribute of /increments/control
    /cycles/               one row per recorded cycle: cycle, phase, equivalent_cycles and one
                           dataset per global figure (figures/<name>); fields/<name> (rows, n[, k])
    /increment_fields/     only with [procedure] field_output: per-point fields at chosen increments
                           of the recorded cycles ("increment": every one; a list of cycle fractions:
                           the increment nearest each). One row per written increment: time
                           (cycles; (cycle − 1) + fraction, as in /increments/time), cycle,
                           fraction (of the cycle, exact: k / increments_per_cycle), and
                           fields/<name> (rows, n[, k]): pressure, shear, cof, accumulated_slip,
                           dissipation, wear_depth as at that increment (at fraction 1 the same
                           numbers as the cycle's row in /cycles/fields) and status, the
                           increment's own status (codes as /final/status; /cycles/fields/status
                           is the worst status over a whole cycle)
    /final/                the final per-point fields. wear_depth (2, n): the slave's depth and the
                           master's; in finite sliding the master's row is its depth read at each
                           point's current partners (what the point's gap sees), and the master's
                           own field is master_wear_depth (n_master,) mm on the nodes of
                           /master_surface/ (its scar reaches beyond the points' partners)
    /master_surface/       finite sliding only: the master surface's nodes, coordinates (n_master,
                           dim) mm, area (n_master,) mm² (mm in 2D), facets (m, k) node indices
    /summary               attrs: verdict, stationary, figures (JSON)
    /histories/            only in a coupled run: the multibody histories that drive its loads, as
                           ``fretwork mbs`` writes them (time s, cw<k>_* signals; see
                           :func:`write_driving_histories`): ``fretwork export-fmu`` plays them back

The file is written as ``results.h5.part`` and renamed when the run completes, so a
``results.h5`` is never half-written. Rows are kept in memory and written in blocks: at every
checkpoint, at the end of every ``flush_cycles``-th cycle since the last block, when a run fails
or is interrupted, and at the end; the part file can then be read after an interruption up to
its last block. (Written row by row, the file cost 30-80 ms per cycle, 1.5-2 ms per increment
of a 12- or 40-increment cycle: as much as the contact solve of a small interface.) When a block
is written changes no value in it, but it changes where HDF5 places the chunks, so the rule
counts cycles and never reads the clock: two runs of one scene give the same bytes however long
they take. (Every 10 s of wall time, as it was, gave longer runs equal datasets in different
bytes.) After every checkpoint the run goes on in a part file made anew from ``checkpoint.h5``
(its groups copied into a fresh file), and a resumed run starts from the same copy: it ends
with the same bytes as the uninterrupted run, and no bigger. (Deleting ``/checkpoint`` from a
copy of ``checkpoint.h5``, as it was, left its space in the file: a counterweight run of 260
cycles, 4.56 MB uninterrupted, was 7.12 MB after two resumes; now 4.79 MB either way.) A
finished file is copied once more into a fresh one before it is moved into place: blocks
appended one by one leave unused space behind, about 40 % of that file.
"""

from __future__ import annotations

import json
import os
import shutil
import tomllib
from pathlib import Path

import h5py
import numpy as np

from contact.energy import EnergyMeter
from contact.procedure import PHASES, CycleSummary, IncrementRecord, Observer
from mbs.results import write_loading_histories
from pipelines import interrupts
from pipelines import scene as scenes
from pipelines.output.checkpoint import read_snapshot, write_snapshot
from reduction.errors import InputError

FORMAT = "fretwork-results"
FORMAT_VERSION = 1
#: the units of a contact area (of the points, or of the master surface's nodes)
AREA_UNITS = "mm^2 (mm per unit thickness in 2D)"
FIELD_UNITS = {
    "pressure": "MPa", "shear": "MPa", "cof": "1", "max_utilised_cof": "1", "max_shear": "MPa",
    "status": "code",
    "slip_range": "mm", "dissipation_in_cycle": "mJ/mm^2", "wear_depth": "mm",
    "accumulated_slip": "mm", "dissipation": "mJ/mm^2",
    "fdp": "MPa*mm", "ffdp": "MPa^2*mm", "surface_tangential_stress": "MPa",
}
STATUS_NAMES = "0 open, 1 stick, 2 slip, 3 slip at cof_max"
#: units of the cycle figures (/cycles/figures/<name>) by the end of their names, longest first
FIGURE_UNITS = (("_fraction", "1 (of the nominal contact area, closed after the preload)"),
                ("_MPa2_mm", "MPa^2*mm"), ("_MPa_mm", "MPa*mm"), ("_MPa", "MPa"), ("_mm3", "mm^3"),
                ("_mm", "mm"), ("_mJ", "mJ"), ("_N", "N"), ("_margin", "1"))


def figure_units(name: str) -> str:
    """The units of the cycle figure ``name`` (:data:`FIGURE_UNITS`)."""
    for ending, units in FIGURE_UNITS:
        if name.endswith(ending):
            return units
    raise KeyError(f"no units known for the cycle figure {name!r}: add its ending to FIGURE_UNITS")


def output_increments(field_output, increments_per_cycle: int) -> frozenset:
    """The increments k (1 … n) of a recorded cycle whose fields ``field_output`` asks for:
    "cycle" or None none (the cycle's end is in /cycles/fields), "increment" all, a list of
    cycle fractions the increment nearest each (k = round(fraction·n), at least 1)."""
    n = increments_per_cycle
    if field_output is None or field_output == "cycle":
        return frozenset()
    if field_output == "increment":
        return frozenset(range(1, n + 1))
    return frozenset(max(1, round(fraction * n)) for fraction in field_output)


def _append_rows(group: h5py.Group, name: str, rows, units: str) -> None:
    """Append a block of rows (k, ...) to a resizable dataset, creating it on first use."""
    rows = np.asarray(rows)
    if rows.dtype.kind not in "fciu":
        rows = rows.astype(float)
    if name not in group:
        shape = rows.shape[1:]
        size = int(np.prod(shape)) if shape else 1
        group.create_dataset(name, data=rows, maxshape=(None,) + shape,
                             chunks=(max(1, min(256, 65536 // size)),) + shape,
                             compression="gzip" if size > 64 else None)
        group[name].attrs["units"] = units
    else:
        dataset = group[name]
        start = dataset.shape[0]
        dataset.resize(start + rows.shape[0], axis=0)
        dataset[start:] = rows


def write_driving_histories(root: h5py.Group, coupled) -> None:
    """``/histories``: the multibody histories a coupled run's loads come from
    (:class:`pipelines.coupling.Coupled`), in the layout ``fretwork mbs`` writes, so that
    ``fretwork export-fmu`` plays them back from either file. ``vibration_scale``: the factor the
    contact load cycle applies to their vibrating parts (a stated wing amplitude); ``load_cycle``
    ("wing_period" or "revolution"), ``wing_amplitude`` and ``multibody_wing_amplitude`` (mm),
    ``load_cycle_frequency_hz``: the cycle they were played in."""
    group = root.create_group("histories")
    write_loading_histories(group, coupled.loading, coupled.settings.counterweight)
    if coupled.cycle is not None:
        group.attrs.update(vibration_scale=coupled.cycle.scale, load_cycle=coupled.cycle.cycle,
                           wing_amplitude=coupled.cycle.wing_amplitude,
                           multibody_wing_amplitude=coupled.cycle.multibody_wing_amplitude,
                           load_cycle_frequency_hz=coupled.cycle.frequency_hz)


class ResultsWriter(Observer):
    """Observer that writes increments and cycles to HDF5 and reports progress.

    ``checkpoint(snapshot)`` copies the results so far, with the snapshot, to
    ``checkpoint.h5`` beside the results (atomic rename); :meth:`resume` reopens a run there.
    """

    def __init__(self, path: Path, model, space, *, record_every: int = 1, progress=None,
                 track_energy: bool = True, resume: bool = False, field_output=None,
                 flush_cycles: int = 25):
        self.final_path = Path(path)
        self.part_path = self.final_path.with_suffix(".h5.part")
        self.checkpoint_path = self.final_path.with_name("checkpoint.h5")
        self.model = model
        self.record_every = record_every
        self.progress = progress
        self.meter = EnergyMeter(space, model.law) if track_energy else None
        self.labels = model.assembly.structure.labels
        self.flush_cycles = flush_cycles
        self._rows: dict[str, dict[str, list]] = {"increments": {}, "cycles": {}}
        self._units: dict[str, str] = {}
        self.snapshot = None
        self.area = space.structure.area
        self.output_increments = output_increments(field_output, model.procedure.increments_per_cycle)
        self._increment_fields: list[tuple[int, int, float, dict]] = []
        if resume:
            self._reopen_from_checkpoint()
            return
        self.file = h5py.File(self.part_path, "w")
        root = self.file
        root.attrs.update(fretwork_format=FORMAT, format_version=FORMAT_VERSION,
                          scene_name=model.scene.name, complete=False,
                          scene_toml=scenes.resolved_text(model.scene))
        pairing = model.assembly.pairing
        points = root.create_group("points")
        for name, data, units in (("coordinates", pairing.slave.coordinates, "mm"),
                                  ("area", pairing.area, AREA_UNITS),
                                  ("normal", pairing.normal, "1"),
                                  ("initial_overclosure", pairing.initial_overclosure, "mm"),
                                  ("facets", pairing.slave.facets, "index")):
            points.create_dataset(name, data=data).attrs["units"] = units
        root.create_group("increments")
        root.create_group("cycles")
        if model.coupling is not None:
            write_driving_histories(root, model.coupling)

    def _reopen_from_checkpoint(self) -> None:
        if not self.checkpoint_path.is_file():
            raise InputError(f"nothing to resume: {self.checkpoint_path} does not exist")
        try:
            with h5py.File(self.checkpoint_path, "r") as file:
                self._check_scene(str(file.attrs.get("scene_toml", "")))
                self.snapshot = read_snapshot(file["checkpoint"], self.meter)
        except InputError:  # a checkpoint of another scene
            raise
        except (OSError, KeyError, ValueError) as error:
            raise InputError(f"{self.checkpoint_path} is damaged ({error}): the run cannot be resumed from it; run "
                             "again without --resume to start the run afresh (that replaces the damaged "
                             "checkpoint)") from None
        self._part_from_checkpoint()

    def _check_scene(self, text: str) -> None:
        """Refuse a checkpoint whose resolved scene (``scene_toml``) is not this run's: a changed
        base file counts as much as a changed scene file; comments and layout do not."""
        try:
            stored = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            stored = {}
        changed = scenes.differences(stored, scenes.resolved(self.model.scene))
        if changed:
            shown = ", ".join(changed[:5]) + (f" and {len(changed) - 5} more" if len(changed) > 5 else "")
            raise InputError(f"{self.checkpoint_path} belongs to a different scene ({shown} changed "
                             "since the run started, in the scene file or a base it extends); resume "
                             "with the scene the run started from, or start the run again")

    def _part_from_checkpoint(self) -> None:
        """Make the part file anew from ``checkpoint.h5``: its results copied into a fresh file,
        ``/checkpoint`` left out. Done after every checkpoint as well as on resume, so that a
        resumed run goes on from the very bytes the uninterrupted run went on from, and ends with
        the same file (a copy with ``/checkpoint`` deleted would keep the freed space)."""
        _copy_fresh(self.checkpoint_path, self.part_path, leave_out=("checkpoint",))
        self.file = h5py.File(self.part_path, "a")

    def checkpoint(self, snapshot) -> None:
        """Write ``checkpoint.h5`` atomically: results so far + ``/checkpoint`` snapshot; then go on
        in a part file made from it (:meth:`_part_from_checkpoint`)."""
        self._flush()
        self.file.close()
        temporary = self.checkpoint_path.with_suffix(".h5.tmp")
        shutil.copyfile(self.part_path, temporary)
        with h5py.File(temporary, "a") as file:
            write_snapshot(file.create_group("checkpoint"), snapshot, self.meter)
        os.replace(temporary, self.checkpoint_path)
        self._part_from_checkpoint()

    def follow(self, space) -> None:
        """Go on in ``space``, a new pairing's contact space (finite sliding): its point areas."""
        self.area = space.structure.area
        if self.meter is not None:
            self.meter.follow(space)

    def phase(self, name, n_cycles):
        if self.progress is not None:
            self.progress.phase(name, n_cycles)

    def _row(self, name: str, value, units: str, group: str = "increments") -> None:
        self._rows[group].setdefault(name, []).append(value)
        self._units[f"{group}/{name}"] = units

    def _flush(self) -> None:
        """Write the rows kept since the last flush, and flush the file."""
        for group_name, rows in self._rows.items():
            group = self.file[group_name]
            for name, values in rows.items():
                _append_rows(group, name, np.array(values), self._units[f"{group_name}/{name}"])
        self._label_columns()
        self._rows = {"increments": {}, "cycles": {}}
        self._flush_increment_fields()
        self.file.flush()

    def _label_columns(self) -> None:
        """Name the columns of the per-increment tables (bolts, control DOFs and their units) as
        soon as they exist, so that a run's partial file (and its checkpoint) reads like a
        finished one."""
        increments = self.file["increments"]
        if "bolt_forces" in increments:
            increments["bolt_forces"].attrs["bolts"] = ",".join(self.model.assembly.structure.bolts.names)
        if "control/displacement" in increments:
            increments["control"].attrs["dofs"] = ",".join(self.labels)
            rotation = [label.rsplit(".", 1)[-1].startswith("r") for label in self.labels]  # rx, ry, rz
            for name, units in (("displacement", ("mm", "rad")), ("force", ("N", "N*mm"))):
                increments[f"control/{name}"].attrs["units"] = ",".join(units[r] for r in rotation)

    def increment(self, record: IncrementRecord) -> None:
        interrupts.check()
        self._row("time", record.time, "cycles")
        self._row("cycle", record.cycle, "1")
        self._row("phase", PHASES.index(record.phase), "0 preload, 1 cof, 2 wear")
        self._row("iterations", record.iterations, "1")
        self._row("cutbacks", record.cutbacks, "1")
        area = self.model.assembly.structure.area
        self._row("dissipation", float(np.sum(record.state.dissipation * area)), "mJ")
        if self.meter is not None:
            work, stored = self.meter.update(record.equilibrium, record.state, record.locked_elongation)
            self._row("external_work", work, "mJ")
            self._row("stored_energy", stored, "mJ")
            self._row("wear_release", self.meter.wear_release, "mJ")
            self._row("stick_source", self.meter.stick_source, "mJ")
            displacement, forces = self.meter.control_values(np.fromiter(self.labels.values(), dtype=int))
            self._row("control/displacement", displacement, "mm")
            self._row("control/force", forces, "N")
        if record.bolt_forces is not None:
            self._row("bolt_forces", record.bolt_forces, "N")
        if self.output_increments and record.phase != "preload" and self._recorded(record.cycle):
            self._keep_increment_fields(record)
        if self.progress is not None:
            self.progress.increment(record)

    def _recorded(self, cycle: int) -> bool:
        return cycle % self.record_every == 0 or cycle == 1

    def _keep_increment_fields(self, record: IncrementRecord) -> None:
        n = self.model.procedure.increments_per_cycle
        k = round((record.time - (record.cycle - 1)) * n)
        if k not in self.output_increments:
            return
        # the same operations as the cycle summary's, so that at k = n the numbers are its own
        per_point = record.equilibrium.forces.reshape(self.area.size, -1) / self.area[:, None]
        state = record.state
        fields = {"pressure": per_point[:, 0], "shear": per_point[:, 1:], "status": record.status,
                  "cof": state.cof, "accumulated_slip": state.accumulated_slip, "dissipation": state.dissipation}
        if state.wear_depth is not None:
            fields["wear_depth"] = state.wear_depth
        self._increment_fields.append((record.cycle, k, record.time,
                                       {name: np.array(value, copy=True) for name, value in fields.items()}))

    def _flush_increment_fields(self) -> None:
        if not self._increment_fields:
            return
        group = self.file.require_group("increment_fields")
        n = self.model.procedure.increments_per_cycle
        cycles, steps, times, rows = zip(*self._increment_fields)
        _append_rows(group, "time", np.array(times), "cycles")
        _append_rows(group, "cycle", np.array(cycles), "1")
        _append_rows(group, "fraction", np.array(steps) / n, "1 (of the load cycle)")
        for name in rows[0]:
            _append_rows(group, f"fields/{name}", np.stack([row[name] for row in rows]), FIELD_UNITS[name])
        group["fields/status"].attrs["codes"] = STATUS_NAMES
        self._increment_fields = []

    def cycle(self, summary: CycleSummary) -> None:
        recorded = self._recorded(summary.cycle)
        self._row("cycle", summary.cycle, "1", "cycles")
        self._row("phase", PHASES.index(summary.phase), "0 preload, 1 cof, 2 wear", "cycles")
        self._row("equivalent_cycles", summary.equivalent_cycles, "cycles", "cycles")
        for name, value in summary.figures.items():
            self._row(f"figures/{name}", np.nan if value is None else value, figure_units(name), "cycles")
        if recorded:
            self._row("fields/cycle", summary.cycle, "1", "cycles")
            for name, value in self._fields(summary).items():
                # copied: a field may be a view of state the run goes on to change
                self._row(f"fields/{name}", np.array(value), FIELD_UNITS[name], "cycles")
        if len(self._rows["cycles"]["cycle"]) >= self.flush_cycles:  # cycles kept since the last block
            self._flush()
        if self.progress is not None:
            self.progress.cycle(summary)

    @staticmethod
    def _fields(summary: CycleSummary) -> dict:
        state = summary.state
        fields = {
            "pressure": summary.pressure, "shear": summary.shear, "cof": summary.cof,
            "max_utilised_cof": summary.max_utilised_cof, "max_shear": summary.max_shear,
            "status": summary.status,
            "slip_range": summary.slip_range, "dissipation_in_cycle": summary.dissipation_in_cycle,
            "accumulated_slip": state.accumulated_slip, "dissipation": state.dissipation,
        }
        if state.wear_depth is not None:
            fields["wear_depth"] = state.wear_depth
        fields.update(summary.damage)
        return fields

    def finish(self, result) -> Path:
        """Write the final fields and the summary, close, and move the file into place."""
        self._flush()
        final = self.file.create_group("final")
        last = result.cycles[-1]
        for name, value in self._fields(last).items():
            final.create_dataset(name, data=value).attrs["units"] = FIELD_UNITS[name]
        final["status"].attrs["codes"] = STATUS_NAMES
        master_wear = getattr(last.state, "master_wear", None)
        if master_wear is not None:
            self._write_master_wear(master_wear)
        summary = self.file.create_group("summary")
        summary.attrs.update(verdict=result.verdict, stationary=result.stationary,
                             figures=json.dumps(result.figures))
        return self.stop(result.ending)

    def _write_master_wear(self, depth: np.ndarray) -> None:
        """The master body's own wear field (finite sliding): ``/final/master_wear_depth`` on
        the nodes of ``/master_surface/``, whose scar reaches beyond the points' partners."""
        master = self.model.assembly.pairing.master
        surface = self.file.create_group("master_surface")
        for name, data, units in (("coordinates", master.coordinates, "mm"),
                                  ("area", master.area, AREA_UNITS),
                                  ("facets", master.facets, "index")):
            surface.create_dataset(name, data=data).attrs["units"] = units
        self.file["final"].create_dataset("master_wear_depth", data=depth).attrs["units"] = "mm"

    def stop(self, ending, message: str | None = None) -> Path:
        """Mark the file with the run's :class:`contact.verdict.Ending`, close it and move it into
        place; alone, for a run that ended early (slid off, runaway wear): the cycles so far, and
        ``message``, why the increment that ended it failed, as ``ending_message``."""
        self._flush()
        self.file.attrs.update(complete=True, ending=ending.value)
        if message is not None:
            self.file.attrs["ending_message"] = message
        self.file.close()
        # the rows were appended block by block, each compressed block leaving unused space
        # behind; a fresh copy holds the same datasets in about 60 % of the bytes
        compact = self.part_path.with_suffix(".compact")
        _copy_fresh(self.part_path, compact)
        compact.replace(self.final_path)
        self.part_path.unlink()
        self.checkpoint_path.unlink(missing_ok=True)
        return self.final_path

    def abort(self) -> None:
        """Write what is kept and close the file after a failure; the part file stays for inspection."""
        if self.file.id.valid:
            self._flush()
            self.file.close()

    def discard(self) -> None:
        """Close and remove the part file of a run refused before its first cycle (nothing presses
        the surfaces together after the preload): a refused input leaves no output behind."""
        if self.file.id.valid:
            self.file.close()
        self.part_path.unlink(missing_ok=True)


def _copy_fresh(source_path: Path, target_path: Path, leave_out: tuple = ()) -> None:
    """Copy an HDF5 file's root attributes (with their exact types) and groups, but those named
    in ``leave_out``, into a fresh file at ``target_path``: no freed or unused space is carried
    over, and the same source gives the same bytes."""
    with h5py.File(source_path, "r") as source, h5py.File(target_path, "w") as target:
        for name in source.attrs:
            target.attrs.create(name, source.attrs[name], dtype=source.attrs.get_id(name).dtype)
        for name in source:
            if name not in leave_out:
                source.copy(source[name], target, name=name)


def read_summary(path: str | Path) -> dict:
    """Verdict and figures of a finished results file; InputError for a file of another kind
    (a sweep, a multibody run.h5) or a run that did not finish."""
    from mbs.results import SWEEP_FORMAT

    with h5py.File(path, "r") as file:
        tag = file.attrs.get("fretwork_format")
        if tag == SWEEP_FORMAT:
            raise InputError(f"{path} is a speed sweep of `fretwork sweep`, not a run's results file: "
                             "`fretwork report FOLDER` reads its margins")
        if tag != FORMAT:
            raise InputError(f"{path} is not a fretwork results file (no fretwork_format = {FORMAT!r})")
        if "summary" not in file:
            ending = file.attrs.get("ending")
            raise InputError(f"{path} has no summary: "
                             + (f"the run stopped early ({ending})" if ending not in (None, "completed") else
                                "an unfinished run, or the run.h5 of `fretwork mbs` (`fretwork export-fmu` reads that)"))
        summary = file["summary"].attrs
        return {"verdict": summary["verdict"], **json.loads(summary["figures"])}
