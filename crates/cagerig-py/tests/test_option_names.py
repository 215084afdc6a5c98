"""The stubs' option literals are the names the library accepts (one definition per kind)."""

import ast
import pathlib

import cagerig

STUBS = pathlib.Path(cagerig.__file__).with_name("_cagerig.pyi")

# Stub alias -> the package's list of the names that option accepts.
ALIASES = {
    "_Skinning": "SKINNING_METHODS",
    "_Coords": "COORDS_KINDS",
    "_CageFit": "CAGE_FITS",
    "_CageLayout": "CAGE_LAYOUTS",
    "_UnfittedCage": "UNFITTED_CAGE_POLICIES",
    "_FitRows": "FIT_ROWS",
    "_Localisation": "LOCALISATIONS",
    "_FitSource": "FIT_SOURCES",
    "_Precision": "COORDS_PRECISIONS",
    "_GreenFaceTerm": "GREEN_FACE_TERMS",
}


def stub_literals():
    """{alias: [names]} of the `_Alias = Literal[...]` assignments in the stubs."""
    out = {}
    for node in ast.parse(STUBS.read_text()).body:
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and isinstance(node.value, ast.Subscript)
            and getattr(node.value.value, "id", None) == "Literal"
        ):
            elements = node.value.slice
            items = elements.elts if isinstance(elements, ast.Tuple) else [elements]
            out[node.targets[0].id] = [item.value for item in items]
    return out


def test_the_stub_literals_list_exactly_the_accepted_names():
    literals = stub_literals()
    for alias, constant in ALIASES.items():
        names = list(getattr(cagerig, constant))
        assert literals.get(alias) == names, (alias, literals.get(alias), names)


def test_every_listed_name_is_accepted_and_others_are_refused():
    for name in cagerig.COORDS_KINDS:
        rig = cagerig.Rig.builtin("bar", coords=name)
        assert rig.coords == name
    for name in cagerig.CAGE_FITS:
        assert cagerig.Rig.builtin("bar", cage_fit=name).cage_fit == name
    try:
        cagerig.Rig.builtin("bar", coords="harmonic")
    except ValueError as error:
        assert "mvc" in str(error) and "harmonic" in str(error), error
    else:
        raise AssertionError("an unknown coordinates name was accepted")


def test_the_localisation_reads_dash_and_underscore_alike():
    for spelling in ("reference-tool", "reference_tool", "Reference_Tool"):
        cagerig.Rig.builtin("bar", localisation=spelling)
