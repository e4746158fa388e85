"""How the kernel's functions are compiled (pipeline.model.compiled): every kernel function is cached on
disk, releases the GIL and uses numpy's error model (a division by zero is inf, not an exception); its
cache folder is named by the code key of its module and everything that module imports, so an edited law
inlined into the kernel gets a new folder; the decoration leaves numba's global cache folder as it was."""

from __future__ import annotations

import os

import numba
import numpy as np
import pytest

from pipeline.code_version import code_key
from pipeline.model import compiled, piecewise, static_solver


def test_cache_folder_is_named_by_the_modules_code_key():
    folder = compiled.cache_folder("pipeline.model.dynamics")
    assert os.path.basename(folder) == "numba-" + code_key("pipeline.model.dynamics")[:16]
    # dynamics imports more of the package than piecewise: their code keys, and so their folders, differ
    assert compiled.cache_folder("pipeline.model.piecewise") != folder
    assert compiled.cache_folder("pipeline.model.piecewise") == compiled.cache_folder("pipeline.model.piecewise")


def test_kernel_functions_carry_the_options_and_their_cache_folder():
    for fn, module in ((piecewise.ppval, "pipeline.model.piecewise"), (static_solver._newton,
                                                                       "pipeline.model.static_solver")):
        assert fn.targetoptions["nogil"] and fn.targetoptions["error_model"] == "numpy", fn
        assert type(fn._cache).__name__ == "FunctionCache"  # cache=True (a plain njit has a NullCache)
        assert os.path.dirname(fn._cache._cache_path) == compiled.cache_folder(module)


def test_kernel_jit_compiles_with_the_options_and_restores_the_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))

    @compiled.kernel_jit("pipeline.model.piecewise", inline="always")
    def ratio(a, b):
        return a / b

    assert numba.config.CACHE_DIR == str(tmp_path)  # (set around the decoration only)
    assert ratio.targetoptions["nogil"] and ratio.targetoptions["inline"] == "always"
    assert os.path.dirname(ratio._cache._cache_path) == compiled.cache_folder("pipeline.model.piecewise")
    assert ratio(1.0, 0.0) == np.inf and np.isnan(ratio(0.0, 0.0))  # numpy's error model: no ZeroDivisionError
    with pytest.raises(TypeError):
        compiled.kernel_jit("pipeline.model.piecewise", nogil=False)(lambda x: x)  # options cannot be overridden
    assert numba.config.CACHE_DIR == str(tmp_path)
