"""The one discovery rule: a module's ROLE line, never its file name, makes it a producer, errata, kind or engine."""
import ast
from pathlib import Path

import symmech
from symmech.core import discovery

PACKAGE = Path(symmech.__file__).resolve().parent


def protocol(tree: ast.Module) -> set[str]:
    """The roles a module's top level actually plays: what it defines or registers."""
    roles = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == "module_specs":
            roles.add("producer")
        if isinstance(node, ast.FunctionDef) and node.name == "checks":
            roles.add("errata")
        for call in ast.walk(node):
            if (isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute) and call.func.attr == "register"
                    and isinstance(call.func.value, ast.Name)):
                roles.add({"registry": "kind", "engines": "engine"}.get(call.func.value.id, "other"))
    return roles - {"other"}


def test_every_module_declares_exactly_the_role_it_plays():
    declared = discovery.declared()
    expected = {"derivation": {"producer"}, "printed": {"producer"}, "errata": {"errata"}, "kind": {"kind"},
                "engine": {"engine"}}
    checked = 0
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[0] in discovery.NOT_PAPERS or len(parts) < 2:
            continue
        name = "symmech." + ".".join(p for p in parts if p != "__init__")
        plays = protocol(ast.parse(path.read_text(encoding="utf-8")))
        assert plays == expected.get(declared.get(name), set()), f"{name}: ROLE {declared.get(name)!r}, plays {plays}"
        checked += 1
    assert checked > 60 and len(declared) >= 20


def test_every_role_is_found_in_every_paper():
    for role in ("derivation", "printed", "errata", "kind"):
        papers = {name.split(".")[1] for name in discovery.modules(role)}
        assert papers == {"grain", "smm", "trolley"}, (role, papers)
    assert {name.split(".")[1] for name in discovery.modules("engine")} == {"grain", "trolley"}


def test_a_subpackage_is_walked_and_file_names_play_no_part():
    """The elastic trolley's modules sit in a subpackage under plain names (derive.py, engine.py): found by ROLE."""
    assert discovery.declared()["symmech.trolley.elastic.derive"] == "derivation"
    assert discovery.declared()["symmech.trolley.elastic.engine"] == "engine"
    assert "symmech.trolley.elastic.system" not in discovery.declared()
