"""``modelDescription.xml`` of an exported model, FMI 2.0 or 3.0, and FMI 3's ``buildDescription.xml``.

Names follow FMI's structured naming convention (``der(x)``, ``der(x,2)``); every unit is declared in
``UnitDefinitions`` with its SI base-unit exponents where the unit text is a product of known units.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections import Counter

from symmech import __version__
from symmech.export.model import ExportModel, Variable

BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
# derived SI units in base units
DERIVED = {"N": {"kg": 1, "m": 1, "s": -2}, "J": {"kg": 1, "m": 2, "s": -2}, "W": {"kg": 1, "m": 2, "s": -3},
           "Pa": {"kg": 1, "m": -1, "s": -2}, "Hz": {"s": -1}}
_FACTOR = re.compile(r"([A-Za-z]+)(?:\^(-?\d+))?\Z")


def base_units(unit: str) -> dict[str, int] | None:
    """SI base-unit exponents of a unit text such as ``N m``, ``m/s^2``, ``kg m^2`` (``1``: dimensionless);
    None when a factor is not an SI unit symbol symmech writes."""
    out: Counter = Counter()
    numerator, _, denominator = unit.partition("/")
    for sign, part in ((1, numerator), (-1, denominator)):
        for factor in part.replace("*", " ").split():
            if factor == "1":
                continue
            match = _FACTOR.match(factor)
            if not match:
                return None
            symbol, power = match.group(1), sign * int(match.group(2) or 1)
            if symbol in BASE:
                out[symbol] += power
            elif symbol in DERIVED:
                for b, e in DERIVED[symbol].items():
                    out[b] += power * e
            else:
                return None
    return {b: out[b] for b in BASE if out[b]}


def _units(parent: ET.Element, variables: tuple[Variable, ...]) -> None:
    defs = ET.SubElement(parent, "UnitDefinitions")
    for unit in sorted({v.unit for v in variables}):
        element = ET.SubElement(defs, "Unit", name=unit)
        exponents = base_units(unit)
        if exponents is not None:
            ET.SubElement(element, "BaseUnit", {b: str(e) for b, e in exponents.items()})


def _number(x: float) -> str:
    return repr(float(x))


def _attributes(v: Variable) -> dict[str, str]:
    out = {"name": v.name, "valueReference": str(v.vr), "description": v.description, "causality": v.causality,
           "variability": v.variability}
    if v.initial is not None and v.causality == "output":
        out["initial"] = v.initial
    return out


def _root(model: ExportModel, version: str, token_name: str, token: str) -> ET.Element:
    return ET.Element("fmiModelDescription", {
        "fmiVersion": version, "modelName": model.identifier, "description": model.description,
        token_name: token, "generationTool": f"symmech {__version__}", "variableNamingConvention": "structured"})


def fmi3(model: ExportModel, token: str, kind: str) -> str:
    """FMI 3.0 ``modelDescription.xml`` text; ``kind`` ``me`` or ``cs``."""
    root = _root(model, "3.0", "instantiationToken", token)
    if kind == "me":
        interface = ET.SubElement(root, "ModelExchange", modelIdentifier=model.identifier)
        if model.n_z:  # fmi3CompletedIntegratorStep checks that no indicator was crossed without its event
            interface.set("needsCompletedIntegratorStep", "true")
    else:
        ET.SubElement(root, "CoSimulation", modelIdentifier=model.identifier,
                      canHandleVariableCommunicationStepSize="true")
    _units(root, model.variables)
    _experiment(root, model, kind)
    variables = ET.SubElement(root, "ModelVariables")
    for v in model.variables:
        attributes = _attributes(v) | {"unit": v.unit}
        if v.start is not None:
            attributes["start"] = _number(v.start)
        if v.derivative_of is not None:
            attributes["derivative"] = str(v.derivative_of)
        if v.nominal is not None:
            attributes["nominal"] = _number(v.nominal)
        ET.SubElement(variables, "Float64", attributes)
    structure = ET.SubElement(root, "ModelStructure")
    for v in model.variables:
        if v.causality == "output":
            ET.SubElement(structure, "Output", valueReference=str(v.vr))
    if kind == "me":
        for v in model.variables:
            if v.derivative_of is not None:
                ET.SubElement(structure, "ContinuousStateDerivative", valueReference=str(v.vr))
    for v in _initial_unknowns(model):
        ET.SubElement(structure, "InitialUnknown", valueReference=str(v.vr))
    if kind == "me":
        z = model.layout()["VR_Z"]
        for vr in range(z, z + model.n_z):
            ET.SubElement(structure, "EventIndicator", valueReference=str(vr))
    return _text(root)


def fmi2(model: ExportModel, token: str, kind: str) -> str:
    """FMI 2.0 ``modelDescription.xml`` text; ``kind`` ``me`` or ``cs``. Time is implicit (not a variable)."""
    root = _root(model, "2.0", "guid", token)
    root.set("numberOfEventIndicators", str(model.n_z if kind == "me" else 0))
    element = "ModelExchange" if kind == "me" else "CoSimulation"
    interface = ET.SubElement(root, element, modelIdentifier=model.identifier)
    if kind == "cs":
        interface.set("canHandleVariableCommunicationStepSize", "true")
    files = ET.SubElement(interface, "SourceFiles")
    for name in source_files(model, 2):
        ET.SubElement(files, "File", name=name)
    variables = [v for v in model.variables if v.causality != "independent"]
    _units(root, tuple(variables))
    _experiment(root, model, kind)
    index = {v.vr: i + 1 for i, v in enumerate(variables)}  # FMI 2 refers to variables by 1-based position
    listing = ET.SubElement(root, "ModelVariables")
    for v in variables:
        scalar = ET.SubElement(listing, "ScalarVariable", _attributes(v))
        real = ET.SubElement(scalar, "Real", unit=v.unit)
        if v.start is not None:
            real.set("start", _number(v.start))
        if v.derivative_of is not None:
            real.set("derivative", str(index[v.derivative_of]))
        if v.nominal is not None:
            real.set("nominal", _number(v.nominal))
    structure = ET.SubElement(root, "ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    for v in variables:
        if v.causality == "output":
            ET.SubElement(outputs, "Unknown", index=str(index[v.vr]))
    if kind == "me":
        derivatives = ET.SubElement(structure, "Derivatives")
        for v in variables:
            if v.derivative_of is not None:
                ET.SubElement(derivatives, "Unknown", index=str(index[v.vr]))
    unknowns = _initial_unknowns(model)
    if unknowns:
        initial = ET.SubElement(structure, "InitialUnknowns")
        for v in unknowns:
            ET.SubElement(initial, "Unknown", index=str(index[v.vr]))
    return _text(root)


def _initial_unknowns(model: ExportModel) -> list[Variable]:
    """Outputs the model computes at initialization (initial="calculated"), in value-reference order."""
    return [v for v in model.variables if v.causality == "output" and v.initial == "calculated"]


def _experiment(root: ET.Element, model: ExportModel, kind: str) -> None:
    """The native run's span and output step (where the scene has a run); under Model Exchange the tolerance at
    which the importer's integrator reproduces the native run (Co-Simulation's own integrator has its default,
    DEFAULT_TOLERANCE in C)."""
    experiment = {}
    if model.native is not None:
        t = model.native.column("t")
        experiment = {"startTime": _number(t[0]), "stopTime": _number(t[-1]), "stepSize": _number(t[1] - t[0])}
    if kind == "me":
        experiment["tolerance"] = _number(model.me_tolerance)
    if experiment:
        ET.SubElement(root, "DefaultExperiment", experiment)


def build_description(model: ExportModel) -> str:
    """FMI 3.0 ``sources/buildDescription.xml``: the C99 files an importer compiles for another platform."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model.identifier)
    files = ET.SubElement(config, "SourceFileSet", language="C99")
    for name in source_files(model, 3):
        ET.SubElement(files, "SourceFile", name=name)
    return _text(root)


def source_files(model: ExportModel, fmi: int) -> tuple[str, ...]:
    """The C files an importer compiles, with the FMI glue of version ``fmi``."""
    return (f"fmi{fmi}.c", "symmech_model.c", *model.c_files())


def _text(root: ET.Element) -> str:
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
