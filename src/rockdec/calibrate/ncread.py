"""A small NetCDF file read whole with netCDF4 alone: no xarray, pandas or Dask to import.

``rockdec estimate`` with its calibration in the cache reads one small NetCDF file
(:func:`rockdec.calibrate.calibration.load_or_build`); xarray and the libraries it loads (pandas,
Dask) would take longer to import than the rest of the command takes to run. :func:`read`
gives the subset of :class:`xarray.Dataset` the calibration's readers use: ``ds[name]``
with ``.values``, ``.dims``, ``.sizes``, ``.attrs`` and ``.sel(dim=label)`` (one label of a dimension
that has a coordinate), ``ds.sizes`` and ``ds.attrs``; values decoded as xarray decodes them
(``_FillValue`` to NaN in float variables, character arrays with ``_Encoding`` to strings).
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = ["Stored", "read"]


class Variable(NamedTuple):
    """One variable: its ``dims``, ``values`` and ``attrs``, and the file it came from (for ``sel``)."""

    dims: tuple[str, ...]
    values: np.ndarray
    attrs: dict
    dataset: Stored

    @property
    def sizes(self) -> dict[str, int]:
        """The length of each of the variable's dimensions."""
        return dict(zip(self.dims, self.values.shape))

    def sel(self, **labels) -> Variable:
        """The variable at one label of each dimension named, found in its coordinate."""
        values, dims = self.values, list(self.dims)
        for dim, label in labels.items():
            coordinate = self.dataset[dim].values
            hits = np.flatnonzero(coordinate == label)
            if hits.size != 1:
                raise KeyError(f"{label!r} is not one label of {dim}")
            values = np.take(values, hits[0], axis=dims.index(dim))
            dims.remove(dim)
        return Variable(tuple(dims), values, self.attrs, self.dataset)


class Stored:
    """The variables and global attributes of a NetCDF file (:func:`read`)."""

    def __init__(self, variables: dict[str, tuple[tuple[str, ...], np.ndarray, dict]], sizes: dict[str, int], attrs: dict):
        self._variables = variables
        self.sizes = sizes
        self.attrs = attrs

    def __getitem__(self, name: str) -> Variable:
        """Variable ``name``; a dimension without a coordinate variable counts 0, 1, ... (as in xarray)."""
        if name not in self._variables and name in self.sizes:
            return Variable((name,), np.arange(self.sizes[name]), {}, self)
        return Variable(*self._variables[name], self)

    def __contains__(self, name: str) -> bool:
        return name in self._variables


def _decoded(var) -> np.ndarray:
    """The values of a netCDF4 variable as xarray decodes them."""
    values = var[...]
    if np.ma.isMaskedArray(values):
        values = values.filled(np.nan) if values.dtype.kind == "f" else values.data
    return np.asarray(values)


def read(path: str | Path) -> Stored:
    """Every variable and attribute of the NetCDF file at ``path`` (raises ``OSError`` when
    it is no readable NetCDF file)."""
    import netCDF4

    variables = {}
    with netCDF4.Dataset(path, "r") as nc:
        for name, var in nc.variables.items():
            values = _decoded(var)  # a character array arrives as strings, its last dimension gone
            attrs = {k: var.getncattr(k) for k in var.ncattrs() if not k.startswith("_")}
            variables[name] = (tuple(var.dimensions[: values.ndim]), values, attrs)
        sizes = {name: len(dim) for name, dim in nc.dimensions.items() if not any(
            name in var.dimensions[len(variables[v][0]):] for v, var in nc.variables.items())}
        attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
    return Stored(variables, sizes, attrs)
