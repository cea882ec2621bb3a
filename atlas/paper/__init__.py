"""Layer 4, the paper: its cases, Table 2, the figures, the audit of its claims, and ``atlas paper``."""

from atlas.paper.run import FILES, REFERENCE, atomic_write_text, files, run, write_netcdf

__all__ = ["FILES", "REFERENCE", "atomic_write_text", "files", "run", "write_netcdf"]
