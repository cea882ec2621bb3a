"""House rules a tool checks: no private names used across modules (ruff and lint-imports are CI
steps of ``.ci/run``, not tests)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "atlas"


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        yield path, ast.parse(path.read_text(), str(path))


def _atlas_aliases(tree) -> dict:
    """Local names bound to atlas modules: ``from atlas.core import points as p`` -> {p: ...}."""
    names = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("atlas"):
            for a in node.names:
                names[a.asname or a.name] = f"{node.module}.{a.name}"
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("atlas."):
                    names[a.asname or a.name.split(".")[0]] = a.name
    return names


def test_no_private_names_across_modules():
    offences = []
    for path, tree in _modules():
        rel = path.relative_to(ROOT)
        if path.name == "__init__.py":  # a package may use its own private modules
            continue
        aliases = _atlas_aliases(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("atlas"):
                offences += [
                    f"{rel}:{node.lineno} from {node.module} import {a.name}"
                    for a in node.names
                    if a.name.startswith("_") and not a.name.startswith("__")
                ]
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
            ):
                offences.append(f"{rel}:{node.lineno} {node.value.id}.{node.attr}")
    assert not offences, "\n".join(offences)
