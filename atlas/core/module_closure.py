"""The atlas modules whose code a module can run: the module itself and every ``atlas`` module it
imports at module level, transitively (its import closure within the package).

Read from the source files (their import statements), not from ``sys.modules``: the closure is the same in every
process, whatever the entry point imported before.  Module-level imports are followed wherever
they stand (``try``, ``if``, ``with`` blocks; not ``if TYPE_CHECKING:``, which never runs); imports
inside functions and classes are not (a module imported only lazily is outside the closure: the
code a kernel traces imports its helpers at module level: ``tests/core/test_module_closure.py``
checks that the lazy imports of the closures of the built-in kernels are in them all the same), nor names a package attaches lazily (PEP 562).
``from atlas.core import points`` follows the module ``atlas.core.points``; a name that is no
module (``from atlas.core.verdicts import Verdict``) follows the module it is taken from.  A module
without a source file (``python -c``) is followed through the atlas modules, functions and
classes its globals hold.  :mod:`atlas.core.warm` digests the live code of this closure of each
kept kernel's module.
"""

from __future__ import annotations

import ast
import functools
import re
import sys
import types
from pathlib import Path

__all__ = ["closure", "imports", "lazy_imports"]

#: the directory of the ``atlas`` package
PACKAGE = Path(__file__).resolve().parents[1]


@functools.cache
def closure(name: str) -> tuple[str, ...]:
    """``name`` and the atlas modules it imports at module level, transitively, sorted."""
    seen, todo = set(), [name]
    while todo:
        mod = todo.pop()
        if mod not in seen:
            seen.add(mod)
            todo += imports(mod)
    return tuple(sorted(seen))


@functools.cache
def imports(name: str) -> tuple[str, ...]:
    """The atlas modules module ``name`` imports at module level (module docstring)."""
    found = _import_statements(name)
    if found is None:
        return _global_modules(sys.modules.get(name))
    return _targets(name, [node for node, where in found if where == "module"])


def lazy_imports(name: str) -> tuple[str, ...]:
    """The atlas modules module ``name`` imports inside its functions and classes only."""
    found = _import_statements(name) or []
    lazy = _targets(name, [node for node, where in found if where == "lazy"])
    return tuple(sorted(set(lazy) - set(imports(name))))


def _targets(name: str, nodes) -> tuple[str, ...]:
    """The atlas modules the ``import`` statements ``nodes`` of module ``name`` load."""
    out = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] == "atlas"}
        else:
            base = _absolute(name, node.module or "", node.level)
            if base.split(".")[0] == "atlas":
                for a in node.names:
                    sub = f"{base}.{a.name}"
                    out.add(sub if _path(sub) is not None else base)
    return tuple(sorted(out))


#: the start of an import statement (a line beginning with ``from`` or ``import``)
_IMPORT = re.compile(r"^([ \t]*)(?:from|import)[ \t][^\n]*", re.M)
#: a compound statement at column 0: what an indented line below it belongs to
_HEADER = re.compile(
    r"^(?:(?:async[ \t]+)?def[ \t]+\w+[ \t]*\(|class[ \t]+\w+[ \t]*[(:]|@|if[ \t(]|try[ \t]*:"
    r"|with[ \t(]|else[ \t]*:|elif[ \t(]|except\b|finally[ \t]*:)[^\n]*",
    re.M,
)


@functools.cache
def _import_statements(name: str) -> list | None:
    """:func:`_scan` of module ``name``'s source (``None``: no source file)."""
    path = _path(name)
    return None if path is None else _scan(path.read_text())


def _scan(text: str) -> list:
    """``(node, where)`` of the import statements of a module's source ``text``, ``where`` being
    ``"module"`` (run on import), ``"lazy"`` (in a function or class) or ``"typing"`` (``if
    TYPE_CHECKING:``).  Found by a scan of the lines, each statement parsed alone (parsing whole
    modules costs ~0.1 s per kernel at start-up); a docstring line that parses as an import is
    taken as one (an extra module, never a missed one)."""
    headers = [(m.start(), m.group()) for m in _HEADER.finditer(text)]
    out = []
    for m in _IMPORT.finditer(text):
        stmt = m.group().strip()
        if "(" in stmt and ")" not in stmt:
            stmt = text[m.start() : text.find(")", m.start()) + 1].strip()
        try:
            node = ast.parse(stmt).body[0]
        except (SyntaxError, IndexError):  # prose in a docstring
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append((node, _context(m.group(1), m.start(), headers)))
    return out


def _context(indent: str, at: int, headers: list) -> str:
    """Where an import statement at offset ``at`` stands (:func:`_import_statements`)."""
    if not indent:
        return "module"
    header = next((h for pos, h in reversed(headers) if pos < at), "")
    if header.startswith(("def", "async", "class", "@")):
        return "lazy"
    if header.startswith("if") and "TYPE_CHECKING" in header:
        return "typing"
    return "module"


def _absolute(name: str, module: str, level: int) -> str:
    """The absolute name of a (possibly relative) ``from`` import in module ``name``."""
    if not level:
        return module
    path = _path(name)
    package = name if path is not None and path.name == "__init__.py" else name.rpartition(".")[0]
    parts = package.split(".")[: len(package.split(".")) - level + 1]
    return ".".join(parts + ([module] if module else []))


def _path(name: str) -> Path | None:
    """The source file of module ``name`` (``None``: no source file)."""
    parts = name.split(".")
    if parts[0] == "atlas":
        base = PACKAGE.joinpath(*parts[1:])
        for path in (base.with_suffix(".py"), base / "__init__.py"):
            if path.is_file():
                return path
        return None
    file = getattr(sys.modules.get(name), "__file__", None)
    return Path(file) if file and file.endswith(".py") and Path(file).is_file() else None


def _global_modules(mod) -> tuple[str, ...]:
    """The atlas modules of the modules, functions and classes among ``mod``'s globals."""
    out = set()
    for value in vars(mod).values() if mod is not None else ():
        if isinstance(value, types.ModuleType):
            where = value.__name__
        else:
            where = getattr(value, "__module__", None)
            if not isinstance(where, str) or not isinstance(value, (type, types.FunctionType)):
                continue
        if where.split(".")[0] == "atlas":
            out.add(where)
    return tuple(sorted(out))
