"""Shared helpers of the hard-case tests: how much headline outputs change under refinement."""

from __future__ import annotations

import numpy as np

NM = 1e-9


def deltas(a: dict, b: dict, fh0: float = 11 * NM) -> dict[str, tuple[float, float]]:
    """Relative and absolute [nm] changes of fhm_bv, clearance and contact_force between two summaries."""
    out = {}
    for name, to_nm in (("fhm_bv", fh0 / 100 / NM), ("clearance", 1 / NM), ("contact_force", None)):
        if name not in a:
            continue
        x, y = a[name], b[name]
        big = max(abs(x), abs(y))
        rel = abs(x - y) / big if big > 0 else 0.0
        out[name] = (rel, abs(x - y) * to_nm if to_nm else np.inf)
    return out


def assert_converged(d: dict, what: str, skip: tuple = ()) -> None:
    """Each change below 1 % relative or 1e-3 nm absolute (the hard-case criterion of the issue)."""
    for name, (rel, abs_nm) in d.items():
        if name in skip:
            continue
        assert rel < 0.01 or abs_nm < 1e-3, f"{what}: {name} changed by {rel:.3%} ({abs_nm:.3g} nm)"
