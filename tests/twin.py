"""The twin scene of the identification tests and a stand-in for the slider's evaluations.

The twin: the paper scene with short runs (0.8 ms, the steady window from 0.3 ms), k fixed (no
calibration) and two free parameters, the DMW amplitude and the work of adhesion; each test adds its
own targets and budget. The stand-in returns evaluation records (:mod:`pipeline.evaluations`) whose
outputs are given functions of the parameters, for tests of the stage around the fit, not of the fit.
"""

from __future__ import annotations

from typing import Callable, Sequence

#: The twin's scene file up to its ``[identify]`` targets and budget: ``{paper}`` is the scene it extends,
#: ``{name}`` its name (``str.format``; the TOML braces are doubled).
HEAD = """
[scene]
name = "{name}"
extends = "{{paper}}"

[solver]
duration_ms = 0.8
transient_ms = 0.3

[contact]
k = 0.978

[identify]
parameters = [{{{{key = "dmw.rms_nm", low = 0.08, high = 0.25}}}},
              {{{{key = "lubricant.work_of_adhesion_j_m2", low = 0.03, high = 0.11}}}}]
"""


def scene_text(identify: str, name: str = "twin") -> str:
    """The twin's scene text with the ``[identify]`` lines ``identify`` (targets, tolerances, budget), still
    to be formatted with ``paper=`` (the path of the scene it extends)."""
    return HEAD.format(name=name) + identify.lstrip("\n")


def stub_records(rows: Sequence[tuple[str, Sequence[float]]], protrusions: Sequence[float],
                 outputs: Callable[[Sequence[float]], dict[str, float]]) -> list[tuple[str, dict]]:
    """Evaluation records of ``rows = [(key, parameter values), ...]`` as ``evaluate_batch`` returns them, with
    ``outputs(values) -> {name: value}`` (dataset units) at every protrusion and no time spent."""
    n = len(protrusions)
    return [(key, {"params": [float(v) for v in x], "protrusions": [float(p) for p in protrusions],
                   "outputs": {name: [float(v)] * n for name, v in outputs(x).items()},
                   "seconds": 0.0, "kernel_seconds": 0.0, "error": None}) for key, x in rows]
