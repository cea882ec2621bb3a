"""Layer 4, the paper: its cases, Table 2, the figures, the audit of its claims, and ``atlas paper``.

The names below load on first use (``lazy_loader``): ``atlas table`` needs Table 2, not the
figures."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "run": ["FILES", "REFERENCE", "atomic_write_text", "files", "run", "write_netcdf"]
    },
)
