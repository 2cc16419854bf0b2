"""Build the physics objects of a validated :class:`pipelines.scene.Scene`.

Meshes come from the shipped generators or from files (meshio through ``reduction``);
bodies are assembled and condensed; the contact law, the load program and the procedure
are read from the scene. Only what the scene's effects call for is created.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from contact.bolts import Bolt
from contact.assembly import Assembly, Body, ReferencePoint, assemble
from contact.interface import surface_from_facets
from contact.law import ContactLaw, ContactState
from contact.procedure import LoadProgram, Procedure
from contact.solver import NewtonSettings
from contact.sparse import decide_path, space_of
from pipelines.coupling import Coupled, CouplingSettings, coupled_patterns, coupled_program, multibody_loading
from reduction.mesh import generators as meshes
from pipelines.scene import Scene
from pipelines.scene.checks import mesh_unit_problem
from pipelines.stages import StageCache
from pipelines.support import check_support
from reduction.body_loads import centrifugal, gravity
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.mesh.selection import select_body_nodes, select_facets

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
        try:
            return getattr(meshes, generator)(**args), None
        except TypeError as error:
            raise InputError(f"'{where}': {error}") from None
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
        references[ref_name] = ReferencePoint(nodes, np.asarray(ref["position"], float),
                                              bool(ref.get("rotations", False)))
    return Body(name, elastic, np.zeros(0, int), (), references, _body_loads(scene, name, elastic), tuple(supports))


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
    contact = data["contact"]
    slave, master = ((contact[role]["body"], select_facets(built_meshes[contact[role]["body"]], contact[role],
                                                           f"contact.{role}", named_sets[contact[role]["body"]]))
                     for role in ("slave", "master"))
    bolts = tuple(Bolt(name, spec["head"], spec["nut"], np.asarray(spec["axis"], float),
                       float(spec["stiffness"]), float(spec["pretension"]))
                  for name, spec in data.get("bolts", {}).items()) if "bolts" in scene.effects else ()
    slave_body = next(body for body in bodies if body.name == slave[0])
    n_points = surface_from_facets(slave_body.elastic.mesh, slave[1], "contact.slave").nodes.size
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
