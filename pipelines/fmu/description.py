"""modelDescription.xml and buildDescription.xml of the player FMU (FMI 2.0 and 3.0).

Value references are mirrored in template/player.h: time, then the playback parameters
(time_offset, period, periodic), then the outputs from VR_FIRST_OUTPUT on.
"""

from __future__ import annotations

import datetime
import xml.etree.ElementTree as ET

import numpy as np

from pipelines.fmu.table import PlaybackTable


#: Sources and headers of the player, per FMI version.
PLAYER_SOURCES = ("player.c",)
PLAYER_HEADERS = ("player.h",)
FMI_SOURCES = {2: ("fmi2_player.c",), 3: ("fmi3_player.c",)}
FMI_HEADERS = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}

# Value references, mirrored in template/player.h.
VR_TIME = 0
VR_TIME_OFFSET = 1
VR_PERIOD = 2
VR_PERIODIC = 3
VR_FIRST_OUTPUT = 100

#: The generationTool of every FMU fretwork writes: with the player's table, what marks an FMU as
#: fretwork's (:func:`pipelines.fmu.export.written_by_fretwork`).
GENERATION_TOOL = "fretwork"


# SI base-unit exponents and factor (value_SI = factor * value) of the units fretwork writes,
# so importing tools can convert; other units are declared by name only.
BASE_UNITS = {
    "s": ({"s": 1}, 1.0),
    "m": ({"m": 1}, 1.0),
    "mm": ({"m": 1}, 1e-3),
    "mm/s": ({"m": 1, "s": -1}, 1e-3),
    "mm/s^2": ({"m": 1, "s": -2}, 1e-3),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "m/s^2": ({"m": 1, "s": -2}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "rad/s^2": ({"rad": 1, "s": -2}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "N*mm": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "N.mm": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "MPa": ({"kg": 1, "m": -1, "s": -2}, 1e6),
    "t": ({"kg": 1}, 1e3),
    "mJ": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "Hz": ({"s": -1}, 1.0),
}


def model_description_xml(table: PlaybackTable, fmi_version: int, identifier: str, token: str) -> bytes:
    """modelDescription.xml of the player FMU for FMI 2.0 or 3.0."""
    root = _description_root(table, fmi_version, identifier, token)
    _add_units(root, table)
    log_categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(log_categories, "Category", {"name": "logStatusError", "description": "Errors of the player"})
    ET.SubElement(
        root,
        "DefaultExperiment",
        {
            "startTime": repr(float(table.time[0])),
            "stopTime": repr(float(table.time[-1])),
            "stepSize": f"{np.median(np.diff(table.time)):.12g}",
        },
    )
    span = float(table.time[-1] - table.time[0])
    parameters = [
        (VR_TIME_OFFSET, "time_offset", "Real", "s", "0.0",
         "Shift of the history in time: the output at time t is the history at t - time_offset"),
        (VR_PERIOD, "period", "Real", "s", repr(span),
         "Repetition period when periodic; at least the sampled span t_last - t_first"),
        (VR_PERIODIC, "periodic", "Boolean", "", "false",
         "Repeat the history with the given period instead of holding the first/last sample"),
    ]
    add_variables = _add_variables_fmi3 if fmi_version == 3 else _add_variables_fmi2
    add_variables(root, ET.SubElement(root, "ModelVariables"), table, parameters)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _description_root(table: PlaybackTable, fmi_version: int, identifier: str, token: str) -> ET.Element:
    """The fmiModelDescription element with its CoSimulation capabilities."""
    fmi3 = fmi_version == 3
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0" if fmi3 else "2.0",
            "modelName": identifier,
            ("instantiationToken" if fmi3 else "guid"): token,
            "description": _description(table),
            "generationTool": GENERATION_TOOL,
            "generationDateAndTime": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "variableNamingConvention": "structured",
        },
    )
    if not fmi3:
        root.set("numberOfEventIndicators", "0")
    cosim = ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": identifier,
            "canHandleVariableCommunicationStepSize": "true",
            "canGetAndSetFMUState" if fmi3 else "canGetAndSetFMUstate": "false",
            "canSerializeFMUState" if fmi3 else "canSerializeFMUstate": "false",
        },
    )
    if not fmi3:
        files = ET.SubElement(cosim, "SourceFiles")
        for name in PLAYER_SOURCES + FMI_SOURCES[2]:
            ET.SubElement(files, "File", {"name": name})
    return root


def _description(table: PlaybackTable) -> str:
    """What the FMU plays: how many outputs, which part of a multibody run, and for a coupled run's
    histories, their scaling."""
    text = f"Playback of {len(table.names)} load history outputs sampled at {table.time.size} times"
    if table.multibody_part == "steady":
        text += (f", the steady second half of the multibody run (from t = {table.time[0]:.6g} s), where its wing "
                 "amplitude is measured; the first half, the start-up transient, is left out (export-fmu --whole "
                 "plays it)")
    elif table.multibody_part == "whole":
        text += (", the whole multibody run, its start-up transient included (its wing amplitude is measured on "
                 "the steady second half)")
    return text if table.scaling is None else f"{text}, {table.scaling.describe()}"


def _add_units(root: ET.Element, table: PlaybackTable) -> None:
    """UnitDefinitions: every unit of the outputs and s, with its SI base units where known."""
    units = sorted({unit for unit in table.units if unit} | {"s"})
    unit_definitions = ET.SubElement(root, "UnitDefinitions")
    for unit in units:
        unit_element = ET.SubElement(unit_definitions, "Unit", {"name": unit})
        if unit in BASE_UNITS:
            exponents, factor = BASE_UNITS[unit]
            attributes = {key: str(value) for key, value in exponents.items()}
            if factor != 1.0:
                attributes["factor"] = repr(factor)
            ET.SubElement(unit_element, "BaseUnit", attributes)


def _add_variables_fmi3(root: ET.Element, variables: ET.Element, table: PlaybackTable, parameters) -> None:
    """FMI 3.0 ModelVariables (time, parameters, outputs) and ModelStructure."""
    ET.SubElement(variables, "Float64", {
        "name": "time", "valueReference": str(VR_TIME), "causality": "independent",
        "variability": "continuous", "unit": "s", "description": "Simulation time",
    })
    for vr, name, kind, unit, start, description in parameters:
        attributes = {"name": name, "valueReference": str(vr), "causality": "parameter",
                      "variability": "fixed", "description": description, "start": start}
        if unit:
            attributes["unit"] = unit
        ET.SubElement(variables, "Float64" if kind == "Real" else "Boolean", attributes)
    for j, (name, unit, description) in enumerate(zip(table.names, table.units, table.descriptions)):
        attributes = {"name": name, "valueReference": str(VR_FIRST_OUTPUT + j), "causality": "output",
                      "variability": "continuous"}
        if description:
            attributes["description"] = description
        if unit:
            attributes["unit"] = unit
        ET.SubElement(variables, "Float64", attributes)
    structure = ET.SubElement(root, "ModelStructure")
    for j in range(len(table.names)):
        ET.SubElement(structure, "Output", {"valueReference": str(VR_FIRST_OUTPUT + j)})
    for j in range(len(table.names)):
        ET.SubElement(structure, "InitialUnknown", {"valueReference": str(VR_FIRST_OUTPUT + j)})


def _add_variables_fmi2(root: ET.Element, variables: ET.Element, table: PlaybackTable, parameters) -> None:
    """FMI 2.0 ModelVariables (parameters, outputs) and ModelStructure."""
    for vr, name, kind, unit, start, description in parameters:
        variable = ET.SubElement(variables, "ScalarVariable", {
            "name": name, "valueReference": str(vr), "causality": "parameter",
            "variability": "fixed", "description": description,
        })
        attributes = {"start": start}
        if unit:
            attributes["unit"] = unit
        ET.SubElement(variable, kind, attributes)
    for j, (name, unit, description) in enumerate(zip(table.names, table.units, table.descriptions)):
        attributes = {"name": name, "valueReference": str(VR_FIRST_OUTPUT + j), "causality": "output",
                      "variability": "continuous"}
        if description:
            attributes["description"] = description
        variable = ET.SubElement(variables, "ScalarVariable", attributes)
        ET.SubElement(variable, "Real", {"unit": unit} if unit else {})
    structure = ET.SubElement(root, "ModelStructure")
    # FMI 2.0 ModelStructure refers to variables by 1-based position in ModelVariables.
    first_output_index = len(parameters) + 1
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    for j in range(len(table.names)):
        ET.SubElement(outputs, "Unknown", {"index": str(first_output_index + j)})
        ET.SubElement(initial, "Unknown", {"index": str(first_output_index + j)})


def build_description_xml(identifier: str) -> bytes:
    """FMI 3.0 sources/buildDescription.xml listing the player sources."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    configuration = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": identifier})
    file_set = ET.SubElement(configuration, "SourceFileSet", {"language": "C99"})
    for name in PLAYER_SOURCES + FMI_SOURCES[3]:
        ET.SubElement(file_set, "SourceFile", {"name": name})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
