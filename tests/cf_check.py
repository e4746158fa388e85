"""Shared helper: run the IOOS compliance-checker's CF-1.8 suite on a NetCDF file."""

from __future__ import annotations

from pathlib import Path

from compliance_checker.runner import CheckSuite

CHECK = "cf:1.8"
_SUITE: CheckSuite | None = None


def cf_report(path: str | Path) -> tuple[dict[int, list[str]], list[str]]:
    """``({weight: [failure messages]}, [checks that raised])`` of the CF-1.8 checker on ``path``.

    Weights are the checker's priorities: 3 high (errors), 2 medium (warnings), 1 low (info).
    """
    global _SUITE
    if _SUITE is None:
        _SUITE = CheckSuite()
        _SUITE.load_all_available_checkers()
    ds = _SUITE.load_dataset(str(path))
    groups, errors = _SUITE.run_all(ds, [CHECK], skip_checks=[])[CHECK]
    failures: dict[int, list[str]] = {3: [], 2: [], 1: []}
    for result in groups:
        passed, total = result.value if isinstance(result.value, tuple) else (int(bool(result.value)), 1)
        if passed < total:
            failures.setdefault(result.weight, []).extend(f"{result.name}: {m}" for m in result.msgs)
    ds.close()
    return failures, sorted(errors)
