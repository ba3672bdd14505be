"""Habits checked over the sources, nothing imported: no module reads another module's private ``_name`` (ast),
no module is longer than 800 lines, every package folder is declared, and no text file keeps a merge's
conflict markers."""
import ast
import re
import tomllib
from pathlib import Path

import symmech

PACKAGE = Path(symmech.__file__).resolve().parent
MAX_LINES = 800
PRIVATE_ALLOWED: set[tuple[str, str]] = set()
LONG_ALLOWED: set[str] = set()


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def cross_module_private_uses(source: str, me: str, package: str) -> set[tuple[str, str]]:
    """(me, other_module._name) for every private name of another symmech module that the module ``me``
    (of ``package``, for relative imports) with text ``source`` imports by name or reads as an attribute of an
    imported module."""
    tree = ast.parse(source)
    modules, found = {}, set()  # local name -> symmech module it stands for
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("symmech"):
                    modules[a.asname or a.name] = a.name
        elif isinstance(node, ast.ImportFrom):
            base = ("." * node.level + (node.module or "")) if node.level else node.module or ""
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] + ("." + node.module if node.module else "")
            if not base.startswith("symmech"):
                continue
            for a in node.names:
                if private(a.name) and base != me:
                    found.add((me, f"{base}.{a.name}"))
                modules[a.asname or a.name] = f"{base}.{a.name}"
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and private(node.attr) and isinstance(node.value, ast.Name)
                and node.value.id in modules and modules[node.value.id] != me):
            found.add((me, f"{modules[node.value.id]}.{node.attr}"))
    return found


def test_no_module_uses_another_modules_private_names():
    found = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        me = module_name(path)
        package = me if path.name == "__init__.py" else me.rpartition(".")[0]
        found |= cross_module_private_uses(path.read_text(encoding="utf-8"), me, package)
    assert found - PRIVATE_ALLOWED == set(), "private names used across modules:\n" + "\n".join(
        f"  {me} reads {name}" for me, name in sorted(found - PRIVATE_ALLOWED))
    assert PRIVATE_ALLOWED <= found, f"allowed but gone (shrink the list): {sorted(PRIVATE_ALLOWED - found)}"


def test_the_checker_sees_a_private_import_and_attribute():
    """The checker itself: a from-import of ``_x`` and an attribute ``mod._y`` of an imported module count;
    the module's own private names and another module's dunders do not."""
    code = ("from symmech.core.schema import _did_you_mean\nfrom symmech.core import scene as s\n"
            "from . import _sibling\n"
            "def _own():\n    return s._quantity, s.__name__, _own\n")
    me = "symmech.grain.probe"
    assert cross_module_private_uses(code, me, "symmech.grain") == {
        (me, "symmech.core.schema._did_you_mean"), (me, "symmech.core.scene._quantity"),
        (me, "symmech.grain._sibling")}


def test_no_module_is_longer_than_800_lines():
    lengths = {str(p.relative_to(PACKAGE)): len(p.read_text(encoding="utf-8").splitlines())
               for p in PACKAGE.rglob("*.py")}
    long = {p: n for p, n in lengths.items() if n > MAX_LINES and p not in LONG_ALLOWED}
    assert long == {}, f"modules over {MAX_LINES} lines: {long}"


def test_every_package_folder_is_declared():
    """Each folder of symmech/ that is a package (its __init__.py) is among pyproject.toml's packages: a plain
    install leaves an undeclared one out (the grain's compiled engine once went missing that way)."""
    root = Path(__file__).resolve().parents[1]
    declared = set(tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(root).parts) for p in (root / "symmech").rglob("__init__.py")}
    assert found <= declared, sorted(found - declared)


def test_the_architecture_names_every_module():
    """docs/ARCHITECTURE.md has a place for every module of symmech/ (its tree or its module groups' rows): a new
    module goes in with its line there."""
    root = Path(__file__).resolve().parents[1]
    doc = (root / "docs" / "ARCHITECTURE.md").read_text(encoding="utf-8")
    unnamed = [str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
               if p.name != "__init__.py" and p.name not in doc]
    assert unnamed == []


ISSUE_REFERENCE = re.compile(r"\bissues?\s*#?\d+", re.IGNORECASE)


def test_no_code_or_doc_names_an_issue_by_number():
    """Code and docs say why in their own words; only CHANGELOG.md groups its lines by issue."""
    root = Path(__file__).resolve().parents[1]
    files = [root / "README.md"] + [p for d in ("symmech", "docs", "templates", "tools", "benchmarks")
                                    for p in (root / d).rglob("*") if p.suffix in (".py", ".md", ".j2", ".c", ".h")]
    texts = {str(p.relative_to(root)): p.read_text(encoding="utf-8") for p in files}
    found = {p: ISSUE_REFERENCE.findall(text) for p, text in texts.items() if "issue" in text.lower()}
    assert {p: hits for p, hits in found.items() if hits} == {}
    assert ISSUE_REFERENCE.findall("see Issue #31, issues 4 and issue 7") == ["Issue #31", "issues 4", "issue 7"]


CONFLICT_MARKERS = ("<<<<<<< ", "=======", ">>>>>>> ")
TEXT_FOLDERS = ("symmech", "tests", "docs", "templates", "scenes", "benchmarks", "tools", "mutation", "generated")


def conflict_lines(text: str) -> list[int]:
    """1-based numbers of the lines that open, split or close a merge conflict (git's markers at a line's start)."""
    return [i for i, line in enumerate(text.splitlines(), 1)
            if line.startswith(CONFLICT_MARKERS[::2]) or line == CONFLICT_MARKERS[1]]


def test_no_file_keeps_a_merge_conflict():
    """A conflict resolved in haste once left git's markers in docs/export.md for a session."""
    root = Path(__file__).resolve().parents[1]
    files = [root / n for n in ("README.md", "CHANGELOG.md", "pyproject.toml", "Makefile")]
    files += [p for d in TEXT_FOLDERS for p in (root / d).rglob("*")
              if p.is_file() and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".so", ".png")]
    found = {str(p.relative_to(root)): conflict_lines(p.read_text(encoding="utf-8", errors="replace"))
             for p in files if p.exists()}
    assert {p: n for p, n in found.items() if n} == {}


def test_the_checker_sees_each_conflict_marker():
    text = "a\n<<<<<<< HEAD\nb\n=======\nc\n>>>>>>> branch\n=======x\n"
    assert conflict_lines(text) == [2, 4, 6]
