"""Plain objectives, targets, stand-in evaluators and twin scenes for the tests of the identification
(pipeline/analyses/identification/): a correlated quadratic, noisy records for racing, the twin experiment.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import xarray as xr

from pipeline import evaluations
from pipeline.analyses import ensemble_rules as en
from pipeline.analyses import free_parameters, identification, study
from pipeline.model.inputs import SimulationInputs, Source


RHO = 0.9
#: r = R x with R^T R = Sigma^-1 (unit variances, correlation RHO): the objective x^T Sigma^-1 x
R = np.linalg.cholesky(np.linalg.inv(np.array([[1.0, RHO], [RHO, 1.0]]))).T
#: a third residual no parameter moves: the optimum misses it (objective 4), so the interval is where the
#: objective stays within 1 of its profile minimum, the 68 % interval of a Gaussian with covariance Sigma
OFFSET = 2.0


def _targets(n: int) -> list[study.ObjectiveTerm]:
    """``n`` equality targets r0.. of value 0 and tolerance 1, each read from the output of its name."""
    return [study.ObjectiveTerm(f"r{k}", f"residual {k}", "1", "equal", 0.0, 1.0, (9.0,),
                         lambda t, k=k: t.value(f"r{k}", 9.0), "") for k in range(n)]


def _identification(residuals) -> identification.Identification:
    """An identification whose evaluations are ``residuals(x)`` (a vector per point), no stage nor store."""
    def evaluate(points):
        out = []
        for x in points:
            r = residuals(np.asarray(x, float))
            out.append({"key": repr(tuple(map(float, x))), "params": list(map(float, x)), "protrusions": [9.0],
                        "outputs": {f"r{k}": [float(v)] for k, v in enumerate(r)}})
        return out
    return identification.Identification(evaluate, _targets(len(residuals(np.zeros(2)))), 10.0)


PARAMS = [free_parameters.Parameter("dmw.rms_nm", -3.0, 3.0), free_parameters.Parameter("contact.damping_n_s_m", -3.0, 3.0)]


def _cfg(method: str = "optimised", budget: int = 80, points: int = 25, polish: bool = True) -> dict:
    return {"generations": 3, "population": 5, "seed": 1, "profile_points": points, "profile_method": method,
            "profile_evaluations": budget, "polish": polish}


def _quadratic(x: np.ndarray) -> np.ndarray:
    return np.append(R @ x, OFFSET)


# ------------------------------------------------------------------------- the evaluator's parts
def _ensemble_task(base, params, rows, protrusions, inputs, realisations, records=None):
    """A stand-in for the slider on an ensemble: record ``r``'s output is ``x0 + r`` at every protrusion."""
    a, b = records or (0, realisations)
    out = []
    for key, x in rows:
        rec = {"params": list(map(float, x)), "protrusions": list(map(float, protrusions)),
               "outputs": {"fhm_bv": [[float(x[0]) + r for r in range(a, b)] for _ in protrusions]},
               "seconds": 1.0 * (b - a), "kernel_seconds": 0.5 * (b - a), "error": None,
               "realisations": b - a, "seeds": list(range(a, b))}
        if (a, b) != (0, realisations):
            rec["first_record"] = a
        out.append((key, rec))
    return out


def _racing_evaluator(paper_scene, tmp_path):
    """An evaluator of 8 records in racing stages of 2, 4, 8 over one parameter (``dmw.rms_nm``) at 9 nm, on
    :func:`_ensemble_task` (no simulation), and its store."""
    inputs = SimulationInputs(Source("interface", key="i"), Source("dmw", key="d"))
    params = [free_parameters.Parameter("dmw.rms_nm", 0.0, 1.0)]
    store = evaluations.EvaluationStore(tmp_path / "s.jsonl")
    return evaluations.Evaluator(paper_scene, params, [9.0], inputs, store, 2, "synchronous", task=_ensemble_task,
                                 realisations=8, stages=(2, 4, 8)), store


# ------------------------------------------------------------------- racing on a noisy stand-in
RACE_RHO = 0.8
#: r = RACE_R x with RACE_R^T RACE_R = Sigma^-1 (unit variances, correlation RACE_RHO), plus a record's noise
RACE_R = np.linalg.cholesky(np.linalg.inv(np.array([[1.0, RACE_RHO], [RACE_RHO, 1.0]]))).T
N_RECORDS = 8
#: each DMW record's error of each residual, the same for every candidate (common random numbers); its
#: spread NOISE in residual units
NOISE = 0.1
ERRORS = NOISE * np.random.default_rng(7).standard_normal((N_RECORDS, 3))


def _record_values(x: np.ndarray) -> np.ndarray:
    """The residuals of each record at ``x``, shape (records, 3): two correlated ones and one the optimum
    misses by 2 (so the interval is where the objective stays within 1 of its profile minimum)."""
    base = np.append(RACE_R @ x, 2.0)
    # (an error that grows away from the optimum too: a record's noise is not the same everywhere)
    return base[None, :] + ERRORS * (1.0 + 0.3 * np.abs(x).sum())


def _mean_targets() -> list[study.ObjectiveTerm]:
    def ensemble(k):
        def f(ds: xr.Dataset) -> tuple[float, float, float]:
            mu, sd = (float(v) for v in en.mean_std(study.at_protrusions(ds, f"r{k}", (9.0,)).isel(protrusion=0)))
            return mu, mu - sd, mu + sd
        return f
    return [study.ObjectiveTerm(f"r{k}", f"residual {k}", "1", "equal", 0.0, 1.0, (9.0,),
                                lambda t, k=k: t.value(f"r{k}", 9.0), "", ensemble(k)) for k in range(3)]


def _stand_in(calls: list):
    """The evaluation callable of an ensemble identification (``evaluate(points, upto)``), counting the
    (candidate, record) pairs it is asked for in ``calls``."""
    def evaluate(points, upto=N_RECORDS):
        out = []
        for x in points:
            v = _record_values(np.asarray(x, float))[:upto]
            calls.append(upto)
            out.append({"key": repr(tuple(map(float, x))), "params": list(map(float, x)), "protrusions": [9.0],
                        "outputs": {f"r{k}": [list(map(float, v[:, k]))] for k in range(3)},
                        "realisations": upto, "seeds": list(range(upto))})
        return out
    return evaluate


def _full_cost(x: np.ndarray) -> float:
    return study.cost(_record_values(np.asarray(x, float)).mean(axis=0))


CFG = {"generations": 4, "population": 5, "seed": 2, "profile_points": 7, "profile_method": "optimised",
       "profile_evaluations": 20, "polish": True}


def _run(racing):
    calls: list[int] = []
    ident = identification.Identification(_stand_in(calls), _mean_targets(), 10.0, racing)
    out = identification.identify(ident, PARAMS, np.array([2.0, -1.0]), CFG)
    return ident, out


def _agree_within_tolerance(a: dict, b: dict, step: float, truth: np.ndarray) -> None:
    """Two identifications give the same answer within their tolerance: each optimum inside the other's interval,
    ``truth`` inside both, the interval ends within one profile ``step`` of each other."""
    for i in range(len(truth)):
        assert b["intervals"][i, 0] <= a["best"][i] <= b["intervals"][i, 1]
        assert a["intervals"][i, 0] <= b["best"][i] <= a["intervals"][i, 1]
        assert a["intervals"][i, 0] <= truth[i] <= a["intervals"][i, 1]
        assert b["intervals"][i, 0] <= truth[i] <= b["intervals"][i, 1]
    np.testing.assert_allclose(a["intervals"], b["intervals"], atol=step)


# --------------------------------------------------------------- racing against the full method on the twin
TRUE = {"dmw.rms_nm": 0.14, "lubricant.work_of_adhesion_j_m2": 0.07}

#: The twin (tests/twin.py) on 4 DMW records, its targets the ensemble's values at TRUE
ENSEMBLE_TWIN = """
targets = ["fhm_flying", "contact_force"]
fhm_flying_tolerance_percent = 0.3
contact_force_tolerance_mn = 0.05
population = 4
generations = 2
profile_points = 5
profile_evaluations = 8
batch_size = 4
realisations = 4
"""


def _ensemble_twin(write_scene, paper_config, tmp_path):
    """The twin on 4 DMW records (:data:`ENSEMBLE_TWIN`): its scene's path, the scene, its free parameters, its
    targets, the protrusions they need, their inputs and the truth's whole evaluation (at :data:`TRUE`)."""
    import twin
    from pipeline.config.scene import load_scene
    path = write_scene(twin.scene_text(ENSEMBLE_TWIN).format(paper=paper_config))
    scene = load_scene(path)
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], str(path), "identify.parameters")
    tl = study.targets(scene)
    inputs = evaluations.prepare_inputs(scene, tmp_path / "truth")
    prots = study.target_protrusions(tl)
    whole = evaluations.evaluate(scene, params, [TRUE[p.name] for p in params], prots, inputs, 4)
    return path, scene, params, tl, prots, inputs, whole


def _twin_targets(tl, whole) -> list[str]:
    """The ``--set`` options that make the truth's ensemble values the twin's targets."""
    from pipeline.physics import paper
    values, _ = study.residuals(whole, tl, 10.0)
    return [f"identify.{paper.TARGETS[t.name].value.key}={float(v)!r}" for t, v in zip(tl, values)]


def _identified_with_and_without(path, sets: list[str], option: str, tmp_path) -> tuple[xr.Dataset, xr.Dataset]:
    """identify.nc of the twin scene ``path`` (with the ``--set`` strings ``sets``) with ``identify.<option>``
    on, then off, each in a folder of its own."""
    on, off = _identified_by(path, sets, option, ("true", "false"), tmp_path)
    return on, off


def _identified_by(path, sets: list[str], option: str, values: Sequence[str], tmp_path) -> list[xr.Dataset]:
    """identify.nc of the twin scene ``path`` (with the ``--set`` strings ``sets``) for each of ``values`` of
    ``identify.<option>``, each in a folder of its own."""
    from pipeline.config.scene import load_scene
    from pipeline.runner import ensure
    runs = []
    for v in values:
        sc = load_scene(path, sets + [f"identify.{option}={v}"])
        out = ensure("identify", sc, tmp_path / f"{option}-{v}", scheduler="synchronous")
        runs.append(xr.open_dataset(out, engine="netcdf4").load())
    return runs


def _same_answer(one: xr.Dataset, other: xr.Dataset, params, scene) -> None:
    """Two identifications of the twin give the same answer within the tolerance: both within tolerance, each
    optimum inside the other's interval and the truth inside both; the interval ends within one profile step
    of each other."""
    assert one.attrs["within_tolerance"] == other.attrs["within_tolerance"] == 1
    for p in params:
        step = (p.high - p.low) / (scene["identify"]["profile_points"] - 1)
        a, b = one.sel(parameter=p.name), other.sel(parameter=p.name)
        lo_a, hi_a = a["interval"].values
        lo_b, hi_b = b["interval"].values
        assert lo_b <= float(a["best"]) <= hi_b and lo_a <= float(b["best"]) <= hi_a, (p.name, a["best"], b["best"])
        assert lo_a <= TRUE[p.name] <= hi_a and lo_b <= TRUE[p.name] <= hi_b
        np.testing.assert_allclose([lo_a, hi_a], [lo_b, hi_b], atol=step)
