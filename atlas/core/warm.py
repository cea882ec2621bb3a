"""Kernels that start warm: jitted kernels kept as serialized ``jax.export`` programs on disk.

A small run spends its seconds before any arithmetic: tracing the kernels in Python, lowering them
to StableHLO, then (with the persistent compilation cache) loading the compiled executables.  A
:class:`Kernel` (:func:`jit`, used where the package calls ``jax.jit`` on a top-level kernel)
keeps, while :func:`kernel_cache` is active, the exported program of each (kernel, static options,
input shapes and dtypes) in ``<compilation cache>/kernels``: the first process exports and stores
it, every later one deserializes it and skips tracing and lowering; the compiled executable then
comes from the persistent compilation cache.

Staleness.  A file's name holds a digest of the JAX and jaxlib versions, the backend, float64, and
the *live* code of the kernel's module and of every atlas module it imports at module level,
transitively (:mod:`atlas.core.module_closure`; the code objects, defaults, closures and constants
of their module-level names, as loaded in this process): an edited or monkeypatched kernel function gets new files, never an old program.

Compiled executables.  Beside each program the first process also keeps its compiled executable
(``.xlaexec``, :mod:`jax.experimental.serialize_executable`), so that a later process skips the
lowering and the compilation-cache look-up as well.  XLA's CPU client serializes an executable
completely only when it was compiled in the process: one it loaded from the persistent compilation
cache serializes without the code of its fusions, and loading it elsewhere fails with
``NOT_FOUND: Function ..._fusion`` when a result is read.  So an executable is stored only after
its serialized form has been loaded and checked in the process; one the cache served fails that
check, and the program is compiled afresh for it (the caches bypassed, once).  Every executable is
validated before use: a canary input (the first call's own arguments, their first
:data:`CANARY` values repeated to the shape) must give results whose SHA-256 equals that of the
compiled program's results on it in the process that compiled it (where the executable is
stored only if its serialized form, loaded again, passes too); a loaded executable that fails
(or raises, on the canary or on a call) is never used, the exported program runs instead.  The
stored executable is XLA's compilation of the same program with the same options as the
exported program's ``jax.jit``: the same results (the tests compare the two in fresh processes).
Programs with custom calls (LAPACK) keep no executable.  Executables are machine code for this
host and these compiler flags: their names also hold the host's CPU flags and ``$XLA_FLAGS``.
``$ATLAS_KERNEL_EXECUTABLES=0`` keeps none.

Without :func:`kernel_cache` (the library's default; the CLI turns it on for the command it runs)
or with the compilation cache off, a :class:`Kernel` is exactly ``jax.jit``.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import itertools
import os
import pickle
import platform
import sys
import threading
import types
from pathlib import Path

import jax
import jaxlib
import numpy as np

from atlas.core import config, module_closure

__all__ = [
    "Kernel",
    "current_kernel",
    "active_cache",
    "jit",
    "kernel_cache",
    "keep_kernels",
    "save_used",
    "KERNEL_ENV",
    "EXECUTABLE_ENV",
]

#: environment variable: ``0`` keeps :func:`kernel_cache` off
KERNEL_ENV = "ATLAS_KERNEL_CACHE"
#: environment variable: ``0`` keeps no compiled executables (the exported programs only)
EXECUTABLE_ENV = "ATLAS_KERNEL_EXECUTABLES"
#: values of each argument kept as the canary input of a stored executable
CANARY = 256
_STATE: dict = {
    "dir": None, "run": None, "digests": {}, "used": [], "prefetch": {}, "manifest": None
}  # fmt: skip
#: held while the compilation cache is switched off for a fresh compilation
_FRESH = threading.Lock()
#: the :func:`kernel_cache` block :func:`keep_kernels` keeps open until the process exits
_SESSION: dict = {"stack": None, "run": None}
#: per thread: the name of the :class:`Kernel` whose program is being exported, compiled or
#: loaded (:func:`current_kernel`)
_LOADING = threading.local()
_LOADS = itertools.count()


@contextlib.contextmanager
def kernel_cache(where: str | None = None, run: str | None = None):
    """Within the block, :class:`Kernel` calls use (and fill) the exported programs in ``where``
    (default ``<compilation cache>/kernels``; nothing if the compilation cache is off or
    ``$ATLAS_KERNEL_CACHE`` is ``0``).  ``run`` names this kind of run (the CLI: the command line
    without its output paths): the executables the last run of that name used are loaded in
    background threads from the start of the block (each still checked on its canary)."""
    before = dict(_STATE)
    if where is None and os.environ.get(KERNEL_ENV, "") != "0":
        base = config.compile_cache_dir()
        where = None if base is None else os.path.join(base, "kernels")
    manifest = None
    if where is not None and run is not None and os.environ.get(EXECUTABLE_ENV, "") != "0":
        manifest = Path(where) / f"run-{hashlib.sha256(run.encode()).hexdigest()[:24]}.txt"
    _STATE.update(
        dir=where, run=run, digests={}, used=[], prefetch=_prefetch(manifest), manifest=manifest
    )
    try:
        yield where
    finally:
        for future in _STATE["prefetch"].values():
            future.cancel()
        save_used()
        _STATE.update(before)


def active_cache() -> tuple[str | None, str | None]:
    """``(where, run)`` of the active :func:`kernel_cache` block (``(None, None)``: none), for a
    helper process to open its own block on the same kept kernels."""
    return _STATE["dir"], _STATE["run"]


def save_used() -> None:
    """Write the list of executables the active :func:`kernel_cache` block (with a ``run``
    name) used so far, which the next block of that name loads in the background (done when a
    block ends; a long-lived session calls it once warm)."""
    manifest, used = _STATE["manifest"], "\n".join(_STATE["used"])
    if manifest is not None and used and _read_text(manifest) != used:
        _write(manifest, used.encode())


def keep_kernels(run: str) -> str | None:
    """Turn on, for the rest of this process, the persistent compilation cache
    (:func:`atlas.core.config.use_compile_cache`) and a :func:`kernel_cache` block named ``run``:
    a long-lived session (the notebook explorer's kernel) keeps and reuses compiled kernels like
    the CLI, with the same switches (``$ATLAS_JAX_CACHE=0``, ``$ATLAS_KERNEL_CACHE=0``).  The
    block ends when the process exits (:func:`save_used` also writes its list then).  Returns
    the kernels directory (``None``: off); a second call changes nothing, whatever its ``run``."""
    if _SESSION["stack"] is None:
        config.use_compile_cache()
        stack = contextlib.ExitStack()
        stack.enter_context(kernel_cache(run=run))
        _SESSION.update(stack=stack, run=run)
        import atexit  # noqa: PLC0415

        atexit.register(stack.close)
    return _STATE["dir"]


def current_kernel() -> tuple[str, int] | None:
    """The name of the :class:`Kernel` this thread is exporting, compiling or loading a program
    of (``module.function``) and the serial number of that load, else ``None``: what a listener
    of JAX's compilation events (:mod:`jax.monitoring`) attributes them to
    (:mod:`atlas.bench.startup_programs`)."""
    return getattr(_LOADING, "name", None)


def _read_text(path: Path) -> str:
    try:
        return path.read_text()
    except (OSError, ValueError):
        return ""


def _prefetch(manifest: Path | None) -> dict:
    """``{file name: future}`` of the executables listed in ``manifest``, loading in the
    background (:func:`_load_executable`)."""
    names = _read_text(manifest).split() if manifest is not None else []
    if not names:
        return {}
    from concurrent.futures import ThreadPoolExecutor  # noqa: PLC0415

    pool = ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1), thread_name_prefix="warm")
    futures = {n: pool.submit(_load_executable, manifest.parent / n) for n in names}
    pool.shutdown(wait=False)
    return futures


class Kernel:
    """``jax.jit(fn, static_argnames=...)``, whose traced and lowered program is kept on disk
    while :func:`kernel_cache` is active (module docstring).  Arguments: arrays (numpy, NumPy
    scalars or concrete JAX) positionally, static options by keyword."""

    def __init__(self, fn, static_argnames=()):
        self.fn = fn
        self.static_argnames = tuple(static_argnames)
        self.jitted = jax.jit(fn, static_argnames=self.static_argnames or None)
        base = fn.func if isinstance(fn, functools.partial) else fn
        self.module = base.__module__
        self.name = f"{base.__module__}.{base.__qualname__}".replace("<", "").replace(">", "")
        #: the function's own code, closure and bound options (lambdas share a name)
        self.code = hashlib.sha256(_value_digest(fn, 3)).hexdigest()
        self._calls: dict = {}
        self._lock = threading.Lock()
        functools.update_wrapper(self, fn)

    def __call__(self, *args, **static):
        where = _STATE["dir"]
        # a NumPy scalar is a 0-d array to jax.jit as well (strongly typed, unlike a Python one)
        args = tuple(np.asarray(a) if isinstance(a, np.generic) else a for a in args)
        if where is None or not all(_concrete(a) for a in args):
            return self.jitted(*args, **static)
        avals = tuple((tuple(a.shape), np.dtype(a.dtype).str) for a in args)
        key = (where, _digest(self.module), self.code, avals, tuple(sorted(static.items())))
        call = self._calls.get(key)
        if call is None:
            with self._lock:  # threads asking at once (a warm-up and a first use) load it once
                call = self._calls.get(key)
                if call is None:
                    _LOADING.name = (self.name, next(_LOADS))
                    try:
                        call = self._calls[key] = self._load(Path(where), key, args, static)
                    finally:
                        _LOADING.name = None
        return call(*args)

    def __getattr__(self, name):  # the rest of the jax.jit API: lower, trace, ...
        jitted = self.__dict__.get("jitted")
        if jitted is None:
            raise AttributeError(name)
        return getattr(jitted, name)

    def _load(self, where: Path, key, args, static):
        """``jax.jit`` of the exported program of ``key``: read from ``where``, or exported and
        written there (atomically) first; its compiled executable too, when it can be kept."""
        text = repr((self.name, key[1:]))
        path = where / f"{self.name}-{hashlib.sha256(text.encode()).hexdigest()[:24]}.jaxexport"
        host = hashlib.sha256(f"{text} {_host()}".encode()).hexdigest()[:24]
        xpath = where / f"{self.name}-{host}.xlaexec"
        specs = [jax.ShapeDtypeStruct(a.shape, a.dtype) for a in args]
        executables = os.environ.get(EXECUTABLE_ENV, "") != "0"
        future = _STATE["prefetch"].pop(xpath.name, None)
        call = None
        if executables:
            call = future.result() if future is not None else _load_executable(xpath)
        if call is not None:
            _STATE["used"].append(xpath.name)
            return _Guarded(call, lambda: jax.jit(self._export(path, specs, static).call))
        exp = self._export(path, specs, static)
        compiled = _store_executable(xpath, exp, args) if executables else None
        if compiled is None:
            return jax.jit(exp.call)
        _STATE["used"].append(xpath.name)
        return _Guarded(compiled, lambda: jax.jit(exp.call))

    def _export(self, path: Path, specs, static):
        """The ``jax.export`` program of this kernel for the argument ``specs``: read from
        ``path``, or exported and written there (atomically) first."""
        from jax import export  # noqa: PLC0415 - jax.export loads on first use only

        exp = None
        if path.exists():
            try:
                exp = export.deserialize(bytearray(path.read_bytes()))
            except Exception:  # a damaged file: export again
                exp = None
        if exp is None:
            fn = functools.partial(self.fn, **static) if static else self.fn
            exp = export.export(jax.jit(fn))(*specs)
            _write(path, exp.serialize())
        return exp


class _Guarded:
    """An executable whose calls fall back to the exported program: on an error when it is
    called (e.g. arguments it was not compiled for) or, on its first call, when the results are
    read.  Later calls dispatch asynchronously (the same executable, already run on the canary
    and on the first call)."""

    def __init__(self, compiled, exported):
        self.compiled, self.exported, self.fallback = compiled, exported, None
        self.checked = False

    def __call__(self, *args):
        if self.compiled is not None:
            try:
                out = self.compiled(*args)
                if not self.checked:
                    out = jax.block_until_ready(out)
                    self.checked = True
                return out
            except Exception:  # noqa: BLE001 - any failure: the exported program decides
                self.compiled = None
        if self.fallback is None:
            self.fallback = self.exported()
        return self.fallback(*args)


def _write(path: Path, data: bytes) -> None:
    """``data`` into ``path`` atomically (nothing if the cache is read-only)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)
    except OSError:  # a read-only cache: just use the program
        pass


def _host() -> str:
    """What an executable is compiled for besides its program: the machine (architecture, CPU
    flags) and the compiler's flags (``$XLA_FLAGS``, JAX's default matmul precision)."""
    flags = ""
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line for line in f if line.startswith(("flags", "Features"))), "")
    except OSError:
        pass
    precision = jax.config.jax_default_matmul_precision
    return (
        f"{platform.machine()} {platform.processor()} {flags.strip()} "
        f"XLA_FLAGS={os.environ.get('XLA_FLAGS', '')} precision={precision}"
    )


def _canary(sample, shape, dtype):
    return np.resize(np.asarray(sample, dtype), shape)


def _result_digest(out) -> str:
    h = hashlib.sha256()
    for leaf in jax.tree_util.tree_leaves(out):
        a = np.asarray(leaf)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _store_executable(xpath: Path, exp, args):
    """``exp`` compiled, kept in ``xpath`` once its serialized form, loaded again, gives the
    canary's results bit for bit; returns the compiled program (``None`` on any failure: nothing
    is kept).  An executable the compilation cache served does not serialize completely (module
    docstring): then the program is compiled afresh, the caches bypassed."""
    from jax.experimental import serialize_executable  # noqa: PLC0415

    try:
        if "custom_call" in exp.mlir_module():
            return None
        specs = [jax.ShapeDtypeStruct(a.shape, a.dtype) for a in args]
        samples = [np.asarray(a).reshape(-1)[:CANARY].copy() for a in args]
        canary = [_canary(c, a.shape, a.dtype) for c, a in zip(samples, args)]
        for fresh in (False, True):
            if fresh:
                compiled = _compile_afresh(exp, specs)
            else:
                compiled = jax.jit(exp.call).lower(*specs).compile()
            want = _result_digest(compiled(*canary))
            blob, in_tree, out_tree = serialize_executable.serialize(compiled)
            try:
                again = serialize_executable.deserialize_and_load(blob, in_tree, out_tree)
                ok = _result_digest(again(*canary)) == want
            except Exception:  # noqa: BLE001 - incomplete: NOT_FOUND when read
                ok = False
            if ok:
                record = {
                    "executable": (blob, in_tree, out_tree),
                    "canary": samples,
                    "digest": want,
                }
                _write(xpath, pickle.dumps(record, protocol=pickle.HIGHEST_PROTOCOL))
                return compiled
    except Exception:  # noqa: BLE001 - no executable: the exported program serves
        pass
    return None


def _compile_afresh(exp, specs):
    """``exp`` compiled in this process: the in-memory and persistent compilation caches bypassed
    (the other kernels of the process are compiled or loaded again when next used)."""
    with _FRESH, _no_compilation_cache():
        jax.clear_caches()
        return jax.jit(exp.call).lower(*specs).compile()


@contextlib.contextmanager
def _no_compilation_cache():
    """Within the block, compilations neither read nor write the persistent compilation cache."""
    from jax.experimental.compilation_cache import compilation_cache  # noqa: PLC0415

    cached = jax.config.jax_enable_compilation_cache
    try:
        jax.config.update("jax_enable_compilation_cache", False)
        compilation_cache.reset_cache()
        yield
    finally:
        jax.config.update("jax_enable_compilation_cache", cached)
        compilation_cache.reset_cache()


def _load_executable(xpath: Path):
    """The executable in ``xpath`` if it exists, loads, and reproduces its canary digest; else
    ``None``."""
    if not xpath.exists():
        return None
    from jax.experimental import serialize_executable  # noqa: PLC0415

    try:
        record = pickle.loads(xpath.read_bytes())
        compiled = serialize_executable.deserialize_and_load(*record["executable"])
        avals = jax.tree_util.tree_leaves(compiled.in_avals)
        canary = [_canary(c, a.shape, a.dtype) for c, a in zip(record["canary"], avals)]
        if len(canary) == len(avals) and _result_digest(compiled(*canary)) == record["digest"]:
            return compiled
    except Exception:  # noqa: BLE001 - damaged, foreign or failing: not used
        pass
    return None


def jit(fn=None, *, static_argnames=()):
    """:class:`Kernel` as a decorator (``@warm.jit`` or ``@warm.jit(static_argnames=...)``)."""
    if fn is None:
        return lambda f: Kernel(f, static_argnames)
    return Kernel(fn, static_argnames)


def _concrete(a) -> bool:
    return isinstance(a, (np.ndarray, jax.Array)) and not isinstance(a, jax.core.Tracer)


def _digest(module: str) -> str:
    """Digest of the software, the backend and the live code of ``module`` and of every atlas
    module it imports at module level, transitively (:func:`atlas.core.module_closure.closure`,
    read from the sources: the same set whatever the entry point imported before); once per
    :func:`kernel_cache` block and module.  A module-valued name is skipped (a package holds its
    submodules as they happen to be imported; a module's own code is digested in its turn).
    This module and :mod:`~atlas.core.module_closure` are left out: they choose a program's file,
    not what a traced program computes."""
    got = _STATE["digests"].get(module)
    if got is None:
        h = hashlib.sha256()
        dev = jax.devices()[0]
        h.update(
            f"{jax.__version__} {jaxlib.__version__} {dev.platform} {dev.device_kind}".encode()
        )
        h.update(str(bool(jax.config.jax_enable_x64)).encode())
        for name in module_closure.closure(module):
            if name in (__name__, module_closure.__name__):
                continue
            mod = sys.modules.get(name) or _import(name)
            h.update(name.encode())
            for attr, value in sorted(vars(mod).items()) if mod else ():
                if not isinstance(value, types.ModuleType):
                    h.update(attr.encode())
                    h.update(_value_digest(value, 3))
        got = _STATE["digests"][module] = h.hexdigest()
    return got


def _import(name: str):
    """The module ``name`` imported (``None`` if it cannot be)."""
    try:
        return importlib.import_module(name)
    except ImportError:
        return None


def _code_digest(code: types.CodeType) -> bytes:
    """The byte code, names and constants of ``code`` (``marshal`` output depends on reference
    counts, so it differs between processes)."""
    parts = [code.co_code, repr((code.co_names, code.co_varnames, code.co_freevars)).encode()]
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            parts.append(_code_digest(const))
        elif isinstance(const, frozenset):
            parts.append(repr(sorted(map(repr, const))).encode())
        else:
            parts.append(repr(const).encode())
    return b"".join(parts)


def _value_digest(value, depth: int) -> bytes:
    """Bytes that change when a module-level name's code or constant value changes."""
    if depth < 0:
        return b""
    if isinstance(value, Kernel):
        return _value_digest(value.fn, depth)
    if isinstance(value, functools.partial):
        kw = sorted(value.keywords.items())
        return _value_digest((value.func, *value.args, *(x for item in kw for x in item)), depth)
    wrapped = getattr(value, "__wrapped__", None)
    if wrapped is not None and not isinstance(value, types.FunctionType):  # jax.jit objects
        return _value_digest(wrapped, depth)
    if isinstance(value, types.FunctionType):
        if not value.__module__.startswith("atlas"):  # a library's: its versions are elsewhere
            return f"{value.__module__}.{value.__qualname__}".encode()
        kw = sorted((value.__kwdefaults__ or {}).items())
        parts = [_code_digest(value.__code__)]
        parts.append(
            _value_digest((*(value.__defaults__ or ()), *(x for i in kw for x in i)), depth)
        )
        for cell in value.__closure__ or ():
            try:
                parts.append(_value_digest(cell.cell_contents, depth - 1))
            except ValueError:  # an empty cell
                pass
        return b"".join(parts)
    if isinstance(value, (int, float, complex, str, bytes, bool, type(None))):
        return repr(value).encode()
    if isinstance(value, tuple):
        return b"(" + b",".join(_value_digest(v, depth - 1) for v in value) + b")"
    if isinstance(value, frozenset):
        return b"{" + b",".join(sorted(_value_digest(v, depth - 1) for v in value)) + b"}"
    if isinstance(value, np.ndarray):
        return value.tobytes()
    return type(value).__qualname__.encode()  # no repr: it may hold an address
