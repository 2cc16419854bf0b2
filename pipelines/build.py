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
from contact.law import ContactLaw, ContactState
from contact.procedure import LoadProgram, Procedure
from contact.solver import NewtonSettings
from contact.tabulated import TabulatedProgram
from pipelines import coupling as coupling_
from pipelines import meshes
from pipelines.scene import MULTIBODY_EFFECTS, Scene
from pipelines.stages import StageCache
from reduction.body_loads import centrifugal, gravity
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError

AXES = {"x": 0, "y": 1, "z": 2}
COMPONENTS = {"ux": 0, "uy": 1, "uz": 2}


@dataclass(frozen=True)
class Model:
    """Everything a run needs, built from a scene."""

    scene: Scene
    assembly: Assembly
    law: ContactLaw
    program: LoadProgram
    procedure: Procedure
    settings: NewtonSettings
    meshes: dict
    coupling: "Coupled | None" = None

    def initial_state(self) -> ContactState:
        n_tangent = self.scene.dimension - 1
        wear_bodies = 2 if "wear" in self.scene.effects else None
        return ContactState.initial(self.assembly.structure.n_points, n_tangent,
                                    self.scene.data["contact"]["cof_initial"], wear_bodies)


@dataclass(frozen=True)
class Coupled:
    """The multibody side of a coupled scene: settings, the multibody run, the cycle histories."""

    settings: coupling_.CouplingSettings
    loading: coupling_.MultibodyLoading
    cycle: coupling_.CycleLoading
    patterns: tuple

    def summary(self) -> dict:
        return {"wing_amplitude_mm": self.cycle.wing_amplitude,
                "multibody_wing_amplitude_mm": self.cycle.multibody_wing_amplitude,
                "vibration_scale": self.cycle.scale, "load_cycle": self.cycle.cycle,
                "load_cycle_frequency_hz": self.cycle.frequency_hz, "engine_speed_rpm": self.loading.speed_rpm}


def multibody_params(scene: Scene):
    """mbs.ModelParams of a coupled scene: its [mbs] table with the scene's multibody effects."""
    from mbs.scene import model_params_from_mapping

    table = dict(scene.section("mbs"))
    table["effects"] = sorted(set(scene.effects) & set(MULTIBODY_EFFECTS))
    base = scene.path.parent if scene.path else Path(".")
    return model_params_from_mapping(table, where="[mbs]", folder=base)


def multibody_loading(scene: Scene, cache: StageCache | None = None) -> coupling_.MultibodyLoading:
    """The multibody stage of a coupled scene (read from the cache when its inputs are unchanged)."""
    params = multibody_params(scene)
    counterweight = scene.data["coupling"].get("counterweight", 1)
    cache = cache or StageCache(None)
    return cache.get("multibody", {"params": params, "counterweight": counterweight},
                     lambda: coupling_.run_multibody(params, counterweight))


def coupling_settings(scene: Scene) -> coupling_.CouplingSettings:
    table = scene.data["coupling"]
    return coupling_.CouplingSettings(body=table["body"], counterweight=table.get("counterweight", 1),
                                      cycle=table.get("cycle", "wing_period"),
                                      wing_amplitude=table.get("wing_amplitude"),
                                      fields=table.get("fields", "all"))


def _coupled_patterns(scene: Scene, elastic, mesh, loading) -> dict:
    """The CW's unit inertia patterns that the scene's effects call for."""
    geometry = loading.geometry
    low, high = mesh.p.min(axis=1), mesh.p.max(axis=1)
    expected_low = np.array([-0.5 * geometry["width"], 0.0, -0.5 * geometry["thickness"]])
    expected_high = np.array([0.5 * geometry["width"], geometry["height"], 0.5 * geometry["thickness"]])
    if not (np.allclose(low, expected_low, atol=1e-6 * geometry["width"])
            and np.allclose(high, expected_high, atol=1e-6 * geometry["width"])):
        raise InputError(f"'coupling.body' mesh spans {low.round(3).tolist()} … {high.round(3).tolist()} mm, but "
                         f"the multibody counterweight spans {expected_low.tolist()} … {expected_high.tolist()} mm "
                         "in its frame (contact face y = 0): give both the same geometry ([mbs.counterweight])")
    if scene.data["coupling"].get("fields", "all") == "wing_mode":
        patterns = {}
        if "centrifugal" in scene.effects:
            patterns["centrifugal"] = coupling_.centrifugal_pattern(elastic, loading)
        if "flexible_counterweight" in scene.effects:
            face = np.flatnonzero(np.abs(mesh.p[1]) < 1e-6 * geometry["height"])
            patterns["wing_mode"] = coupling_.wing_mode_pattern(elastic, loading, face)
        return patterns
    patterns = coupling_.inertia_patterns(elastic, loading)
    keep = {name for name in patterns if name.startswith(("frame_", "alpha_"))}
    if "centrifugal" in scene.effects:
        keep.add("spin_squared")
    if "flexible_counterweight" in scene.effects:
        keep |= {name for name in patterns if name.startswith(("mode_", "coriolis_"))}
    return {name: patterns[name] for name in patterns if name in keep}


def coupled_program(model: "Model", wing_amplitude: float | None = None) -> "Model":
    """The model with its cycle histories rebuilt for another wing amplitude (mm; None: the
    multibody amplitude). Nothing is re-condensed: the patterns are per unit history value."""
    coupled = model.coupling
    settings = replace(coupled.settings, wing_amplitude=wing_amplitude)
    cycle = coupling_.cycle_loading(coupled.loading, settings, model.procedure.increments_per_cycle)
    tables = {name: cycle.tables[name] for name in coupled.patterns}
    if "centrifugal" not in model.scene.effects:  # the spin's mean belongs to the centrifugal effect
        tables = {name: values - values.mean() if name.startswith("frame_") else values
                  for name, values in tables.items()}
    program = TabulatedProgram(model.program.patterns, model.program.shapes, model.program.held, tables)
    return replace(model, program=program, coupling=Coupled(settings, coupled.loading, cycle, coupled.patterns))


def select_points(coordinates: np.ndarray, selection: dict, where: str, sets=None) -> np.ndarray:
    """Boolean mask of points (n, dim): a named node set of the mesh file (``sets``, a
    :class:`reduction.mesh_io.MeshModel`), a box, a union of boxes, a ring or a plane (mm,
    tolerance 1e-6·size)."""
    if "set" in selection:
        if sets is None:
            raise InputError(f"'{where}.set' names a node set, but the body's mesh is generated, "
                             "not read from a file with named sets")
        mask = np.zeros(len(coordinates), dtype=bool)
        mask[sets.node_set(selection["set"])] = True
        return mask
    if "box" in selection or "boxes" in selection:
        mask = np.zeros(len(coordinates), dtype=bool)
        for box in ([selection["box"]] if "box" in selection else selection["boxes"]):
            low, high = (np.asarray(c, dtype=float) for c in box)
            mask |= np.all((coordinates >= low) & (coordinates <= high), axis=1)
        return mask
    span = float(np.ptp(coordinates)) or 1.0
    if "ring" in selection:
        ring = selection["ring"]
        axis = AXES[ring["axis"]]
        offset = coordinates - np.asarray(ring["center"], dtype=float)
        radial = np.linalg.norm(np.delete(offset, axis, axis=1), axis=1)
        on_plane = np.abs(offset[:, axis]) <= ring.get("tolerance", 1e-6 * span)
        return on_plane & (radial >= ring["inner_radius"] - 1e-9) & (radial <= ring["outer_radius"] + 1e-9)
    axis = AXES[selection["axis"]]
    tolerance = selection.get("tolerance", 1e-6 * span)
    return np.abs(coordinates[:, axis] - selection["value"]) <= tolerance


def select_nodes(mesh, selection: dict, where: str, sets=None) -> np.ndarray:
    nodes = np.flatnonzero(select_points(mesh.p.T, selection, where, sets))
    if nodes.size == 0:
        raise InputError(f"'{where}' selects no nodes of the mesh; check its coordinates")
    return nodes


def select_facets(mesh, selection: dict, where: str, sets=None) -> np.ndarray:
    """Boundary facets whose nodes all lie in the selection."""
    boundary = mesh.boundary_facets()
    inside = select_points(mesh.p.T, selection, where, sets)
    facets = boundary[np.all(inside[mesh.facets[:, boundary]], axis=0)]
    if facets.size == 0:
        raise InputError(f"'{where}' selects no boundary facets of the mesh; check the box or plane")
    return facets


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
        from reduction.mesh_io import read_mesh
    except ImportError:
        raise InputError(f"'{where}.file': reading mesh files needs reduction.mesh_io, "
                         "which is not available in this installation") from None
    if not path.is_file():
        raise InputError(f"'{where}.file': {path} does not exist")
    model = read_mesh(path)
    return model.mesh, model


def build(scene: Scene, meshes_override: dict | None = None, *, cache: StageCache | None = None,
          multibody: "coupling_.MultibodyLoading | None" = None) -> Model:
    """Assemble and condense the scene's bodies and read its law, loads and procedure.

    meshes_override: body name → scikit-fem mesh used instead of the scene's (e.g. a mesh
    whose surface was moved by wear). cache: where the multibody stage of a coupled scene is
    kept (None: always computed); multibody: its result when the caller already has it.
    """
    data = scene.data
    coupled_body = data.get("coupling", {}).get("body")
    loading = (multibody or multibody_loading(scene, cache)) if coupled_body else None
    coupled_patterns = ()
    dim = scene.dimension
    base = scene.path.parent if scene.path else None
    bodies, built_meshes, named_sets = [], {}, {}
    for name, spec in data["bodies"].items():
        override = (meshes_override or {}).get(name)
        if override is None or "file" in spec["mesh"]:
            mesh, sets = make_mesh(spec["mesh"], f"bodies.{name}.mesh", base)
        else:
            sets = None
        mesh = mesh if override is None else override
        named_sets[name] = sets
        if mesh.dim() != dim:
            raise InputError(f"'bodies.{name}.mesh' is {mesh.dim()}D but the scene is {dim}D")
        built_meshes[name] = mesh
        material = data["materials"][spec["material"]]
        elastic = assemble_elastic_body(mesh, material["youngs_modulus"], material["poisson_ratio"],
                                        material.get("density"))
        fixed = spec.get("fixed")
        fixed_nodes = (select_nodes(mesh, fixed["nodes"], f"bodies.{name}.fixed.nodes", sets) if fixed
                       else np.zeros(0, int))
        components = tuple(COMPONENTS[c] for c in (fixed or {}).get("components", ["ux", "uy", "uz"][:dim]))
        references = {}
        for ref_name, ref in spec.get("reference_points", {}).items():
            nodes = select_nodes(mesh, ref["nodes"], f"bodies.{name}.reference_points.{ref_name}.nodes", sets)
            references[ref_name] = ReferencePoint(nodes, np.asarray(ref["position"], float),
                                                  bool(ref.get("rotations", False)))
        body_loads = {}
        for entry in data.get("body_loads", []):
            if entry["body"] != name:
                continue
            if entry["kind"] == "gravity":
                body_loads[entry["name"]] = gravity(elastic, entry["acceleration"])
            else:
                omega = entry["angular_velocity"]
                body_loads[entry["name"]] = centrifugal(elastic, omega[0] if dim == 2 else omega,
                                                        entry.get("axis_point"))
        if name == coupled_body:
            inertia = _coupled_patterns(scene, elastic, mesh, loading)
            body_loads.update(inertia)
            coupled_patterns = tuple(inertia)
        bodies.append(Body(name, elastic, fixed_nodes, components, references, body_loads))
    contact = data["contact"]
    slave_mesh = built_meshes[contact["slave"]["body"]]
    master_mesh = built_meshes[contact["master"]["body"]]
    slave = (contact["slave"]["body"], select_facets(slave_mesh, contact["slave"], "contact.slave",
                                                     named_sets[contact["slave"]["body"]]))
    master = (contact["master"]["body"], select_facets(master_mesh, contact["master"], "contact.master",
                                                       named_sets[contact["master"]["body"]]))

    def patterns(kind):
        out = {}
        for entry in data.get(kind, []):
            body, point, comp = entry["dof"].split(".")
            out[entry["name"]] = [(body, point, comp, float(entry["value"]))]
        return out

    bolts = tuple(Bolt(name, spec["head"], spec["nut"], np.asarray(spec["axis"], float),
                       float(spec["stiffness"]), float(spec["pretension"]))
                  for name, spec in data.get("bolts", {}).items()) if "bolts" in scene.effects else ()
    assembly = assemble(bodies, slave, master, loads=patterns("loads"), motions=patterns("motions"),
                        search_distance=contact.get("search_distance", np.inf), bolts=bolts,
                        pairing=contact.get("pairing", "auto"))
    shapes = {e["name"]: e["history"] for kind in ("loads", "motions", "body_loads") for e in data.get(kind, [])}
    shapes.update({f"bolt.{bolt.name}": "ramp" for bolt in bolts})
    shapes.update({name: "history" for name in coupled_patterns})
    program = LoadProgram(assembly.structure.patterns, shapes)
    law = ContactLaw(
        normal_stiffness=contact["normal_stiffness"],
        critical_slip=contact["critical_slip"],
        cof_max=contact["cof_max"],
        cof_rate=contact.get("cof_rate", 0.0) if "cof_evolution" in scene.effects else 0.0,
        wear_coefficients=tuple(contact.get("wear_coefficients", [0.0, 0.0])),
        pressure_limit=contact.get("pressure_limit", 0.0),
        wear_form=contact.get("wear_form", "pressure"),
    )
    proc = data.get("procedure", {})
    procedure = Procedure(**{k: v for k, v in proc.items()
                             if k in Procedure.__dataclass_fields__})
    settings = NewtonSettings(wear_cap=proc.get("wear_cap", np.inf),
                              max_cutbacks=proc.get("max_cutbacks", NewtonSettings.max_cutbacks))
    model = Model(scene, assembly, law, program, procedure, settings, built_meshes)
    if coupled_body is None:
        return model
    model = replace(model, coupling=Coupled(coupling_settings(scene), loading, None, coupled_patterns))
    return coupled_program(model, model.coupling.settings.wing_amplitude)
