"""Checkpoints of a contact run: the results so far plus everything needed to continue.

A checkpoint is a complete copy of the results file with a ``/checkpoint`` group holding the
procedure's :class:`contact.procedure.Snapshot` and the energy meter's accumulators. It is
written under a temporary name and renamed, so ``checkpoint.h5`` is always whole: a run
killed at any moment resumes from the last complete checkpoint. :func:`check_resumable` says,
before a resumed run builds anything, whether there is a checkpoint to resume and whether it can
be read (one truncated or emptied after it was written cannot).
"""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

import h5py

from contact.law import ContactState
from contact.sliding import SlidingState
from contact.procedure import CycleSummary, Snapshot
from contact.solver import Equilibrium
from reduction.errors import InputError

CHECKPOINT_NAME = "checkpoint.h5"

SUMMARY_ARRAYS = ("pressure", "shear", "cof", "max_utilised_cof", "max_shear", "status", "slip_range",
                  "dissipation_in_cycle")


def _write_state(group: h5py.Group, state: ContactState) -> None:
    for item in fields(state):  # a finite-sliding state adds the master's wear and its pairing
        value = getattr(state, item.name)
        if value is not None:
            group.create_dataset(item.name, data=value)


def _read_state(group: h5py.Group) -> ContactState:
    kind = SlidingState if any(item.name in group for item in fields(SlidingState)
                               if item.name not in ContactState.__dataclass_fields__) else ContactState
    return kind(**{item.name: group[item.name][()] if item.name in group else None
                   for item in fields(kind)})


def write_snapshot(group: h5py.Group, snapshot: Snapshot, meter) -> None:
    """Store ``snapshot`` and the energy meter (or None) in ``group``."""
    scalars = {name: getattr(snapshot, name) for name in
               ("cycle_number", "phase_index", "cycles_in_phase", "quiet_cycles", "equivalent",
                "nominal_area", "initial_clamp", "jump", "loosening_at")}
    group.attrs["scalars"] = json.dumps(scalars)
    group.create_dataset("cof_initial", data=snapshot.cof_initial)
    if snapshot.locked_elongation is not None:
        group.create_dataset("locked_elongation", data=snapshot.locked_elongation)
    _write_state(group.create_group("state"), snapshot.state)
    equilibrium = group.create_group("equilibrium")
    for item in fields(Equilibrium):
        equilibrium.create_dataset(item.name, data=getattr(snapshot.equilibrium, item.name))
    history = group.create_group("history")
    history.attrs["entries"] = json.dumps([{"cycle": c.cycle, "phase": c.phase,
                                            "equivalent_cycles": c.equivalent_cycles,
                                            "clamp_force": c.clamp_force, "figures": c.figures}
                                           for c in snapshot.history])
    last = snapshot.history[-1]
    for name in SUMMARY_ARRAYS:
        history.create_dataset(name, data=getattr(last, name))
    for name in ("predictors", "linear"):
        memory = getattr(snapshot, name)
        if memory:
            stored = group.create_group(name)
            for key, value in memory.items():
                stored.create_dataset(key, data=value)
    if meter is not None:
        energy = group.create_group("energy")
        energy.attrs["sums"] = json.dumps({"external_work": meter.external_work,
                                           "wear_release": meter.wear_release,
                                           "stick_source": meter.stick_source})
        for name, value in meter.memory().items():
            energy.create_dataset(name, data=value)


def read_snapshot(group: h5py.Group, meter) -> Snapshot:
    """The snapshot stored by :func:`write_snapshot`; restores ``meter`` in place."""
    scalars = json.loads(group.attrs["scalars"])
    state = _read_state(group["state"])
    equilibrium = Equilibrium(**{item.name: group["equilibrium"][item.name][()] for item in fields(Equilibrium)})
    entries = json.loads(group["history"].attrs["entries"])
    history = []
    for k, entry in enumerate(entries):
        last = k == len(entries) - 1
        arrays = {name: group["history"][name][()] if last else None for name in SUMMARY_ARRAYS}
        summary = CycleSummary(cycle=entry["cycle"], phase=entry["phase"],
                               equivalent_cycles=entry["equivalent_cycles"], state=state if last else None,
                               clamp_force=entry["clamp_force"], **arrays)
        summary.figures = entry["figures"]
        history.append(summary)
    if meter is not None and "energy" in group:
        energy = group["energy"]
        for name, value in json.loads(energy.attrs["sums"]).items():
            setattr(meter, name, value)
        meter.recall({name: energy[name][()] for name in energy})
    memories = {name: {key: value[()] for key, value in group[name].items()} if name in group else {}
                for name in ("predictors", "linear")}
    return Snapshot(cof_initial=group["cof_initial"][()],
                    locked_elongation=group["locked_elongation"][()] if "locked_elongation" in group else None,
                    state=state, equilibrium=equilibrium, history=history, **memories, **scalars)


def check_resumable(folder) -> Path:
    """``folder``'s checkpoint, if a run can be resumed from it; an InputError saying why not
    (none: nothing to resume, or the run is complete; damaged: empty, truncated or unreadable,
    or without the state a resumed run needs)."""
    folder = Path(folder)
    path = folder / CHECKPOINT_NAME
    if not path.is_file():
        if (folder / "results.h5").is_file():
            raise InputError(f"{folder / 'results.h5'} is complete: there is nothing to resume")
        raise InputError(f"nothing to resume: {path} does not exist (a run writes it every checkpoint_every "
                         "cycles); run without --resume")
    size = path.stat().st_size
    damaged = (f"{path} is damaged ({{}}): the run cannot be resumed from it; run again without --resume "
               "to start the run afresh (that replaces the damaged checkpoint)")
    if size == 0:
        raise InputError(damaged.format("empty: 0 bytes"))
    try:
        with h5py.File(path, "r") as file:
            state = file.get("checkpoint")
            whole = isinstance(state, h5py.Group) and "scalars" in state.attrs and "state" in state
    except OSError:
        raise InputError(damaged.format(f"truncated or unreadable: HDF5 cannot open its {size:,} bytes")) from None
    if not whole:
        raise InputError(damaged.format("it holds no complete /checkpoint state"))
    return path


__all__ = ["CHECKPOINT_NAME", "check_resumable", "write_snapshot", "read_snapshot"]
