"""The exudyn items of the crankshaft-counterweight model (:func:`build_system`).

Items (exudyn vocabulary):

* per throw, two rigid half-throws (journal + web + half crank pin), Tait-Bryan (Rxyz) nodes,
  joined at the crank pin by a 6-DOF spring-damper standing for pin and web flexibility; or,
  with the "flexible_crankshaft" effect, one Craig-Bampton body per throw (mbs.flexible_throw);
* multi-throw shafts (ModelParams.throws): throw k at z = k x throw_pitch, turned by its crank
  angle; neighbouring throws share a main journal and are joined there by a 6-DOF journal
  spring-damper (CrankThrowParams.journal_stiffness);
* main bearings: Cartesian spring-dampers from each journal centre to ground (radial on all,
  axial on journal 1); a shared journal's bearing is split half/half on its two halves;
* drive: the spin coordinate of journal 1 is held at engine speed (velocity-level coordinate
  constraint), or, with the "torsional_vibration" effect, a flywheel held at engine speed is
  coupled to journal 1 by the torsional shaft stiffness;
* one Craig-Bampton counterweight (ObjectFFRFreducedOrder) per web, its floating frame (= its
  rigid contact interface) joined rigidly to the web by a generic joint (the same reduced CW
  for every web);
* loads: tangential gas force at each crank pin, phase-shifted by the cylinder's firing angle
  ("gas_torque"), gear-mesh torque on the last journal ("gear_mesh"). Items of an effect that
  is off are not created.

Units: mm, N, t, s, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import exudyn as exu
import exudyn.utilities as eu
import numpy as np
from exudyn.FEM import ObjectFFRFreducedOrderInterface

from mbs.counterweight import ReducedCounterweight
from mbs.excitation import cylinder_gas_torque_table
from mbs.flexible_throw import ReducedThrow
from mbs.parameters import CrankThrowParams, ModelParams
from reduction.errors import InputError


#: CW local frame -> crank frame: CW y (radial outward) = -x crank, CW x = y crank, z = z.
COUNTERWEIGHT_ROTATION = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def half_throw_inertia(throw: CrankThrowParams, side: float, journal_fraction: float = 1.0) -> eu.RigidBodyInertia:
    """Journal + web + half pin of one side (side = -1 journal 1, +1 journal 2), node at web centre.

    journal_fraction: share of the main journal this half-throw carries (1/2 where a neighbouring
    throw shares the journal)."""
    journal_length = journal_fraction * throw.journal_length
    journal = eu.InertiaCylinder(throw.density, journal_length, throw.journal_radius, axis=2).Translated(
        [0.0, 0.0, side * 0.5 * (throw.web_thickness + journal_length)])
    web_length = throw.counterweight_radius + throw.crank_radius + throw.pin_radius
    web = eu.InertiaCuboid(throw.density, [web_length, throw.web_width, throw.web_thickness]).Translated(
        [0.5 * web_length - throw.counterweight_radius, 0.0, 0.0])
    pin = eu.InertiaCylinder(throw.density, 0.5 * throw.pin_length, throw.pin_radius, axis=2).Translated(
        [throw.crank_radius, 0.0, -side * 0.25 * (2.0 * throw.web_thickness + throw.pin_length)])
    return journal + web + pin


@dataclass
class _Items:
    """Item numbers of the exudyn system, filled while the model is built.

    Per half-throw h (h = 2k: journal-1 side of throw k, 2k + 1: journal-2 side): journal_markers
    (rigid, main-journal centre, frame = crank frame at the reference), web_markers (rigid, CW
    interface, frame = CW frame). pin_markers: (marker, throw, share of the gas force).
    """

    spin_node: int | None = None
    rigid_bodies: list = field(default_factory=list)
    flexible_bodies: list = field(default_factory=list)
    journal_markers: list = field(default_factory=list)
    web_markers: list = field(default_factory=list)
    pin_markers: list = field(default_factory=list)
    pin_force_body_fixed: bool = True
    springs: list = field(default_factory=list)
    cw_rigid_nodes: list = field(default_factory=list)
    cw_modal_nodes: list = field(default_factory=list)
    cw_joints: list = field(default_factory=list)


def _throw_center(params: ModelParams, k: int) -> float:
    return k * params.throw.throw_pitch


def _add_half_throws(mbs, params: ModelParams, speed: float, items: _Items) -> None:
    """Rigid half-throws; the two of one throw are joined at the crank pin by the pin spring."""
    throw = params.throw
    damped = params.solver.damping
    axial_offset = throw.bearing_z - throw.web_center_z
    last = params.throws - 1
    for k, angle in enumerate(params.throw_angles):
        rotation = _rotation_z(angle)
        bodies = []
        for side in (-1.0, 1.0):
            shared = (side < 0 and k > 0) or (side > 0 and k < last)
            created = mbs.CreateRigidBody(
                inertia=half_throw_inertia(throw, side, 0.5 if shared else 1.0),
                referencePosition=[0.0, 0.0, _throw_center(params, k) + side * throw.web_center_z],
                referenceRotationMatrix=rotation,
                initialAngularVelocity=[0.0, 0.0, speed],
                nodeType=exu.NodeType.RotationRxyz,
                returnDict=True,
                show=False,
            )
            body = created["bodyNumber"]
            bodies.append(body)
            items.rigid_bodies.append(body)
            if items.spin_node is None:
                items.spin_node = created["nodeNumber"]
            items.journal_markers.append(mbs.AddMarker(eu.MarkerBodyRigid(
                bodyNumber=body, localHT=exu.HT(rotation=rotation.T, translation=[0.0, 0.0, side * axial_offset]))))
            items.web_markers.append(mbs.AddMarker(eu.MarkerBodyRigid(bodyNumber=body, localHT=exu.HT(
                rotation=COUNTERWEIGHT_ROTATION, translation=[-throw.counterweight_radius, 0.0, 0.0]))))
        pin_markers = [
            mbs.AddMarker(eu.MarkerBodyRigid(bodyNumber=body, localPosition=[throw.crank_radius, 0.0, -side * throw.web_center_z]))
            for body, side in zip(bodies, (-1.0, 1.0))
        ]
        items.springs.append(mbs.AddObject(eu.RigidBodySpringDamper(
            markerNumbers=pin_markers,
            stiffness=np.diag(throw.pin_stiffness),
            damping=np.diag(throw.pin_damping) if damped else np.zeros((6, 6)),
        )))
        items.pin_markers += [(marker, k, 0.5) for marker in pin_markers]


#: Stiffness-proportional damping of the flexible throws, s: 1 % of critical at 400 Hz (the coupled
#: CW torsion mode), beta = 2 zeta / omega.
FLEXIBLE_THROW_DAMPING = 2.0 * 0.01 / (2.0 * math.pi * 400.0)


def _add_flexible_throws(mbs, params: ModelParams, speed: float, items: _Items, reduced_throw: ReducedThrow) -> None:
    """One Craig-Bampton throw body per throw (mbs.flexible_throw); its markers take the places
    of the rigid half-throws' markers. Its frame is journal 1's cut face, which is not a rigid
    body with a spin coordinate: a small drive flange (Rxyz rigid body, the journal's section,
    10 mm long) is joined rigidly to journal 1 of throw 1 and carries the drive and the spin
    sensors. The gas force acts on the pin mid-section (MarkerSuperElementPosition)."""
    throw = params.throw
    interface = ObjectFFRFreducedOrderInterface(reduced_throw.fem_interface())
    journal_nodes, cw_nodes = reduced_throw.interface_nodes[:2], reduced_throw.interface_nodes[2:]
    for k, angle in enumerate(params.throw_angles):
        rotation = _rotation_z(angle)
        created = interface.AddObjectFFRFreducedOrder(
            mbs, positionRef=[0.0, 0.0, _throw_center(params, k)], rotationMatrixRef=rotation,
            initialAngularVelocity=[0.0, 0.0, speed],
            stiffnessProportionalDamping=FLEXIBLE_THROW_DAMPING if params.solver.damping else 0.0)
        body = created["oFFRFreducedOrder"]
        items.flexible_bodies.append((body, created["nRigidBody"], created["nGenericODE2"]))

        def rigid_marker(nodes, local_rotation):
            return mbs.AddMarker(eu.MarkerSuperElementRigid(
                bodyNumber=body, meshNodeNumbers=nodes, weightingFactors=np.full(len(nodes), 1.0 / len(nodes)),
                localHT=exu.HT(rotation=local_rotation, translation=[0.0, 0.0, 0.0])))

        for nodes_j, nodes_cw in zip(journal_nodes, cw_nodes):
            items.journal_markers.append(rigid_marker(nodes_j, rotation.T))
            items.web_markers.append(rigid_marker(nodes_cw, COUNTERWEIGHT_ROTATION))
        pin = reduced_throw.pin_nodes
        items.pin_markers.append((mbs.AddMarker(eu.MarkerSuperElementPosition(
            bodyNumber=body, meshNodeNumbers=pin, weightingFactors=np.full(len(pin), 1.0 / len(pin)))), k, 1.0))
    items.pin_force_body_fixed = False
    flange = mbs.CreateRigidBody(
        inertia=eu.InertiaCylinder(throw.density, 10.0, throw.journal_radius, axis=2),
        referencePosition=[0.0, 0.0, -throw.bearing_z], initialAngularVelocity=[0.0, 0.0, speed],
        nodeType=exu.NodeType.RotationRxyz, returnDict=True, show=False)
    items.rigid_bodies.append(flange["bodyNumber"])
    items.spin_node = flange["nodeNumber"]
    on_flange = mbs.AddMarker(eu.MarkerBodyRigid(bodyNumber=flange["bodyNumber"]))
    mbs.AddObject(eu.GenericJoint(markerNumbers=[on_flange, items.journal_markers[0]], constrainedAxes=[1] * 6))


def _add_bearings_and_journals(mbs, params: ModelParams, items: _Items) -> None:
    """Main bearing per journal (ground springs; thrust on journal 1) and, between neighbouring
    throws, the journal spring-damper that joins them."""
    throw = params.throw
    damped = params.solver.damping
    ground = mbs.AddObject(eu.ObjectGround())
    damping = throw.bearing_damping if damped else 0.0
    # A shared journal's bearing is split half/half onto the two half-journals that meet there
    # (one bearing when the journal spring is stiff; each throw keeps its support when it is soft).
    for h, marker in enumerate(items.journal_markers):
        j = (h + 1) // 2
        share = 1.0 if j in (0, params.throws) else 0.5
        on_ground = mbs.AddMarker(eu.MarkerBodyPosition(
            bodyNumber=ground, localPosition=[0.0, 0.0, _throw_center(params, j) - throw.bearing_z]))
        axial = throw.axial_stiffness if j == 0 else 0.0
        items.springs.append(mbs.AddObject(eu.CartesianSpringDamper(
            markerNumbers=[on_ground, marker],
            stiffness=[share * throw.bearing_stiffness, share * throw.bearing_stiffness, axial],
            damping=[share * damping, share * damping, damping if j == 0 else 0.0],
        )))
    for j in range(1, params.throws):
        items.springs.append(mbs.AddObject(eu.RigidBodySpringDamper(
            markerNumbers=[items.journal_markers[2 * j - 1], items.journal_markers[2 * j]],
            stiffness=np.diag(throw.journal_stiffness),
            damping=np.diag(throw.journal_damping) if damped else np.zeros((6, 6)),
        )))


def _add_drive(mbs, params: ModelParams, speed: float, items: _Items) -> None:
    if params.solver.drive == "free":
        return
    spin = mbs.AddMarker(eu.MarkerNodeCoordinate(nodeNumber=items.spin_node, coordinate=5))
    ground_node = mbs.AddNode(eu.NodePointGround())
    fixed = mbs.AddMarker(eu.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    if "torsional_vibration" not in params.effects:
        mbs.AddObject(eu.CoordinateConstraint(markerNumbers=[fixed, spin], velocityLevel=True, offset=speed))
        return
    excitation = params.excitation
    flywheel = mbs.AddNode(eu.Node1D(referenceCoordinates=[0.0], initialVelocities=[speed]))
    mbs.AddObject(eu.ObjectMass1D(nodeNumber=flywheel, mass=excitation.flywheel_inertia))
    flywheel_angle = mbs.AddMarker(eu.MarkerNodeCoordinate(nodeNumber=flywheel, coordinate=0))
    mbs.AddObject(eu.CoordinateConstraint(markerNumbers=[fixed, flywheel_angle], velocityLevel=True, offset=speed))
    mbs.AddObject(eu.CoordinateSpringDamper(
        markerNumbers=[flywheel_angle, spin],
        stiffness=excitation.torsional_stiffness,
        damping=excitation.torsional_damping if params.solver.damping else 0.0,
    ))


def _add_counterweights(mbs, params: ModelParams, reduced: ReducedCounterweight, speed: float, items: _Items) -> None:
    """One reduced CW per half-throw (the same reduced body reused), frame joined to its web marker."""
    throw = params.throw
    interface = ObjectFFRFreducedOrderInterface(reduced.fem_interface())
    modal_damping = np.diag(2.0 * params.modal_damping_ratio * 2.0 * np.pi * reduced.eigenfrequencies)
    for h, on_web in enumerate(items.web_markers):
        k, side = divmod(h, 2)
        rotation = _rotation_z(params.throw_angles[k])
        position = rotation @ [-throw.counterweight_radius, 0.0, 0.0] \
            + [0.0, 0.0, _throw_center(params, k) + (2 * side - 1) * throw.web_center_z]
        created = interface.AddObjectFFRFreducedOrder(
            mbs,
            positionRef=position,
            initialVelocity=np.cross([0.0, 0.0, speed], position),
            rotationMatrixRef=rotation @ COUNTERWEIGHT_ROTATION,
            initialAngularVelocity=[0.0, 0.0, speed],
        )
        if params.solver.damping and params.modal_damping_ratio > 0:
            mbs.SetObjectParameter(created["oFFRFreducedOrder"], "dampingMatrixReduced", exu.MatrixContainer(modal_damping))
        on_cw = mbs.AddMarker(eu.MarkerNodeRigid(nodeNumber=created["nRigidBody"]))
        if throw.joint_stiffness is None:
            joint = mbs.AddObject(eu.GenericJoint(markerNumbers=[on_web, on_cw], constrainedAxes=[1] * 6))
        else:
            joint = mbs.AddObject(eu.RigidBodySpringDamper(markerNumbers=[on_web, on_cw],
                                                           stiffness=np.diag(throw.joint_stiffness)))
            items.springs.append(joint)
        items.cw_rigid_nodes.append(created["nRigidBody"])
        items.cw_modal_nodes.append(created["nGenericODE2"])
        items.cw_joints.append(joint)


def _add_loads(mbs, params: ModelParams, speed: float, items: _Items) -> None:
    """Loads evaluate scalar math in their user functions: numpy call overhead per step would
    dominate the solver time (measured: 45 us per numpy evaluation against 120 us per step).
    Both loads fade in over SolverParams.ramp_revolutions (half-cosine): switching the full gas
    torque on at t = 0 is a step of several hundred kN at the pin that rings for revolutions.
    Cylinder k's gas torque is the order table shifted by its firing angle (order n: phase
    - n x firing angle)."""
    excitation = params.excitation
    radius = params.throw.crank_radius
    ramp_time = params.solver.ramp_revolutions * 2.0 * math.pi / speed

    def ramp(t):
        return 1.0 if t >= ramp_time else 0.5 * (1.0 - math.cos(math.pi * t / ramp_time))

    if "gas_torque" in params.effects:
        for marker, k, share in items.pin_markers:
            table = [(w, share * amplitude / radius, phase) for w, amplitude, phase
                     in cylinder_gas_torque_table(speed, excitation, params.firing_angles[k])]
            mbs.AddLoad(_gas_load(marker, table, ramp, items.pin_force_body_fixed, speed, params.throw_angles[k]))
    if "gear_mesh" in params.effects:
        mesh_speed = excitation.gear_teeth * speed
        amplitude = excitation.gear_torque_amplitude

        def mesh_torque(mbs_, t, load_vector):
            return [0.0, 0.0, ramp(t) * amplitude * math.sin(mesh_speed * t)]

        mbs.AddLoad(eu.LoadTorqueVector(markerNumber=items.journal_markers[-1], bodyFixed=True,
                                        loadVectorUserFunction=mesh_torque))


def _gas_load(marker: int, table: list, ramp, body_fixed: bool, speed: float, throw_angle: float):
    """Tangential gas force at a pin marker: in the body frame, or (flexible throws, whose pin
    markers have no body-fixed frame) along the tangent of the ideally spinning pin."""
    if body_fixed:
        def tangential_force(mbs_, t, load_vector):
            return [0.0, ramp(t) * sum(a * math.cos(w * t + p) for w, a, p in table), 0.0]
    else:
        def tangential_force(mbs_, t, load_vector):
            force = ramp(t) * sum(a * math.cos(w * t + p) for w, a, p in table)
            angle = throw_angle + speed * t
            return [-force * math.sin(angle), force * math.cos(angle), 0.0]
    return eu.LoadForceVector(markerNumber=marker, bodyFixed=body_fixed, loadVectorUserFunction=tangential_force)


def _sensor(mbs, **kwargs):
    return mbs.AddSensor(eu.SensorNode(storeInternal=True, **kwargs)) if "nodeNumber" in kwargs \
        else mbs.AddSensor(eu.SensorObject(storeInternal=True, **kwargs))


def add_sensors(mbs, items: _Items, energy: bool) -> dict:
    ovt = exu.OutputVariableType
    sensors = {"spin": _sensor(mbs, nodeNumber=items.spin_node, outputVariableType=ovt.Coordinates_t),
               "angle": _sensor(mbs, nodeNumber=items.spin_node, outputVariableType=ovt.Coordinates)}
    per_cw = {
        "q": ("node", ovt.Coordinates), "q_t": ("node", ovt.Coordinates_t), "q_tt": ("node", ovt.Coordinates_tt),
        "rotation": ("rigid", ovt.RotationMatrix), "acceleration": ("rigid", ovt.Acceleration),
        "omega": ("rigid", ovt.AngularVelocityLocal), "alpha": ("rigid", ovt.AngularAcceleration),
        "velocity": ("rigid", ovt.Velocity),
        "joint_displacement": ("joint", ovt.DisplacementLocal), "joint_rotation": ("joint", ovt.Rotation),
        "joint_force": ("joint", ovt.ForceLocal), "joint_moment": ("joint", ovt.TorqueLocal),
    }
    for c in range(len(items.cw_joints)):
        for key, (kind, variable) in per_cw.items():
            if kind == "node":
                sensors[(key, c)] = _sensor(mbs, nodeNumber=items.cw_modal_nodes[c], outputVariableType=variable)
            elif kind == "rigid":
                sensors[(key, c)] = _sensor(mbs, nodeNumber=items.cw_rigid_nodes[c], outputVariableType=variable)
            else:
                sensors[(key, c)] = _sensor(mbs, objectNumber=items.cw_joints[c], outputVariableType=variable)
    if energy:
        sensors["kinetic"] = [mbs.AddSensor(eu.SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=ovt.KineticEnergy))
                              for b in items.rigid_bodies]
        sensors["potential"] = [mbs.AddSensor(eu.SensorObject(objectNumber=o, storeInternal=True, outputVariableType=ovt.PotentialEnergy))
                                for o in items.springs]
    return sensors


def build_system(params: ModelParams, reduced: ReducedCounterweight, *, loads: bool,
           initial_modal_coordinates: np.ndarray | None = None, reduced_throw: ReducedThrow | None = None):
    speed = params.shaft_speed
    system = exu.SystemContainer()
    mbs = system.AddSystem()
    items = _Items()
    if "flexible_crankshaft" in params.effects:
        if reduced_throw is None:
            raise InputError("the flexible_crankshaft effect needs the reduced throw: pass reduced_throw "
                             "(mbs.model.reduce_bodies reduces both bodies of a model)")
        _add_flexible_throws(mbs, params, speed, items, reduced_throw)
    else:
        _add_half_throws(mbs, params, speed, items)
    _add_bearings_and_journals(mbs, params, items)
    _add_drive(mbs, params, speed, items)
    _add_counterweights(mbs, params, reduced, speed, items)
    if initial_modal_coordinates is not None:
        for node in items.cw_modal_nodes:
            mbs.SetNodeParameter(node, "initialCoordinates", list(np.asarray(initial_modal_coordinates, dtype=float)))
    if loads:
        _add_loads(mbs, params, speed, items)
    return system, mbs, items
