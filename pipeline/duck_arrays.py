"""xarray's duck-array checks without importing dask, dask.array or pint for them.

xarray asks, on the first Variable or index it makes, whether the data is a dask array or a pint
quantity (``isinstance(data, array_type("dask"))``), and to answer it imports ``dask.array`` (~0.2 s)
and ``pint`` (~0.15 s), in every process, although hdi's own datasets hold neither (its fan-out uses
dask's scheduler, not its arrays). An object of a module's type cannot exist before that module is
imported, so until it is the answer is "no" without importing anything: :func:`defer` puts a stand-in
into xarray's cache of those modules that answers so while the module is absent from ``sys.modules``
and hands over to xarray's own entry the first time it is present (a user's ``import dask.array`` or
``import pint_xarray``, ``open_mfdataset``'s chunks). The answers are xarray's in every case; only the
imports are deferred. Measured in docs/performance.md, section "xarray's duck-array imports".

xarray also asks, for every index it makes, whether the data is a dask collection
(``xarray.namedarray.utils.is_dask_collection``), and imports dask itself to let dask answer (~0.1-0.3 s with
what dask imports: jinja2, importlib_metadata, multiprocessing, ...). dask's own answer is "no" for any object
without a ``__dask_graph__`` attribute (the dask collection protocol), whether dask is imported or not, so
:func:`defer` puts in front of xarray's function one that answers so for such objects and asks xarray's for
the rest (:func:`_dask_collection_check`).

The cache is xarray's private ``xarray.namedarray.pycompat._cached_duck_array_modules``: where a later
xarray has no such cache or entry type, :func:`defer` leaves it, and where it has no
``xarray.namedarray.utils.is_dask_collection``, that check; xarray then imports as before
(tests/core/test_duck_arrays.py says which case this xarray is).
"""

from __future__ import annotations

import functools
import importlib
import sys
from typing import Any, Callable

#: xarray's name of a duck-array module -> the module whose import makes its type exist.
DEFERRED = {"dask": "dask.array", "pint": "pint"}


def defer() -> bool:
    """Put the stand-ins of :data:`DEFERRED` into xarray's duck-array cache (the module docstring), for the
    modules xarray has not looked up yet and that are not imported, and the dask-collection check in front of
    xarray's (:func:`_defer_dask_collection_check`, which does not depend on that cache); True if xarray has
    the cache."""
    _defer_dask_collection_check()
    try:
        from xarray.namedarray import pycompat
        cache, real = pycompat._cached_duck_array_modules, pycompat.DuckArrayModule
    except (ImportError, AttributeError):  # pragma: no cover (another xarray: its imports as they are)
        return False
    if not isinstance(cache, dict):  # pragma: no cover
        return False
    for name, module in DEFERRED.items():
        if name not in cache and module not in sys.modules:
            cache[name] = _Deferred(name, module, cache, real)
    return True


#: Modules of xarray that hold its ``is_dask_collection`` under that name (the first defines it, the
#: second re-exports it).
DASK_CHECK_HOMES = ("xarray.namedarray.utils", "xarray.core.utils")


def _dask_collection_check(xarray_check: Callable[[object], bool]) -> Callable[[object], bool]:
    """xarray's ``is_dask_collection`` answered without importing dask for an object that has no
    ``__dask_graph__`` (the first condition of dask's own ``dask.base.is_dask_collection``: such an object is
    no dask collection, whatever else dask would check); any other object goes to ``xarray_check``."""

    @functools.wraps(xarray_check)
    def is_dask_collection(x: object) -> bool:
        if not hasattr(x, "__dask_graph__"):
            return False
        return xarray_check(x)

    is_dask_collection.__wrapped_by_hdi__ = True  # type: ignore[attr-defined]
    return is_dask_collection


def _defer_dask_collection_check() -> None:
    """Put :func:`_dask_collection_check` in place of xarray's ``is_dask_collection`` in
    :data:`DASK_CHECK_HOMES` (once; a module whose attribute is not xarray's function is left alone, and an
    xarray without the first home, or without the function there, keeps its own check)."""
    homes = []
    for name in DASK_CHECK_HOMES:
        try:
            homes.append(importlib.import_module(name))
        except ImportError:  # pragma: no cover (another xarray's layout)
            continue
    original = getattr(homes[0], "is_dask_collection", None) if homes else None
    if original is None or getattr(original, "__wrapped_by_hdi__", False):
        return
    wrapped = _dask_collection_check(original)
    for home in homes:
        if getattr(home, "is_dask_collection", None) is original:
            home.is_dask_collection = wrapped


class _Deferred:
    """xarray's ``DuckArrayModule`` of ``name`` before ``module`` is imported: ``type`` is empty (no object
    of it can exist yet); once ``module`` is in ``sys.modules``, or any other attribute is asked for,
    xarray's own entry is made, put in the cache in this one's place, and answers."""

    def __init__(self, name: str, module: str, cache: dict, real: type) -> None:
        self._name, self._module, self._cache, self._real = name, module, cache, real

    def _resolve(self) -> Any:
        entry = self._real(self._name)
        if self._cache.get(self._name) is self:
            self._cache[self._name] = entry
        return entry

    @property
    def type(self) -> tuple:
        if self._module not in sys.modules:
            return ()
        return self._resolve().type

    def __getattr__(self, attr: str) -> Any:  # (module, version, available: xarray's, imported now)
        if attr.startswith("_"):
            raise AttributeError(attr)
        return getattr(self._resolve(), attr)
