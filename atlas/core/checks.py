"""The one validator of the Python API's arguments: one-line ``ValueError`` naming the parameter.

* :func:`real`: real, finite numbers (no booleans, complex numbers, strings or objects);
* :func:`pair`: one real number for both contacts or exactly two;
* :func:`boolean`: ``True`` or ``False`` (``"no"``, ``1`` or ``None`` are refused, not read);
* :func:`float_dtype`: the working precision, ``"float32"`` or ``"float64"`` only (a float16
  kernel has no error model, and its codes differ);
* :func:`integer`, :func:`choice`: integers in a range, one of a few words;
* :func:`axis_size`: an axis whose values alone exceed the memory (``MemoryError``, ``size:``).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "real",
    "pair",
    "boolean",
    "positive_int",
    "float_dtype",
    "FLOAT_DTYPES",
    "integer",
    "choice",
    "axis_size",
]

FLOAT_DTYPES = ("float64", "float32")


def real(name: str, value, *, finite: bool = True) -> np.ndarray:
    """``value`` as a float64 array, or ``ValueError`` naming ``name`` when it holds anything but
    real numbers (booleans, complex numbers, strings, objects) or, with ``finite``, NaN or inf."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise ValueError(f"{name}: expected real numbers, got {value!r}")
    try:
        arr = np.asarray(value)
    except Exception:
        raise ValueError(f"{name}: expected real numbers, got {value!r}") from None
    if arr.dtype.kind not in "iuf":  # b: booleans, c: complex, U/S: text, O: objects
        raise ValueError(f"{name}: expected real numbers, got {value!r}")
    arr = arr.astype(np.float64)
    if finite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    return arr


def pair(name: str, value) -> np.ndarray:
    """One real number (both contacts) or exactly two, as a float64 array of shape (2,)."""
    arr = real(name, value)
    if arr.shape not in ((), (2,)):
        raise ValueError(f"{name}: expected one number or two (one per contact), got {value!r}")
    return np.broadcast_to(arr, (2,)).copy()


def boolean(name: str, value) -> bool:
    """``value`` if it is ``True`` or ``False`` (numpy booleans included), else ``ValueError``."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{name}: expected True or False, got {value!r}")


def positive_int(name: str, value) -> int:
    """``value`` as an ``int`` if it is an integral number >= 1 (not a bool), else ``ValueError``."""
    bad = ValueError(f"{name}: must be a positive integer, got {value!r}")
    if isinstance(value, (bool, np.bool_)):
        raise bad
    try:
        n = int(value)
    except (TypeError, ValueError):
        raise bad from None
    if n < 1 or n != value:
        raise bad
    return n


def float_dtype(value, name: str = "dtype") -> str:
    """``"float32"`` or ``"float64"`` from a name or a numpy float type, else ``ValueError``."""
    try:
        plain = value is None or isinstance(value, (str, bool))
        dt = None if plain else np.dtype(value)
    except TypeError:
        dt = None
    text = value if isinstance(value, str) else (dt.name if dt is not None else None)
    if text not in FLOAT_DTYPES:
        raise ValueError(f"{name}: must be float32 or float64, got {value!r}")
    return text


def integer(name: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an ``int`` if it is an integral number (numpy integers and integral floats
    included; booleans and strings refused) in ``[lo, hi]``, else ``ValueError`` naming ``name``."""
    bound = " and ".join(
        b for b in (f">= {lo}" if lo is not None else "", f"<= {hi}" if hi is not None else "") if b
    )
    bad = ValueError(f"{name}: must be an integer{' ' + bound if bound else ''}, got {value!r}")
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise bad
    try:
        n = int(value)
        whole = n == value
    except (TypeError, ValueError, OverflowError):
        raise bad from None
    if not whole or (lo is not None and n < lo) or (hi is not None and n > hi):
        raise bad
    return n


def choice(name: str, value, options) -> str:
    """``value`` if it is one of the strings ``options``, else ``ValueError`` naming ``name``."""
    if not isinstance(value, str) or value not in options:
        raise ValueError(f"{name}: must be one of {', '.join(options)}, got {value!r}")
    return value


def axis_size(name: str, n: int, available: int | None, itemsize: int = 8) -> int:
    """``n`` values of an axis, or ``MemoryError`` (``size: ...``, naming ``name``) when the axis
    alone (``n * itemsize`` bytes) needs more than ``available`` bytes of memory."""
    need = n * itemsize
    if available is not None and need > available:
        raise MemoryError(
            f"size: {name} has {n:.3g} values: ~{need / 2**40:.3g} TiB of memory for the axis "
            f"alone, {available / 2**30:.3g} GiB available; use fewer values"
        )
    return n


def plain(value):
    """A numpy scalar (``np.float32(1e-10)``, ``np.int64(2)``) as the Python number it holds;
    anything else unchanged, for the range checks that follow to accept or name."""
    if isinstance(value, np.generic) and not isinstance(value, np.bool_):
        return value.item()
    return value


def model_values(name: str, value) -> np.ndarray:
    """Values of a model parameter as float64: ``kappa > 0``, ``q``, ``q1``, ``q2 >= 0``, all
    finite, else the one-line ``ValueError`` of the command line naming ``name``."""
    arr = real(name, value)
    if name == "kappa" and np.any(arr <= 0):
        raise ValueError(f"{name}: must be > 0 (k1|b1|/(k2|b2|)), got {float(np.min(arr))}")
    if name in ("q", "q1", "q2") and np.any(arr < 0):
        raise ValueError(f"{name}: must be >= 0, got {float(np.min(arr))}")
    return arr
