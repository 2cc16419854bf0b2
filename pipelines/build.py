"""Build the physics objects of a validated :class:`pipelines.scene.Scene`.

Meshes come from the shipped generators or from files (meshio through ``reduction``);
bodies are assembled and condensed; the contact law, the load program and the procedure
are read from the scene. Only what the scene's effects call for is created.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from contact.bolts import Bolt, facets_near_axis, joint_tilt, ring_offset
from contact.assembly import Assembly, Body, ReferencePoint, assemble
from contact.interface import Surface, surface_from_facets
from contact.law import ContactLaw, ContactState
from contact.procedure import LoadProgram, Procedure
from contact.solver import NewtonSettings
from contact.sparse import decide_path, space_of
from pipelines.coupling import Coupled, CouplingSettings, coupled_patterns, coupled_program, multibody_loading
from reduction.mesh import generators as meshes
from pipelines.scene import Scene
from pipelines.scene.checks import (BOLT_NEAR_RINGS, SceneWarning, bolt_tilt_finding, mesh_unit_problem,
                                    ring_offset_finding)
from pipelines.stages import StageCache
from pipelines.support import check_support
from reduction.body_loads import centrifugal, gravity
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.mesh.selection import select_body_nodes, select_facets
from reduction.threads import one_blas_thread

COMPONENTS = {"ux": 0, "uy": 1, "uz": 2}


@dataclass(frozen=True)
class Model:
    """Everything a run needs, built from a scene.

    contact_path: "dense" (condensed bodies, dense W) or "sparse" (bodies kept whole,
    :mod:`contact.sparse`), as ``[contact] solver`` asked or chose; contact_path_reason: why,
    in words (e.g. "2,704 points ≥ 2,500").
    """

    scene: Scene
    assembly: Assembly
    law: ContactLaw
    program: LoadProgram
    procedure: Procedure
    settings: NewtonSettings
    meshes: dict
    coupling: Coupled | None = None
    contact_path: str = "dense"
    contact_path_reason: str = ""

    def contact_space(self):
        """The contact space of the model's structure on its contact path (dense or sparse)."""
        return space_of(self.assembly.structure)

    def solver(self, space=None):
        """The contact solver the scene's ``contact.sliding`` asks for, on ``space`` (default: a
        new :meth:`contact_space`): small sliding a :class:`contact.solver.ContactSolver`, else
        (default auto: the pairing follows the bodies once they slide by an element) a
        :class:`contact.sliding.SlidingSolver`. Every job and study runs the scene with it."""
        from contact.sliding import SlidingSolver
        from contact.solver import ContactSolver

        space = self.contact_space() if space is None else space
        contact = self.scene.data["contact"]
        sliding = contact.get("sliding", "auto")
        if sliding == "small":
            return ContactSolver(space, self.law, self.settings)
        method = "node_to_segment" if contact.get("pairing") == "node_to_segment" else "mortar"
        return SlidingSolver(self.assembly, self.law, self.settings, mode=sliding, method=method, space=space)

    def initial_state(self) -> ContactState:
        n_tangent = self.scene.dimension - 1
        wear_bodies = 2 if "wear" in self.scene.effects else None
        return ContactState.initial(self.assembly.structure.n_points, n_tangent,
                                    self.scene.data["contact"]["cof_initial"], wear_bodies)


def make_mesh(spec: dict, where: str, base: Path | None):
    """The body's mesh and, for a mesh file, its named sets (None for generated meshes)."""
    if "generator" in spec:
        generator = spec["generator"]
        args = {k: v for k, v in spec.items() if k != "generator"}
        given = ", ".join(f"{key} = {value!r}" for key, value in args.items())
        try:
            return getattr(meshes, generator)(**args), None
        # an optional key of the wrong type (growth = "fine"), or the generator's own geometry
        # rules (scene.checks says the 2D blocks')
        except (TypeError, InputError) as error:
            raise InputError(f"'{where}' (mesh generator {generator}: {given}): {error}") from None
    path = Path(spec["file"])
    if base is not None and not path.is_absolute():
        path = base / path
    try:
        from reduction.mesh.io import read_mesh
    except ImportError:
        raise InputError(f"'{where}.file': reading mesh files needs reduction.mesh.io, "
                         "which is not available in this installation") from None
    model = read_mesh(path, f"{where}.file")
    return model.mesh, model


def _body_mesh(scene: Scene, name: str, spec: dict, override):
    """(mesh, named sets or None) of body ``name``: ``override`` (a moved mesh) or the scene's."""
    base = scene.path.parent if scene.path else None
    sets = None
    if override is None or "file" in spec["mesh"]:
        mesh, sets = make_mesh(spec["mesh"], f"bodies.{name}.mesh", base)
    mesh = mesh if override is None else override
    if mesh.dim() != scene.dimension:
        raise InputError(f"'bodies.{name}.mesh' is {mesh.dim()}D but the scene is {scene.dimension}D")
    if sets is not None:
        problem = mesh_unit_problem(scene.data, name, mesh.p.min(axis=1), mesh.p.max(axis=1), sets.source)
        if problem:
            raise InputError(problem)
    return mesh, sets


def _body_loads(scene: Scene, name: str, elastic) -> dict:
    """The scene's gravity and centrifugal loads (N) on body ``name``."""
    loads = {}
    for entry in scene.data.get("body_loads", []):
        if entry["body"] != name:
            continue
        if entry["kind"] == "gravity":
            loads[entry["name"]] = gravity(elastic, entry["acceleration"])
        else:
            omega = entry["angular_velocity"]
            loads[entry["name"]] = centrifugal(elastic, omega[0] if scene.dimension == 2 else omega,
                                               entry.get("axis_point"))
    return loads


def _body(scene: Scene, name: str, spec: dict, mesh, sets) -> Body:
    """Body ``name``: its assembled elastic body, supports, reference points and body loads."""
    dim = scene.dimension
    material = scene.data["materials"][spec["material"]]
    elastic = assemble_elastic_body(mesh, material["youngs_modulus"], material["poisson_ratio"],
                                    material.get("density"), quadratic=bool(sets is not None and sets.serendipity))
    fixed = spec.get("fixed", [])
    tables = [("fixed", fixed)] if isinstance(fixed, dict) else [(f"fixed[{k}]", t) for k, t in enumerate(fixed)]
    nodes_of = elastic.coordinates  # every node, mid-edge nodes of quadratic elements included
    supports = [(select_body_nodes(nodes_of, mesh, table["nodes"], f"bodies.{name}.{where}.nodes", sets),
                 tuple(COMPONENTS[c] for c in table.get("components", ["ux", "uy", "uz"][:dim])))
                for where, table in tables]
    references = {}
    for ref_name, ref in spec.get("reference_points", {}).items():
        nodes = select_body_nodes(nodes_of, mesh, ref["nodes"], f"bodies.{name}.reference_points.{ref_name}.nodes",
                                  sets)
        for other, earlier in references.items():
            _check_not_shared(name, spec["reference_points"], other, earlier.nodes, ref_name, nodes)
        references[ref_name] = ReferencePoint(nodes, np.asarray(ref["position"], float),
                                              bool(ref.get("rotations", False)))
    return Body(name, elastic, np.zeros(0, int), (), references, _body_loads(scene, name, elastic), tuple(supports))


def _check_not_shared(body: str, tables: dict, first: str, first_nodes, second: str, second_nodes) -> None:
    """Two reference points of ``body`` must couple different nodes (an RBE2 node follows one
    reference point); the error names both keys and the node sets they name."""
    shared = np.intersect1d(first_nodes, second_nodes).size
    if not shared:
        return
    keys = [f"'bodies.{body}.reference_points.{point}.nodes'" for point in (first, second)]
    sets = [tables[point]["nodes"].get("set") for point in (first, second)]
    if sets[0] is not None and sets[0] == sets[1]:
        said = f"{keys[0]} and {keys[1]} both name node set '{sets[0]}'"
    else:
        named = [key + (f" (node set '{name}')" if name else "") for key, name in zip(keys, sets)]
        said = f"{named[0]} and {named[1]} select {shared} of the same nodes"
    raise InputError(f"{said}: a node follows one reference point only; give each reference point its own nodes")


def _check_bolt_geometry(scene: Scene, bodies: list[Body], slave: Surface) -> None:
    """Each bolt against the mesh (:mod:`pipelines.scene.checks`: thresholds and why): its
    axis against the joint's normal where it clamps, the area-weighted mean normal of the slave
    surface's facets within :data:`BOLT_NEAR_RINGS` ring radii of its axis (the whole surface if
    none lies so near), and each end's reference point against the centre of the nodes it
    couples. Refusals raise one :class:`InputError`; warnings are :class:`SceneWarning`."""
    by_name = {body.name: body for body in bodies}
    centroids = slave.coordinates[slave.facets].mean(axis=1)
    weights = slave.area[slave.facets].mean(axis=1)  # the facets' share of the tributary areas
    problems, found = [], []
    for name, spec in scene.data["bolts"].items():
        axis = np.asarray(spec["axis"], float)
        radii, positions = [], []
        for end in ("head", "nut"):
            body_name, point = spec[end].split(".")
            reference = by_name[body_name].reference_points[point]
            ring = ring_offset(by_name[body_name].elastic.coordinates[reference.nodes], reference.position, axis)
            problem, warning = ring_offset_finding(f"bodies.{body_name}.reference_points.{point}",
                                                   reference.position, ring)
            problems += [problem] if problem else []
            found += [warning] if warning else []
            radii.append(ring.radius)
            positions.append(reference.position)
        reach = BOLT_NEAR_RINGS * max(radii)
        near = facets_near_axis(centroids, positions[0], axis, reach)
        where = (f"mean over the {near.sum()} contact facets within {reach:.3g} mm of its axis" if near.any() else
                 f"mean over the whole contact surface, none of whose facets lies within {reach:.3g} mm of its axis")
        near = near if near.any() else np.ones_like(near)
        problem, warning = bolt_tilt_finding(name, joint_tilt(axis, slave.facet_normals[near], weights[near]),
                                             where, float(scene.data["contact"]["cof_initial"]))
        problems += [problem] if problem else []
        found += [warning] if warning else []
    if problems:
        raise InputError("; ".join(problems))
    for message in found:
        warnings.warn(message, SceneWarning, stacklevel=3)


def _control_patterns(scene: Scene, kind: str) -> dict:
    """Patterns of ``[[loads]]`` or ``[[motions]]``: name → [(body, point, component, value)]."""
    out = {}
    for entry in scene.data.get(kind, []):
        body, point, comp = entry["dof"].split(".")
        out[entry["name"]] = [(body, point, comp, float(entry["value"]))]
    return out


def _law(scene: Scene) -> ContactLaw:
    contact = scene.data["contact"]
    return ContactLaw(
        normal_stiffness=contact["normal_stiffness"],
        critical_slip=contact["critical_slip"],
        cof_max=contact["cof_max"],
        cof_rate=contact.get("cof_rate", 0.0) if "cof_evolution" in scene.effects else 0.0,
        wear_coefficients=tuple(contact.get("wear_coefficients", [0.0, 0.0])),
        pressure_limit=contact.get("pressure_limit", 0.0),
        wear_form=contact.get("wear_form", "pressure"),
    )


@one_blas_thread
def build(scene: Scene, meshes_override: dict | None = None, *, cache: StageCache | None = None,
          multibody=None) -> Model:
    """Assemble and condense the scene's bodies and read its law, loads and procedure.

    meshes_override: body name → scikit-fem mesh used instead of the scene's (e.g. a mesh
    whose surface was moved by wear). cache: where the multibody stage of a coupled scene is
    kept (None: always computed); multibody: its result when the caller already has it.
    """
    data = scene.data
    bodies, built_meshes, named_sets = [], {}, {}
    for name, spec in data["bodies"].items():
        mesh, named_sets[name] = _body_mesh(scene, name, spec, (meshes_override or {}).get(name))
        built_meshes[name] = mesh
        bodies.append(_body(scene, name, spec, mesh, named_sets[name]))
    motions = _control_patterns(scene, "motions")
    check_support(scene, bodies, motions)  # before the multibody stage and the condensation
    contact = data["contact"]
    slave, master = ((contact[role]["body"], select_facets(built_meshes[contact[role]["body"]], contact[role],
                                                           f"contact.{role}", named_sets[contact[role]["body"]]))
                     for role in ("slave", "master"))
    slave_body = next(body for body in bodies if body.name == slave[0])
    slave_surface = surface_from_facets(slave_body.elastic.mesh, slave[1], "contact.slave")
    if "bolts" in scene.effects:
        _check_bolt_geometry(scene, bodies, slave_surface)
    coupled_body = data.get("coupling", {}).get("body")
    loading = (multibody or multibody_loading(scene, cache)) if coupled_body else None
    pattern_names, condensers = (), {}
    for k, body in enumerate(bodies):
        if body.name == coupled_body:
            inertia, condenser = coupled_patterns(scene, body, built_meshes[body.name], loading)
            bodies[k] = replace(body, body_loads={**body.body_loads, **inertia})
            if condenser is not None:
                condensers[body.name] = condenser
            pattern_names = tuple(inertia)
    bolts = tuple(Bolt(name, spec["head"], spec["nut"], np.asarray(spec["axis"], float),
                       float(spec["stiffness"]), float(spec["pretension"]))
                  for name, spec in data.get("bolts", {}).items()) if "bolts" in scene.effects else ()
    n_points = slave_surface.nodes.size
    path, reason = decide_path(contact.get("solver", "auto"), n_points, scene.dimension)
    assembly = assemble(bodies, slave, master, loads=_control_patterns(scene, "loads"),
                        motions=motions,
                        search_distance=contact.get("search_distance", np.inf), bolts=bolts,
                        pairing=contact.get("pairing", "auto"), condensers=condensers,
                        keep_interior=path == "sparse")
    shapes = {e["name"]: e["history"] for kind in ("loads", "motions", "body_loads") for e in data.get(kind, [])}
    shapes.update({f"bolt.{bolt.name}": "ramp" for bolt in bolts})
    shapes.update({name: "history" for name in pattern_names})
    program = LoadProgram(assembly.structure.patterns, shapes)
    proc = data.get("procedure", {})
    procedure = Procedure(**{k: v for k, v in proc.items()
                             if k in Procedure.__dataclass_fields__})
    settings = NewtonSettings(wear_cap=proc.get("wear_cap", np.inf),
                              max_cutbacks=proc.get("max_cutbacks", NewtonSettings.max_cutbacks))
    model = Model(scene, assembly, _law(scene), program, procedure, settings, built_meshes,
                  contact_path=path, contact_path_reason=reason)
    if coupled_body is None:
        return model
    model = replace(model, coupling=Coupled(CouplingSettings.of(scene), loading, None, pattern_names))
    return coupled_program(model, model.coupling.settings.wing_amplitude)
