"""Layer 2, atlases as data: scenes, the output registry, the tiled engine, netCDF/zarr I/O, dask.

* :mod:`~atlas.data.scene`       what to compute: axes, fixed values, outputs (SPEC §3);
* :mod:`~atlas.data.engine`      tiles of a scene through the core kernels into storage arrays;
* :mod:`~atlas.data.io`          netCDF sinks and atomic writes;
* :mod:`~atlas.data.distributed` the same tiles on a dask cluster into a zarr store.
"""
