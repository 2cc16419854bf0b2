"""The scene's ``[coupling]`` table: one-way coupling of the multibody run to the CW–web contact.

The multibody run (:func:`mbs.loading.counterweight_loading`, cached as stage ``multibody``)
gives, for one counterweight (CW), the motion of its interface frame and its Craig–Bampton
modal coordinates. The contact model is quasi-static in that frame: the CW carries the
d'Alembert load of its absolute acceleration field, one load pattern per term, condensed once
with the CW (:mod:`reduction.modal_loads`) and scaled in time by its history over one contact
load cycle (:func:`mbs.loading.cycle_loading`); the web is held at its far face (the web is
the moving reference frame; its own deformation is not modelled). Contact does not feed back
into the multibody run.

The fields are exact for the multibody CW: held at its face, a CW of the same geometry deforms
under them as the multibody CW vibrates (tested: torsion-mode coordinate within 5 %). The
contact CW may differ from the multibody one in details (the generic joint's screw holes make
it 15 % softer in torsion): its response to the same fields differs accordingly.

Two field sets (``fields``): ``all`` (the default) is the complete acceleration field;
``wing_mode`` is the paper's CW loading ("bolt forces and centrifugal force constant, the wing
vibration sinusoidal"): the steady centrifugal load plus the elastic load of the wing torsion
mode, normalised so that the CW with its contact face held twists its wings by exactly the
wing torsion history (mm). ``all`` carries the CW's whole rigid-body motion at the vibration
frequency as well (for the generic throw at 375 Hz its radial acceleration loads the joint as
much as the torsion itself), ``wing_mode`` isolates the mode the paper's limit is stated for.

Units: mm, N, t, s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from contact.tabulated import TabulatedProgram
from mbs.loading import CycleLoading, MultibodyLoading, counterweight_loading, cycle_loading
from pipelines.scene import Scene
from pipelines.scene.checks import mesh_unit_problem
from pipelines.scene.schema import MULTIBODY_EFFECTS
from pipelines.stages import StageCache
from reduction import modal_loads
from reduction.condensation import BoundarySchur, boundary_schur, condense_from_boundary
from reduction.errors import InputError
from reduction.threads import one_blas_thread


@dataclass(frozen=True)
class CouplingSettings:
    """The scene's ``[coupling]`` table.

    body: contact body that is the counterweight. counterweight: which CW of the multibody
    model (1 = journal-1 side of throw 1). cycle: "wing_period" or "revolution".
    wing_amplitude: mm, or None for the multibody amplitude at the engine speed.
    fields: "all" or "wing_mode". histories: an interface-histories file (relative to the scene)
    read instead of running the multibody model (:mod:`mbs.histories_file`).
    """

    body: str
    counterweight: int = 1
    cycle: str = "wing_period"
    wing_amplitude: float | None = None
    fields: str = "all"
    histories: str | None = None

    @classmethod
    def of(cls, scene: Scene) -> "CouplingSettings":
        """The settings of a coupled scene, defaults for the keys it leaves out."""
        return cls(**scene.data["coupling"])


@dataclass(frozen=True)
class Coupled:
    """The multibody side of a coupled scene: settings, the multibody run, the cycle histories."""

    settings: CouplingSettings
    loading: MultibodyLoading
    cycle: CycleLoading | None
    patterns: tuple

    def summary(self) -> dict:
        """The coupling's figures for a run summary; ``multibody_warning`` when the multibody
        response was not steady where the wing amplitude was measured."""
        out = {"wing_amplitude_mm": self.cycle.wing_amplitude,
               "multibody_wing_amplitude_mm": self.cycle.multibody_wing_amplitude,
               "vibration_scale": self.cycle.scale, "load_cycle": self.cycle.cycle,
               "load_cycle_frequency_hz": self.cycle.frequency_hz, "engine_speed_rpm": self.loading.speed_rpm,
               "multibody_unsettled_change": self.loading.unsettled_change}
        if self.loading.unsettled is not None:
            out["multibody_warning"] = self.loading.unsettled
        return out


def multibody_params(scene: Scene):
    """mbs.ModelParams of a coupled scene: its [mbs] table with the scene's multibody effects.
    A CW body read from a mesh file is the multibody CW too (:func:`_file_counterweight`).
    A scene whose loads come from an interface-histories file is refused: the file, not the
    [mbs] model, drives it, at the one speed it was recorded at, so a multibody run, sweep or
    margin of the [mbs] table would judge another joint (its excitation switched off)."""
    from mbs.scene import model_params_from_mapping

    if scene.data.get("coupling", {}).get("histories") is not None:
        raise InputError(f"the scene's loads come from the interface-histories file "
                         f"'{scene.data['coupling']['histories']}' ([coupling] histories), recorded at one "
                         "speed: its [mbs] model does not drive them, so it cannot give a multibody run, a "
                         "speed sweep or margins; run those on the scene of the multibody model the file came "
                         "from (or on your own multibody code), and this scene for the contact at that speed")

    table = dict(scene.section("mbs"))
    table["effects"] = sorted(set(scene.effects) & set(MULTIBODY_EFFECTS))
    base = scene.path.parent if scene.path else Path(".")
    cw_table = _file_counterweight(scene, base)
    if cw_table:
        table["counterweight"] = {**table.get("counterweight", {}), **cw_table}
    return model_params_from_mapping(table, where="[mbs]", folder=base)


def _file_counterweight(scene: Scene, base: Path) -> dict:
    """[mbs.counterweight] keys that make the coupled body's mesh file the multibody CW: the file,
    its contact face (the named set that selects the body's contact surface) and its material."""
    name = scene.data["coupling"]["body"]
    body = scene.data["bodies"][name]
    if "file" not in body["mesh"]:
        return {}
    roles = [role for role in ("slave", "master") if scene.data["contact"][role]["body"] == name]
    face = scene.data["contact"][roles[0]].get("set") if roles else None
    if face is None:
        raise InputError(f"'coupling.body' '{name}' is read from a mesh file, so the multibody model reduces that "
                         f"mesh: select its contact surface by a named set ('contact.{(roles or ['slave'])[0]}.set'), "
                         "which becomes the multibody interface")
    material = scene.data["materials"][body["material"]]
    path = (base / Path(body["mesh"]["file"])).resolve()
    if not path.is_file():
        # said here, before the multibody stage reads it, in the scene's own key
        raise InputError(f"'bodies.{name}.mesh.file': {path} "
                         + ("is a folder, not a mesh file" if path.is_dir() else "does not exist"))
    _check_units(scene, name, path)
    return {"mesh_file": str(path), "interface": face,
            "youngs_modulus": material["youngs_modulus"], "poisson_ratio": material["poisson_ratio"],
            "density": material["density"]}


def histories_path(scene: Scene) -> Path | None:
    """The interface-histories file a coupled scene names (absolute), or None."""
    name = scene.data["coupling"].get("histories")
    if name is None:
        return None
    path = Path(name)
    return path if path.is_absolute() or scene.path is None else scene.path.parent / path


@one_blas_thread
def multibody_loading(scene: Scene, cache: StageCache | None = None) -> MultibodyLoading:
    """The multibody stage of a coupled scene (read from the cache when its inputs are unchanged),
    or the scene's interface-histories file."""
    path = histories_path(scene)
    if path is not None:
        from mbs.histories_file import read_interface_histories, to_loading
        from pipelines.build import make_mesh

        spec = scene.data["bodies"][scene.data["coupling"]["body"]]["mesh"]
        cw_mesh = make_mesh(spec, f"bodies.{scene.data['coupling']['body']}.mesh",
                            scene.path.parent if scene.path else None)[0]
        return to_loading(read_interface_histories(path), cw_mesh)
    params = multibody_params(scene)
    counterweight = CouplingSettings.of(scene).counterweight
    cache = cache or StageCache(None)
    return cache.get("multibody", {"params": params, "counterweight": counterweight},
                     lambda: counterweight_loading(params, counterweight))


def _check_units(scene: Scene, name: str, path: Path) -> None:
    """The CW's mesh file, which the multibody model reduces, read before the multibody run and
    its size checked against the scene's lengths for the body (reference points, selections): a
    CW in metres would make the run fail in exudyn's time integration (a body 10⁹ times too light)
    instead of here, in words (:func:`pipelines.scene.checks.mesh_unit_problem`)."""
    from reduction.mesh.io import read_mesh

    points = read_mesh(path, f"bodies.{name}.mesh.file").points
    problem = mesh_unit_problem(scene.data, name, points.min(axis=0), points.max(axis=0),
                                f"'bodies.{name}.mesh.file': {scene.data['bodies'][name]['mesh']['file']}")
    if problem:
        raise InputError(problem + " (it is the multibody counterweight too: checked before the multibody run)")


def _check_geometry(mesh, loading: MultibodyLoading) -> None:
    """The contact CW must span the multibody CW's box in its frame (contact face y = 0)."""
    if not loading.mesh_points.size:
        return
    low, high = mesh.p.min(axis=1), mesh.p.max(axis=1)
    expected_low, expected_high = loading.mesh_points.min(axis=1), loading.mesh_points.max(axis=1)
    tolerance = 1e-6 * float(np.max(expected_high - expected_low))
    if not (np.allclose(low, expected_low, atol=tolerance) and np.allclose(high, expected_high, atol=tolerance)):
        raise InputError(f"'coupling.body' mesh spans {low.round(3).tolist()} … {high.round(3).tolist()} mm, but "
                         f"the multibody counterweight spans {expected_low.tolist()} … {expected_high.tolist()} mm "
                         "in its frame (contact face y = 0): give both the same geometry ([mbs.counterweight])")


def coupled_patterns(scene: Scene, body, mesh, loading: MultibodyLoading) -> tuple[dict, SharedCondenser | None]:
    """The CW's unit inertia patterns (N per unit history value) that the scene's effects call
    for, and, for the wing-mode field, the condenser that condenses the body with the same
    factorisation that normalised the wing mode (:class:`SharedCondenser`; None otherwise).

    body: the :class:`contact.assembly.Body` of the CW (its scene loads, reference points, fixed nodes).
    """
    elastic = body.elastic
    _check_geometry(mesh, loading)
    if not loading.n_modes and "flexible_counterweight" in scene.effects:
        raise InputError("effect 'flexible_counterweight' needs the CW's modal coordinates and mode shapes, which "
                         "the interface histories do not hold")
    if CouplingSettings.of(scene).fields != "wing_mode":
        patterns = modal_loads.inertia_patterns(elastic, loading.modes)
        keep = {name for name in patterns if name.startswith(("frame_", "alpha_"))}
        if "centrifugal" in scene.effects:
            keep.add("spin_squared")
        if "flexible_counterweight" in scene.effects:
            keep |= {name for name in patterns if name.startswith(("mode_", "coriolis_"))}
        return {name: patterns[name] for name in patterns if name in keep}, None
    patterns = {}
    if "centrifugal" in scene.effects:
        patterns["centrifugal"] = modal_loads.centrifugal_pattern(
            elastic, [loading.frame_acceleration[:, k].mean() for k in range(3)],
            float(np.mean(loading.angular_velocity[:, 2] ** 2)))
    if "flexible_counterweight" not in scene.effects:
        return patterns, None
    face = np.flatnonzero(np.abs(mesh.p[1]) < 1e-6 * float(np.ptp(mesh.p, axis=1).max()))
    if not share_factorisation(body, face):
        patterns["wing_mode"] = modal_loads.wing_mode_pattern(elastic, loading.modes, loading.torsion_mode,
                                                              loading.torsion_frequency_hz, face)
        return patterns, None
    wing = modal_loads.wing_mode_load(elastic, loading.modes, loading.torsion_mode, loading.torsion_frequency_hz)
    schur = wing_mode_schur(body, face, {**body.body_loads, **patterns}, wing)
    patterns["wing_mode"] = wing / schur.torsion
    return patterns, SharedCondenser(schur.schur)


#: the shared factorisation is used while the nodes it adds to the face (coupled nodes, wing
#: tips) are at most this fraction of the face's. PARDISO's Schur phase grows about as the
#: boundary size to the power 1.7, and a second factorisation of a graded body is cheap, so a
#: larger boundary costs more than it saves. Measured on the extreme CW at 2.5 mm (one BLAS
#: thread, load ~11 on 2 cores): tensor mesh, screw heads as fine as the pads (boundary 11,000
#: DOFs against 4,800): build 420 s shared, 173 s with two factorisations; 3:1-graded mesh (heads
#: 9 % of the face): CW condensation 109 s shared, about 45 s with two factorisations
SHARE_LIMIT = 0.05


def share_factorisation(body, face: np.ndarray) -> bool:
    """Whether the CW's wing-mode normalisation and its condensation share one factorisation
    (:func:`wing_mode_schur`): when the body has no fixed nodes (the clamped case would hold them
    too) and its coupled nodes are few beside its contact face (:data:`SHARE_LIMIT`)."""
    if body.held_dofs().size:
        return False
    coupled = sum(len(point.nodes) for point in body.reference_points.values())
    return coupled <= SHARE_LIMIT * face.size


@dataclass(frozen=True)
class WingModeSchur:
    """The CW condensed onto its face, coupled nodes and wing tips (one factorisation), with the
    wing-mode load already normalised: torsion (mm) is the wing torsion of the held CW under the
    unnormalised load."""

    schur: BoundarySchur
    torsion: float


def wing_mode_schur(body, face: np.ndarray, loads: dict, wing_load: np.ndarray) -> WingModeSchur:
    """One factorisation of the CW for both of its uses (issue 14): the wing-mode normalisation
    (the CW held at its contact face ``face`` (node indices), its heads free, loaded by
    ``wing_load``) and its static condensation onto the contact surface and the reference
    points (:class:`SharedCondenser`). The boundary holds every node either problem treats
    differently: the face, the nodes coupled to reference points, the wing tips. ``loads``: the
    body's other loads (N), condensed with it."""
    elastic = body.elastic
    minus, plus = modal_loads.wing_tip_dofs(elastic)
    coupled = [np.asarray(point.nodes) for point in body.reference_points.values()]
    held = elastic.node_dofs[face].ravel()
    boundary = np.unique(np.concatenate([held, minus, plus] + [elastic.node_dofs[n].ravel() for n in coupled]))
    schur = boundary_schur(elastic.stiffness, boundary, (), {**loads, "wing_mode": wing_load})
    u = schur.clamped_response(held, "wing_mode")
    index = np.searchsorted(schur.boundary, np.concatenate([minus, plus]))
    torsion = modal_loads.wing_torsion(u[index[:minus.size]], u[index[minus.size:]])
    normalised = {**schur.loads, "wing_mode": schur.loads["wing_mode"] / torsion}
    return WingModeSchur(replace(schur, loads=normalised), torsion)


class SharedCondenser:
    """Condenses one body (:func:`contact.assembly.assemble`'s ``condensers``) from a
    :class:`reduction.condensation.BoundarySchur` of it, once: the dense complement is let go
    after the call, so the run does not carry it."""

    def __init__(self, schur):
        self._schur = schur

    def __call__(self, stiffness, transformation, retained, fixed, loads):
        if self._schur is None:
            raise RuntimeError("a SharedCondenser condenses its body once")
        schur, self._schur = self._schur, None
        return condense_from_boundary(schur, stiffness, transformation, retained, fixed, loads)


def coupled_program(model, wing_amplitude: float | None = None):
    """The model (:class:`pipelines.build.Model`) with its cycle histories rebuilt for another wing
    amplitude (mm; None: the multibody amplitude). Nothing is re-condensed: the patterns are per
    unit history value."""
    coupled = model.coupling
    settings = replace(coupled.settings, wing_amplitude=wing_amplitude)
    cycle = cycle_loading(coupled.loading, settings.cycle, wing_amplitude, model.procedure.increments_per_cycle)
    tables = {name: cycle.tables[name] for name in coupled.patterns}
    if "centrifugal" not in model.scene.effects:  # the spin's mean belongs to the centrifugal effect
        tables = {name: values - values.mean() if name.startswith("frame_") else values
                  for name, values in tables.items()}
    program = TabulatedProgram(model.program.patterns, model.program.shapes, model.program.held, tables)
    # the scene as run states the amplitude run (results.h5's scene_toml; a limit search's runs
    # had the scene's own amplitude there)
    coupling_table = {key: value for key, value in model.scene.data["coupling"].items() if key != "wing_amplitude"}
    if wing_amplitude is not None:
        coupling_table["wing_amplitude"] = float(wing_amplitude)
    scene = replace(model.scene, data={**model.scene.data, "coupling": coupling_table})
    return replace(model, scene=scene, program=program,
                   coupling=Coupled(settings, coupled.loading, cycle, coupled.patterns))
