"""House rules a tool checks: no private names used across modules, no issue numbers outside the
changelog, no swallowed options, no function over 80 lines or module over 900 (ruff and
lint-imports are CI steps of ``.ci/run``, not tests)."""

import ast
import functools
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "atlas"


@functools.cache
def _modules() -> tuple:
    """``(path, nodes)`` of every module of the package: all nodes of its syntax tree
    (``ast.walk``), parsed and walked once for these tests."""
    return tuple(
        (p, tuple(ast.walk(ast.parse(p.read_text(), str(p)))))
        for p in sorted(PACKAGE.rglob("*.py"))
    )


def _nodes(source: str) -> tuple:
    return tuple(ast.walk(ast.parse(source)))


def _atlas_aliases(nodes) -> dict:
    """Local names bound to atlas modules: ``from atlas.core import points as p`` -> {p: ...}."""
    names = {}
    for node in nodes:
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
    for path, nodes in _modules():
        rel = path.relative_to(ROOT)
        if path.name == "__init__.py":  # a package may use its own private modules
            continue
        aliases = _atlas_aliases(nodes)
        for node in nodes:
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


#: a reference to an issue number (history belongs in the git log and CHANGELOG.md)
ISSUE = re.compile(r"issue [0-9]")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".ipynb", ".txt", ".cfg", ".json", ".csv"}


def _tracked_text_files():
    out = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    for rel in out:
        path = ROOT / rel
        if path.suffix in TEXT_SUFFIXES and rel != "CHANGELOG.md" and path.is_file():
            yield rel, path


def test_no_issue_numbers_outside_the_changelog():
    # the check can fail
    assert ISSUE.search("see issue " + "12") and not ISSUE.search("the issues")
    offences = [
        f"{rel}:{n}"
        for rel, path in _tracked_text_files()
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if ISSUE.search(line)
    ]
    assert not offences, "\n".join(offences)


def _swallowing(nodes) -> list[int]:
    """Lines of functions with a ``**_`` parameter (unknown options silently ignored)."""
    return [
        node.lineno
        for node in nodes
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        and node.args.kwarg is not None
        and node.args.kwarg.arg.startswith("_")
    ]


def test_no_parameter_swallows_unknown_options():
    assert _swallowing(_nodes("def f(a, **_):\n    pass\n")) == [1]  # the check can fail
    offences = [
        f"{path.relative_to(ROOT)}:{line}"
        for path, nodes in _modules()
        for line in _swallowing(nodes)
    ]
    assert not offences, "\n".join(offences)


#: the largest function and module of the package, in lines (decorators and docstrings counted)
MAX_FUNCTION_LINES = 80
MAX_MODULE_LINES = 900


def _long_functions(nodes, limit: int) -> list[str]:
    return [
        f"{node.lineno}: {node.name} ({n} lines)"
        for node in nodes
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        for n in [
            node.end_lineno - min([node.lineno, *(d.lineno for d in node.decorator_list)]) + 1
        ]
        if n > limit
    ]


def test_no_function_or_module_is_too_long():
    body = lambda n: "".join(f"    x{i} = {i}\n" for i in range(n))  # noqa: E731
    # the check can fail: a decorated function of 81 lines, not one of 80
    assert _long_functions(_nodes(f"@d\ndef f():\n{body(79)}"), 80)
    assert not _long_functions(_nodes(f"def f():\n{body(79)}"), 80)
    offences = [
        f"{path.relative_to(ROOT)}:{line}"
        for path, nodes in _modules()
        for line in _long_functions(nodes, MAX_FUNCTION_LINES)
    ]
    offences += [
        f"{path.relative_to(ROOT)} ({n} lines)"
        for path in sorted(PACKAGE.rglob("*.py"))
        for n in [len(path.read_text().splitlines())]
        if n > MAX_MODULE_LINES
    ]
    assert not offences, "\n".join(offences)
