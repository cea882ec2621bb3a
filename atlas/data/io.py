"""netCDF4 files of atlases: encodings, atomic writes, and streaming generation.

Two ways to a file, producing the same file (same variables, types, attributes, chunks):

* :func:`write_netcdf` writes an in-memory :class:`xarray.Dataset` (from :func:`atlas.generate`)
  with the ``netcdf4`` engine;
* :func:`generate_to_file` never holds the full arrays: :func:`atlas.data.engine.run` hands each tile
  to a :class:`NetCDFSink`, which writes it into a ``netCDF4.Dataset`` opened directly.  Memory is
  bounded by the tile (and the 2-D ``model_dependent_*`` accumulators), so atlases larger than
  memory work.  This is what ``atlas generate`` uses.

Both write to a temporary file ``.NAME.XXXX.tmp`` in the target directory and ``os.replace`` it onto
the final name only after the file is complete and closed; on any error (or KeyboardInterrupt) the
temporary file is removed.  An existing file is replaced only with ``overwrite=True`` and is never
left half-written; an interrupted run leaves nothing under the final name.

Encodings (xarray issues #1576, #6055): integer flag variables get no ``_FillValue`` (an int8 with a
fill value reads back as float), coordinates get ``_FillValue = None`` (no NaN fill), booleans are
stored as int8 with the attribute ``dtype = "bool"`` (xarray's convention, read back as bool).
Compression: zlib level 4 with shuffle; chunks = the generation tiles
(:func:`atlas.data.engine.block_shape`), so each tile writes whole chunks.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import tempfile
from typing import TYPE_CHECKING

import numpy as np

from atlas.core import interrupts
from atlas.data.engine import DEFAULT_TILE_POINTS, RunOptions, Schema, Sink, block_shape, run
from atlas.data.scene import Scene

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "write_netcdf",
    "generate_to_file",
    "check_output_path",
    "AtomicFile",
    "committed_together",
    "write_error",
    "atomic_path",
    "atomic_write_text",
    "savefig",
    "FIGURE_METADATA",
    "NetCDFSink",
    "COMPLEVEL",
]

COMPLEVEL = 4


def check_output_path(path, overwrite: bool = False) -> str:
    """Validate an output path before any work: ``OSError`` naming ``out`` if it cannot be used."""
    path = os.fspath(path)
    if not path:
        raise OSError("out: empty path")
    directory = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise IsADirectoryError(f"out: {path} is a directory")
    if not os.path.isdir(directory):
        raise FileNotFoundError(f"out: directory {directory} does not exist")
    try:  # a real probe: os.access says yes to root even on a read-only file system
        fd, probe = tempfile.mkstemp(prefix=".atlas-probe-", dir=directory)
        try:
            os.close(fd)
        finally:
            os.unlink(probe)
    except OSError as e:
        raise PermissionError(
            f"out: directory {directory} is not writable ({e.strerror})"
        ) from None
    if os.path.exists(path) and not overwrite:
        raise FileExistsError(f"out: {path} exists (use --overwrite to replace it)")
    return path


def write_error(path, exc: BaseException, name: str = "out") -> OSError | None:
    """One-line ``OSError`` naming the parameter ``name``, ``path`` and the cause of a failed write (``None`` when
    ``exc`` is not a write failure: a bug stays a bug).  netCDF/HDF errors carry no ``errno``: a
    full file system is recognised by its free space."""
    if isinstance(exc, OSError) and exc.errno is not None:
        cause = exc.strerror or str(exc)
        if exc.errno == errno.ENOSPC:
            cause = "no space left on device"
    elif isinstance(exc, (OSError, RuntimeError)) and str(exc).startswith(("NetCDF", "HDF")):
        cause = str(exc)
        directory = os.path.dirname(os.path.abspath(os.fspath(path)))
        with contextlib.suppress(OSError):
            if shutil.disk_usage(directory).free < _FULL:
                cause = f"no space left on device ({cause})"
    else:
        return None
    err = OSError(f"{name}: cannot write {os.fspath(path)}: {cause}")
    err.errno = getattr(exc, "errno", None) if isinstance(exc, OSError) else None
    return err


#: free bytes below which a netCDF/HDF write error is reported as a full file system
_FULL = 1 << 20

#: the paths committed in this process since :func:`forget_commits` (for an honest interrupt message)
COMMITTED: list[str] = []


def forget_commits() -> None:
    COMMITTED.clear()


#: the AtomicFiles of the innermost :func:`committed_together` block (``None``: commit at once)
_GROUP: list | None = None


@contextlib.contextmanager
def committed_together(overwrite: bool | None = None):
    """Every :class:`AtomicFile` committed inside the block is renamed onto its path only when the
    block ends without error, all together; otherwise none is (their temporary files are removed).
    Multi-file outputs (``atlas boundaries``' netCDF, CSV and GeoJSON, ``atlas paper``) are thus
    complete or absent.  Nested blocks join the outermost one.  ``overwrite`` (if not None)
    applies to every file of the block: ``False`` refuses to replace any existing file."""
    global _GROUP
    if _GROUP is not None:
        yield
        return
    _GROUP = pending = []
    try:
        yield
        _GROUP = None
        interrupts.check()
        for f in pending:
            if overwrite is not None:
                f.overwrite = overwrite
            f.check_target()
        for f in pending:
            f.rename()
    except BaseException:
        for f in pending:
            f.discard()
        raise
    finally:
        _GROUP = None


class AtomicFile:
    """The one atomic write of the package: a temporary file in the target directory, renamed onto
    ``path`` (``os.replace``) by :meth:`commit` or removed by :meth:`discard`.  An existing ``path``
    is never left half-written, and is replaced only with ``overwrite=True``.  As a context manager
    it yields the temporary path and commits when the block ends without error.

    The temporary file is only *named* here (``.<name>.<random>.tmp``, 96 random bits); the writer
    creates it.  So an interrupt can never leave a file that the owner of this object does not know
    about: once the object exists, :meth:`discard` removes whatever was written."""

    def __init__(self, path, overwrite: bool = True, suffix: str = ".tmp"):
        self.path = os.fspath(path)
        self.overwrite = overwrite
        directory = os.path.dirname(os.path.abspath(self.path))
        os.makedirs(directory, exist_ok=True)  # the library's writers create their directory
        name = os.path.basename(self.path)
        self.tmp = os.path.join(directory, f".{name}.{secrets.token_hex(12)}{suffix}")

    def commit(self) -> str:
        """Rename the temporary file onto ``path`` (inside :func:`committed_together`: when the
        block ends); nothing is committed after a stop signal
        (:func:`atlas.core.interrupts.check`): the temporary file is removed instead."""
        try:
            interrupts.check()
            self.check_target()
            if _GROUP is not None:
                _GROUP.append(self)
                return self.path
            self.rename()
        except BaseException:
            self.discard()
            raise
        return self.path

    def check_target(self) -> None:
        if not self.overwrite and os.path.exists(self.path):
            raise FileExistsError(f"out: {self.path} exists (use --overwrite to replace it)")

    def rename(self) -> None:
        os.chmod(self.tmp, 0o644 & ~_umask())
        try:
            os.replace(self.tmp, self.path)
        finally:  # an interrupt just after the rename still names the file it completed
            if not os.path.exists(self.tmp):
                COMMITTED.append(self.path)

    def discard(self) -> None:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.tmp)

    def __enter__(self) -> str:
        return self.tmp

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.commit()
            return
        self.discard()
        err = write_error(self.path, exc)
        if err is not None:
            raise err from None


atomic_path = AtomicFile  # ``with atomic_path(path) as tmp: ...``


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_text(path, text: str, overwrite: bool = True) -> str:
    """Write a text file atomically (:func:`atomic_path`)."""
    with atomic_path(path, overwrite) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    return os.fspath(path)


#: metadata of the figures :func:`savefig` writes: no dates and no versions, so that a figure is
#: a pure function of what is drawn (two runs give the same bytes)
FIGURE_METADATA = {
    ".png": {"Software": None},
    ".pdf": {"Creator": None, "Producer": None, "CreationDate": None, "ModDate": None},
    ".svg": {"Creator": None, "Date": None},
}


def savefig(fig, path, dpi: int = 120, **kwargs) -> str:
    """``fig.savefig`` atomically (:func:`atomic_path`); the format follows the suffix of ``path``;
    the metadata are :data:`FIGURE_METADATA` (``metadata=`` adds to them), SVG ids not random."""
    suffix = os.path.splitext(os.fspath(path))[1] or ".png"
    metadata = {**FIGURE_METADATA.get(suffix.lower(), {}), **kwargs.pop("metadata", {})}
    import matplotlib  # noqa: PLC0415 - loaded already: ``fig`` is a matplotlib figure

    with (
        atomic_path(path, suffix=".tmp" + suffix) as tmp,
        matplotlib.rc_context({"svg.hashsalt": "painleve-atlas"}),  # SVG ids: not random
    ):
        fig.savefig(tmp, dpi=dpi, metadata=metadata or None, **kwargs)
    return os.fspath(path)


def encoding(ds: xr.Dataset, tile_points: int = DEFAULT_TILE_POINTS) -> dict:
    """Per-variable netCDF4 encodings: compression, tile chunks, no fill values."""
    enc = {}
    for name, var in ds.variables.items():
        if name in ds.coords:
            enc[name] = {"_FillValue": None}
            continue
        e = {"_FillValue": None}
        if var.ndim:
            e.update(
                zlib=True,
                complevel=COMPLEVEL,
                shuffle=True,
                chunksizes=block_shape(var.shape, tile_points),
            )
        enc[name] = e
    return enc


def write_netcdf(ds: xr.Dataset, path, overwrite: bool = False, tile_points=DEFAULT_TILE_POINTS):
    """Write an atlas to a netCDF4 file atomically (see the module docstring).

    Parameters
    ----------
    ds : xarray.Dataset
        An atlas from :func:`atlas.generate`.
    path : str or os.PathLike
        Target file; its directory must exist and be writable.
    overwrite : bool
        Replace an existing file (atomically).  Without it an existing file raises
        ``FileExistsError`` and is left untouched.
    tile_points : int
        Chunk size in points (use the value the atlas was generated with).
    """
    path = check_output_path(path, overwrite)
    with atomic_path(path, overwrite) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding(ds, tile_points))
    return path


class NetCDFSink(Sink):
    """Writes tiles from :func:`atlas.data.engine.run` straight into a netCDF4 file (streaming)."""

    def __init__(self, path, overwrite: bool = False):
        self.path = check_output_path(path, overwrite)
        self.overwrite = overwrite
        self.file = None
        self.nc = None

    def begin(self, sch: Schema):
        self.file = AtomicFile(self.path, self.overwrite)
        with self._reported():
            self._begin(sch)

    @contextlib.contextmanager
    def _reported(self):
        """A failed write (a full disk: netCDF says only "HDF error") as one line naming ``path``."""
        try:
            yield
        except Exception as e:
            err = write_error(self.path, e)
            if err is None:
                raise
            raise err from None

    def _begin(self, sch: Schema):
        import netCDF4

        nc = self.nc = netCDF4.Dataset(self.file.tmp, "w", format="NETCDF4")
        nc.set_auto_mask(False)
        for dim, n in sch.shape.items():
            nc.createDimension(dim, n)
        scalar = []
        for name, (dims, values, attrs) in sch.coords.items():
            v = nc.createVariable(name, np.asarray(values).dtype, dims, fill_value=False)
            v.setncatts(attrs)
            v[...] = values
            if not dims:
                scalar.append(name)
        self.vars = {}
        for name, (dims, dt, attrs, chunks) in sch.variables.items():
            stored = np.dtype(np.int8) if dt == np.dtype(bool) else dt
            kw = dict(fill_value=False)
            if dims:
                kw.update(zlib=True, complevel=COMPLEVEL, shuffle=True, chunksizes=tuple(chunks))
            v = nc.createVariable(name, stored, dims, **kw)
            a = dict(attrs)
            if dt == np.dtype(bool):
                a["dtype"] = "bool"
            if scalar:
                a["coordinates"] = " ".join(scalar)
            v.setncatts(a)
            self.vars[name] = (v, stored)
        nc.setncatts(sch.attrs)

    def write(self, name, index, block):
        interrupts.check()  # a stop signal lost in a gc callback still ends the run here
        v, stored = self.vars[name]
        with self._reported():
            v[index] = np.asarray(block).astype(stored, copy=False)

    def finish(self, attrs: dict, var_attrs: dict):
        with self._reported():
            for name, a in var_attrs.items():
                self.vars[name][0].setncatts(a)
            self.nc.setncatts(attrs)
            self.nc.close()
            self.nc = None
        return self.file.commit()

    def abort(self):
        if self.nc is not None:
            try:
                self.nc.close()
            except Exception:  # pragma: no cover - best effort on an already failing path
                pass
            self.nc = None
        if self.file is not None:
            self.file.discard()


def generate_to_file(
    scene: Scene,
    path,
    options: RunOptions | None = None,
    *,
    overwrite: bool = False,
    **changes,
) -> dict:
    """Generate an atlas tile by tile straight into a netCDF4 file (memory bounded by the tile).

    Same options as :func:`atlas.generate` (:class:`atlas.data.engine.RunOptions`, or changed by
    name); the file equals ``write_netcdf(generate(...))``.  Returns the run's diagnostics
    (:class:`atlas.data.engine.Run`) with ``path`` and ``bytes`` (file size).
    """
    opts = RunOptions.of(options, **changes)
    sink = NetCDFSink(path, overwrite)
    stats = run(scene, sink, opts).stats
    return {**stats, "path": sink.path, "bytes": os.path.getsize(sink.path)}
