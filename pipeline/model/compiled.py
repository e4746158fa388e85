"""How the kernel's functions are compiled: numba options and the on-disk cache folder.

numba's on-disk cache of a jitted function checks the timestamp of the file that holds it, not of
the files whose functions it inlines (e.g. the air-bearing laws of :mod:`pipeline.physics.air_bearing`
inlined into the right-hand side): with an edited law the kernel would load its old machine code
while the runner (which keys on the code) recomputes the results. So each kernel module's functions
are cached in a folder named by the code key of that module and of everything it imports
(:func:`pipeline.code_version.code_key`). numba picks a function's cache folder when it is
decorated, so :func:`kernel_jit` sets the folder around the decoration only.
"""

from __future__ import annotations

import os
from typing import Callable

import numba
from numba import njit

from ..code_version import code_key

#: Options of every kernel function: cached on disk, releases the GIL, numpy's error model (a division
#: by zero gives inf/nan, no exception path in the machine code).
OPTIONS = dict(cache=True, nogil=True, error_model="numpy")


def cache_folder(module: str) -> str:
    """The numba cache folder of the kernel module ``module`` (a dotted name): named by its code key."""
    base = numba.config.CACHE_DIR or os.path.join(os.path.dirname(__file__), "__pycache__")
    return os.path.join(base, f"numba-{code_key(module)[:16]}")


def kernel_jit(module: str, **options) -> Callable[[Callable], Callable]:
    """A decorator compiling a function of the module ``module`` with :data:`OPTIONS` (and ``options``,
    e.g. ``inline="always"``), cached in :func:`cache_folder` of the module."""
    folder = cache_folder(module)

    def decorate(fn: Callable) -> Callable:
        saved = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = folder
        try:
            return njit(**OPTIONS, **options)(fn)
        finally:
            numba.config.CACHE_DIR = saved

    return decorate
