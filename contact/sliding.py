"""Finite sliding: the pairing follows the bodies, and each body wears on its own surface.

Small sliding pairs the surfaces once, from the undeformed geometry; that is exact while the
relative tangential motion stays well below the element size. In gross-slip fretting the
stroke is comparable to the contact width: a slave point then travels over many master
elements, and the master's scar must widen by the stroke. :class:`SlidingSolver` wraps a
:class:`contact.solver.ContactSolver` and, between increments, re-pairs the surfaces at their
current (deformed) positions when the points have slid by a fraction of a master element.
Only the small pairing operator G, the gaps and the contact-space compliance are rebuilt;
the condensed bodies are not.

Wear lives where it happens. The slave's depth is a field on the slave's nodes (the contact
points themselves, row 0 of ``wear_depth``). The master's depth is a field on the master's
nodes (:attr:`SlidingState.master_wear`): after each increment the wear the points did to
their partner (row 1) is spread over the master nodes they were paired with, with the
mortar weights, so that the worn volume is conserved; at every re-pairing row 1 is read
back from that field at the points' new partners. The gap a point sees is thus its own
worn depth plus its partner's current worn surface at the current position.

``mode``: "small" (fixed pairing), "finite" (re-pair as the bodies slide) or "auto": small
sliding until some pressed point has slid by one master element since the pairing, finite
sliding from then on. Finite strains and rotations are not modelled: normals and the gap
are measured along the undeformed surfaces' normals (finite sliding, small deformation).
Units: mm, N, MPa.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from contact.assembly import Assembly
from contact.interface import Pairing, kinematic_operator, pair_surfaces
from contact.law import ContactLaw, ContactState
from contact.mortar import facet_measures
from contact.solver import ContactSolver, ConvergenceError, Effects, Equilibrium, NewtonSettings
from contact.sparse import space_of
from contact.structure import ContactSpace
from reduction.errors import InputError

SLIDING_MODES = ("auto", "small", "finite")


@dataclass(frozen=True)
class SlidingState(ContactState):
    """A :class:`contact.law.ContactState` whose master wear lives on the master's surface.

    master_wear: (n_master_nodes,) mm, the master body's wear depth at its own nodes, or None
        while the pairing is fixed (row 1 of ``wear_depth`` then holds it at the points).
    paired_at: (n_dofs,) mm, the retained displacements the current pairing was made at, or
        None for the initial pairing: with it a checkpointed run resumes on the same pairing.
    """

    master_wear: np.ndarray | None = None
    paired_at: np.ndarray | None = None


def sliding_state(state: ContactState) -> SlidingState:
    """The same history as a :class:`SlidingState` (no master field yet)."""
    if isinstance(state, SlidingState):
        return state
    return SlidingState(**{f.name: getattr(state, f.name) for f in fields(ContactState)})


def worn_volumes(pairing: Pairing, state: ContactState) -> tuple[float, float]:
    """Worn volume of the slave and of the master body, mm³ (mm² per mm in 2D)."""
    if state.wear_depth is None:
        return 0.0, 0.0
    slave = float(np.sum(state.wear_depth[0] * pairing.area))
    master_field = getattr(state, "master_wear", None)
    if master_field is None:
        return slave, float(np.sum(state.wear_depth[1] * pairing.area))
    return slave, float(np.sum(master_field * pairing.master.area))


def master_wear_field(pairing: Pairing, wear_at_points: np.ndarray) -> np.ndarray:
    """Spread a master wear depth given at the points (n,) onto the master nodes, mm.

    Point j's worn volume A_j·r_j goes to its partners k in proportion to the mortar (or
    projection) weights and is divided by the master nodes' areas: volume is conserved.
    Removed material only: the dual mortar weights are negative at some partners (the dual
    shape functions change sign), which left nodes just outside a worn scar with a negative
    depth (-4.5e-9 mm, the flat of tests/contact/test_sliding.py). Those are set to zero and
    the rest scaled by the volume they held (a relative change of that order), so the field
    stays the mortar transfer, conserves volume, and wear never adds material.
    """
    volume = np.zeros(pairing.master.nodes.size)
    np.add.at(volume, pairing.master_nodes.ravel(),
              (pairing.weights * (pairing.area * wear_at_points)[:, None]).ravel())
    removed = np.maximum(volume, 0.0)
    total, kept = volume.sum(), removed.sum()
    if total > 0.0 and kept > total:
        removed *= total / kept
    return removed / pairing.master.area


def master_wear_at_points(pairing: Pairing, master_wear: np.ndarray) -> np.ndarray:
    """The master's wear depth (n_master,) read at every point's partners, (n,) mm: an average
    with the positive part of each point's weights (scaled to their sum, so a uniform depth
    reads as itself). The dual mortar weights themselves, negative at some partners, read
    the field of the shipped cylinder-on-plane as -33 nm deep just outside its scar."""
    weights = np.maximum(pairing.weights, 0.0)
    total, kept = pairing.weights.sum(axis=1), weights.sum(axis=1)
    weights *= np.divide(total, kept, out=np.zeros_like(total), where=kept > 0.0)[:, None]
    return np.einsum("nk,nk->n", weights, master_wear[pairing.master_nodes])


def _tributary_area(surface) -> np.ndarray:
    """Nodal tributary areas (mm², or mm in 2D) of a surface at its current coordinates."""
    measure = facet_measures(surface.coordinates, surface.facets)
    area = np.zeros(surface.nodes.size)
    k = surface.facets.shape[1]
    np.add.at(area, surface.facets.ravel(), np.repeat(measure / k, k))
    return area


def _element_size(pairing: Pairing) -> np.ndarray:
    """Master element size (mm) seen by every point: nodal tributary length (2D) or √area."""
    master = pairing.master
    size = master.area if master.dim == 2 else np.sqrt(master.area)
    # A tributary length is half an element at the ends of the surface, about one inside.
    return np.einsum("nk,nk->n", pairing.weights, size[pairing.master_nodes])


class SlidingSolver:
    """A contact solver whose pairing follows the bodies (see the module).

    It offers what :func:`contact.procedure.run` uses of a :class:`ContactSolver`
    (``increment``, ``space``, ``law``, ``settings``, ``area``, ``n_points``, ...), so it can
    stand in for one. ``space``: the contact space of the assembly's pairing, when the caller
    has already built it. ``method``: how the surfaces are re-paired (mortar is right once
    the meshes have slid off each other's nodes). ``listeners`` are called with the new :class:`ContactSpace` after every
    re-pairing (an energy meter must follow it). ``repair_fraction``: re-pair once a pressed
    point has slid by this fraction of a master element since the last pairing.
    """

    def __init__(self, assembly: Assembly, law: ContactLaw, settings: NewtonSettings = NewtonSettings(), *,
                 mode: str = "auto", method: str = "mortar", repair_fraction: float = 0.2,
                 space: ContactSpace | None = None):
        if mode not in SLIDING_MODES:
            raise InputError(f"sliding must be one of {', '.join(SLIDING_MODES)}, got {mode!r}")
        self.assembly, self.law, self.settings = assembly, law, settings
        self.mode, self.method, self.repair_fraction = mode, method, repair_fraction
        self.finite = mode == "finite"
        if self.finite and assembly.structure.bolts is not None:
            raise InputError("finite sliding with bolts is not supported: locking the bolts "
                             "rebuilds the solver without the re-pairing")
        self.repairs = 0
        self.listeners: list = []
        dim = assembly.pairing.normal.shape[1]
        self._dofs = {}
        for role, name in (("slave", assembly.slave_body), ("master", assembly.master_body)):
            surface = getattr(assembly.pairing, role)
            offset = assembly.bodies[name].offset
            self._dofs[role] = offset + np.arange(surface.nodes.size * dim).reshape(-1, dim)
        self._reference_gap = self._geometric_gap(assembly.pairing)
        self._use(assembly.pairing, np.zeros(assembly.structure.n_dofs), space)

    # -- what the procedure reads of a solver ------------------------------------------
    @property
    def space(self) -> ContactSpace:
        return self.solver.space

    @property
    def area(self) -> np.ndarray:
        return self.solver.area

    @property
    def n_points(self) -> int:
        return self.solver.n_points

    def initial_equilibrium(self) -> Equilibrium:
        return self.solver.initial_equilibrium()

    def forget_cached_factorisations(self) -> None:
        """Also forgets the cyclic predictors: a re-pairing starts a new solver without them,
        and a resumed run re-pairs, so an uninterrupted run must forget them here too."""
        self.solver.forget_cached_factorisations()
        self.solver.recall_predictors({})

    def at_checkpoint(self) -> None:
        self.forget_cached_factorisations()

    def predictor_memory(self) -> dict:
        return {}

    def linear_memory(self) -> dict:
        return {}

    def recall_linear(self, memory: dict) -> None:
        pass

    def recall_predictors(self, memory: dict) -> None:
        self.solver.recall_predictors(memory)

    def summary(self) -> dict:
        """How the pairing was handled, for the run summary."""
        return {"sliding": "finite" if self.finite else "small", "sliding_mode": self.mode,
                "repairings": self.repairs, "pairing": self.pairing.method}

    # -- re-pairing --------------------------------------------------------------------
    def _geometric_gap(self, pairing: Pairing) -> np.ndarray:
        """Overclosure (n,) mm of the undeformed surfaces along the pairing's weights and normals."""
        nodes, weights = pairing.slave_side()
        reference = self.assembly.pairing
        position = (np.einsum("nk,nkd->nd", weights, reference.slave.coordinates[nodes])
                    - np.einsum("nk,nkd->nd", pairing.weights, reference.master.coordinates[pairing.master_nodes]))
        return np.einsum("nd,nd->n", position, pairing.normal)

    def _use(self, pairing: Pairing, displacement: np.ndarray, space: ContactSpace | None = None) -> None:
        structure = self.assembly.structure
        if pairing is not self.assembly.pairing:
            G = kinematic_operator(pairing, self._dofs["slave"], self._dofs["master"], structure.n_dofs)
            # every re-pairing eliminates all DOFs of both surfaces, paired or not: the
            # re-paired spaces then share the bodies' factor (ContactSpace.repaired)
            surfaces = np.concatenate([self._dofs["slave"].ravel(), self._dofs["master"].ravel()])
            structure = replace(structure, contact_operator=G, area=pairing.area,
                                initial_overclosure=pairing.initial_overclosure, surface_dofs=surfaces)
        if space is None:
            # the same bodies (dense or sparse) with the new pairing
            space = self.solver.space.repaired(structure) if hasattr(self, "solver") else space_of(structure)
        self.pairing, self.paired_at = pairing, displacement
        self.solver = ContactSolver(space, self.law, self.settings)
        self.element_size = _element_size(pairing)
        for listener in self.listeners:
            listener(self.solver.space)

    def _slid(self, displacement: np.ndarray, start: Equilibrium) -> float:
        """Largest tangential motion of a pressed point since the pairing, in master elements."""
        rows = self.space.structure.contact_operator @ (displacement - self.paired_at)
        tangential = np.linalg.norm(rows.reshape(self.n_points, -1)[:, 1:], axis=1)
        pressed = start.forces.reshape(self.n_points, -1)[:, 0] > 0.0
        return float(np.max(tangential[pressed] / self.element_size[pressed], initial=0.0))

    def _repair(self, displacement: np.ndarray, start: Equilibrium, state: SlidingState):
        reference = self.assembly.pairing
        moved = {role: replace(getattr(reference, role), coordinates=getattr(reference, role).coordinates
                               + displacement[self._dofs[role]]) for role in ("slave", "master")}
        try:
            pairing = pair_surfaces(moved["slave"], moved["master"], method=self.method)
        except InputError:
            # the selections paired at build time: what the bodies did since parted them
            raise ConvergenceError(self._separated(displacement, state), cause="separated") from None
        # The gap of the undeformed surfaces along the new pairing, plus any gap the scene
        # gave instead of the geometric one (an analytic profile on flat meshes).
        gap = self._geometric_gap(pairing) + reference.initial_overclosure - self._reference_gap
        # Areas are measured on the undeformed slave (small strain): the mortar integrals of
        # the deformed one are rescaled node by node.
        area = pairing.area * reference.slave.area / _tributary_area(moved["slave"])
        pairing = replace(pairing, slave=reference.slave, master=reference.master, initial_overclosure=gap,
                          point_area=area)
        self._use(pairing, displacement.copy())
        self.repairs += 1
        state = replace(state, paired_at=self.paired_at)
        # Surface nodes no point is paired with are control DOFs of the contact space, so
        # the control vector is re-read from the displacements as well as the kinematics.
        start = replace(start, kinematics=self.space.structure.contact_operator @ displacement,
                        control=displacement[self.space.control_dofs])
        if state.master_wear is not None:
            wear = state.wear_depth.copy()
            wear[1] = master_wear_at_points(pairing, state.master_wear)
            state = replace(state, wear_depth=wear)
        return start, state

    def _separated(self, displacement: np.ndarray, state: SlidingState) -> str:
        """Why a re-pairing found the surfaces apart, with how far the slave moved relative to the
        master, along the surface and across it, and how deep the surfaces wore (mm)."""
        normal = self.assembly.pairing.normal
        moved = displacement[self._dofs["slave"]] - displacement[self._dofs["master"]].mean(axis=0)
        across = np.einsum("nd,nd->n", moved, normal)
        along = np.linalg.norm(moved - across[:, None] * normal, axis=1)
        worn = 0.0 if state.wear_depth is None else float(np.max(state.wear_depth.sum(axis=0), initial=0.0))
        return (f"the contact surfaces no longer face each other: re-paired where the bodies have moved, no master "
                f"facet faces a slave facet; relative to the master the slave moved up to "
                f"{np.max(along, initial=0.0):.3g} mm along the surface and {np.max(np.abs(across), initial=0.0):.3g} "
                "mm across it" + (f", and the surfaces wore up to {worn:.3g} mm" if worn > 0.0 else "")
                + ": they slid or wore apart (a motion or load far larger than meant, a µm value given in mm, a "
                "contact stiffness far too low, or more wear cycles than the surfaces are deep)")

    def _resume_pairing(self, state: SlidingState) -> None:
        """Take up the pairing a state was solved on (a run resumed from a checkpoint)."""
        self.finite = True
        rows = self.n_points
        start = Equilibrium(np.zeros(rows * self.space.structure.dim), np.zeros(self.space.n_control),
                            np.zeros(rows * self.space.structure.dim), np.zeros(0))
        self._repair(state.paired_at, start, replace(state, master_wear=None))

    def increment(self, start: Equilibrium, state: ContactState, amplitudes: np.ndarray, effects: Effects,
                  position: tuple[int, int] | None = None):
        """:meth:`ContactSolver.increment`, re-pairing first where the bodies have slid."""
        state = sliding_state(state)
        if state.paired_at is not None and not np.array_equal(state.paired_at, self.paired_at):
            self._resume_pairing(state)
        if self.mode != "small":
            displacement = self.space.displacements(start.control, start.forces, start.amplitudes)
            slid = self._slid(displacement, start)
            if not self.finite and slid > 1.0 and self.assembly.structure.bolts is None:
                self.finite = True
            if self.finite and state.wear_depth is not None and state.master_wear is None:
                state = replace(state, master_wear=master_wear_field(self.pairing, state.wear_depth[1]))
            if self.finite and slid > self.repair_fraction:
                start, state = self._repair(displacement, start, state)
        equilibrium, new_state, status, stats = self.solver.increment(start, state, amplitudes, effects, position)
        if new_state.master_wear is not None and effects.wear:
            added = new_state.wear_depth[1] - state.wear_depth[1]
            new_state = replace(new_state, master_wear=new_state.master_wear
                                + master_wear_field(self.pairing, added))
        return equilibrium, new_state, status, stats
