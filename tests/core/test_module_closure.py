"""The import closure of a module within the package: what the kept kernels' digest covers.

References: a full :mod:`ast` walk of every module (the scan reads only the import lines), and the
modules a fresh interpreter actually loads when it imports a kernel's module."""

import ast
import importlib
import json
import subprocess
import sys
from pathlib import Path

from atlas.core import kernels, module_closure, warm

ROOT = Path(__file__).resolve().parents[2]


def _atlas_modules() -> list[str]:
    out = []
    for path in sorted((ROOT / "atlas").rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        out.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return out


def _executed(body: list) -> list:
    """Statements run on import: not in functions or classes, not under ``if TYPE_CHECKING``."""
    out = []
    for stmt in body:
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        if isinstance(stmt, ast.If):
            typing = "TYPE_CHECKING" in ast.unparse(stmt.test)
            out += ([] if typing else _executed(stmt.body)) + _executed(stmt.orelse)
        elif isinstance(stmt, (ast.Try, ast.With)):
            inner = [*stmt.body, *getattr(stmt, "orelse", []), *getattr(stmt, "finalbody", [])]
            out += _executed(inner + [s for h in getattr(stmt, "handlers", []) for s in h.body])
        else:
            out.append(stmt)
    return out


def _ast_imports(name: str) -> tuple[set, set, set]:
    """(modules imported on import, modules imported only lazily, modules named by import lines
    inside string literals) by a walk of the whole tree."""
    path = module_closure._path(name)
    tree = ast.parse(path.read_text())
    imp = (ast.Import, ast.ImportFrom)
    now = [n for s in _executed(tree.body) for n in ast.walk(s) if isinstance(n, imp)]
    nodes = list(ast.walk(tree))  # one walk of the whole tree (most of this function's time)
    every = [n for n in nodes if isinstance(n, imp)]
    typing = [
        n
        for s in tree.body
        if isinstance(s, ast.If) and "TYPE_CHECKING" in ast.unparse(s.test)
        for n in ast.walk(s)
        if isinstance(n, imp)
    ]
    lazy = [n for n in every if n not in now and n not in typing]
    texts = [n.value for n in nodes if isinstance(n, ast.Constant)]
    quoted = [n for t in texts if isinstance(t, str) for n, _ in module_closure._scan(t)]
    targets = lambda nodes: set(module_closure._targets(name, nodes))  # noqa: E731
    return targets(now), targets(lazy) - targets(now), targets(quoted)


def test_the_line_scan_finds_what_a_full_parse_finds():
    """Nothing missed; an extra only where a string literal holds an import line (a script)."""
    extras = 0
    for name in _atlas_modules():
        now, lazy, quoted = _ast_imports(name)
        got, got_lazy = set(module_closure.imports(name)), set(module_closure.lazy_imports(name))
        assert now <= got <= now | quoted, name
        assert got_lazy - quoted <= lazy <= got_lazy | got, name
        extras += len(got - now)
    assert extras < 5


def test_the_scan_can_tell_the_kinds_of_import_apart():
    """A made-up module: module level (in ``try``), lazy (in a function, a method), typing-only."""
    text = (
        '"""Doc.\nfrom atlas.core import exact\n"""\nimport numpy\n'
        "from atlas.core import (\n    signs,\n    hurwitz,\n)\n"
        "try:\n    from atlas.core import points\nexcept ImportError:\n    pass\n"
        "if TYPE_CHECKING:\n    from atlas.data import io\n"
        "def f():\n    from atlas.core import spectral\n"
        "class C:\n    def g(self):\n        import atlas.core.baseline\n"
    )
    found = {
        ast.unparse(n): where for n, where in module_closure._scan(text)
    }  # the docstring's line is taken as an import too: a harmless extra, not a miss
    assert found["from atlas.core import signs, hurwitz"] == "module"
    assert found["from atlas.core import points"] == "module"
    assert found["from atlas.data import io"] == "typing"
    assert found["from atlas.core import spectral"] == "lazy"
    assert found["import atlas.core.baseline"] == "lazy"


def _kernel_modules() -> list[str]:
    """The modules of every kept kernel (:class:`atlas.core.warm.Kernel` at module level) and of
    every registered point kernel's function."""
    import atlas.cli  # noqa: F401 - every command's modules
    import atlas.explore.inspector  # noqa: F401

    names = {k.fn.__module__ for k in kernels.KERNELS.values()}
    for name, mod in list(sys.modules.items()):
        if name.startswith("atlas") and mod is not None:
            names |= {v.module for v in vars(mod).values() if isinstance(v, warm.Kernel)}
    return sorted(names)


def test_every_kernel_module_is_found():
    mods = _kernel_modules()
    assert {"atlas.core.rootfree", "atlas.core.kernels", "atlas.explore.inspector"} <= set(mods)


def test_code_a_kernel_can_trace_imports_its_helpers_at_module_level():
    """Where a built-in kernel's closure imports an atlas module lazily, that module is in the
    closure all the same (the inspector's map helpers load the box layers lazily: host code, no
    kernel traces it; ``atlas table`` writes its file through ``atlas.data.io``, beside Table 2's
    kept kernel)."""
    host = {
        ("atlas.explore.maps", "atlas.data.over_models"),
        ("atlas.paper.tables", "atlas.data.io"),
    }
    for start in _kernel_modules():
        c = set(module_closure.closure(start))
        missing = {(m, x) for m in c for x in module_closure.lazy_imports(m) if x not in c}
        assert missing <= host, (start, missing - host)


LOADED = """
import importlib, json, sys
out = {}
for name in sys.argv[1:]:
    for m in [m for m in sys.modules if m == "atlas" or m.startswith("atlas.")]:
        del sys.modules[m]
    importlib.import_module(name)
    out[name] = sorted(m for m in sys.modules if m == "atlas" or m.startswith("atlas."))
print(json.dumps(out))
"""


def test_the_closure_is_what_a_fresh_interpreter_loads():
    """Importing a kernel's module loads exactly its closure, besides the packages and what
    ``import atlas`` itself loads (its interrupt handling)."""
    starts = ["atlas.core.rootfree", "atlas.core.kernels", "atlas.core.contact_modes"]
    p = subprocess.run(
        [sys.executable, "-c", LOADED, *starts],
        capture_output=True, text=True, cwd=ROOT, timeout=300, check=True,
    )  # fmt: skip
    loaded = json.loads(p.stdout)
    base = set(module_closure.closure("atlas"))
    for name in starts:
        real = {
            m for m in loaded[name] if module_closure._path(m).name != "__init__.py"
        }  # fmt: skip
        assert real - base == set(module_closure.closure(name)) - base, name


def test_a_module_without_a_source_follows_its_globals(monkeypatch):
    from atlas.core import hurwitz

    mod = type(sys)("made_up_script")
    mod.helper, mod.signs = hurwitz.ss_margin, importlib.import_module("atlas.core.signs")
    monkeypatch.setitem(sys.modules, "made_up_script", mod)
    got = module_closure.closure("made_up_script")
    assert {"atlas.core.hurwitz", "atlas.core.signs", "made_up_script"} <= set(got)
    assert set(module_closure.closure("atlas.core.hurwitz")) <= set(got)
