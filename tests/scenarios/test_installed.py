"""The package as a user gets it: the wheel built from this tree, installed (with the versions of uv.lock)
into fresh virtual environments, one per extra, used from empty folders outside the clone.

* the wheel ships every scene of configs/ byte for byte, and each loads in the installed package to the
  same configuration as in the clone (``extends`` chains between shipped scenes included);
* every script of docs/examples/, copied out of the clone, runs in the plain install (no extra);
* ``hdi dmw paper-2009-identified`` finds the shipped scene by name;
* each extra imports what the docs promise: ``units`` quantifies a dataset with pint (docs/datasets.md),
  ``cluster`` serves dask's dashboard pages and writes a dask-jobqueue job script (docs/scaling.md),
  ``notebook`` lets tqdm draw the progress widget of a notebook (docs/cli.md) where the plain install falls
  back to text with a warning.

It needs uv (``.bootstrap/bin/uv``, which ``make test`` installs, or one on the PATH) and PyPI or uv's cache.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from pipeline.config.loading import load_scene

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "docs" / "examples"
#: What the wheel is built from (copied out, so the build's own folders never land in the clone)
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "pipeline", "configs")
#: Per extra, the imports the docs name for it (docs/datasets.md, docs/scaling.md)
EXTRAS = {"units": ("cf_xarray.units", "pint_xarray"), "cluster": ("bokeh", "dask_jobqueue"),
          "notebook": ("ipywidgets",)}

pytestmark = pytest.mark.slow


def _uv() -> str:
    local = ROOT / ".bootstrap" / "bin" / "uv"
    found = str(local) if local.is_file() else shutil.which("uv")
    if found is None:
        pytest.skip("uv is not installed (`make test` installs it into .bootstrap/)")
    return found


def _env() -> dict[str, str]:
    """The environment of every child: nothing that would import from the clone or a developer's venv."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    return {**env, "UV_PYTHON_DOWNLOADS": "never", "UV_COMPILE_BYTECODE": "0", "MPLBACKEND": "Agg"}


def _run(args: list[str], cwd: Path, timeout: float = 600, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(args, cwd=cwd, env=env or _env(), capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{' '.join(map(str, args))}:\n{done.stderr[-3000:]}"
    return done.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel of this tree, built by uv in a copy of the sources."""
    uv, tmp = _uv(), tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "build")
    for name in SOURCES:
        item = ROOT / name
        if item.is_dir():  # (symlinks=True: pipeline/scenes/ keeps its links to ../../configs/)
            shutil.copytree(item, src / name, symlinks=True, ignore=ignore)
        else:
            shutil.copy2(item, src / name)
    _run([uv, "build", "--wheel", "--out-dir", str(tmp / "dist")], cwd=src)
    (found,) = (tmp / "dist").glob("hdi_dynamics-*.whl")
    return found


def _install(wheel: Path, extra: str | None, folder: Path) -> Path:
    """A fresh virtual environment in ``folder`` with the wheel (and ``extra``) at the lock's versions;
    its ``bin`` folder."""
    uv = _uv()
    pins = folder / "constraints.txt"
    _run([uv, "export", "--frozen", "--no-hashes", "--no-emit-project", "--quiet", "-o", str(pins),
          *(["--extra", extra] if extra else [])], cwd=ROOT)
    _run([uv, "venv", "--quiet", "--python", sys.executable, str(folder / "env")], cwd=folder)
    python = folder / "env" / "bin" / "python"
    _run([uv, "pip", "install", "--quiet", "--python", str(python), "-c", str(pins),
          f"{wheel}[{extra}]" if extra else str(wheel)], cwd=folder)
    return python.parent


def _python(bin_dir: Path, code: str, cwd: Path, env: dict[str, str] | None = None) -> dict:
    """Run ``code`` with the environment's Python in ``cwd``; the JSON of its last line."""
    return json.loads(_run([str(bin_dir / "python"), "-c", code], cwd, env=env).strip().splitlines()[-1])


def _empty(folder: Path) -> Path:
    folder.mkdir(parents=True)
    return folder


def test_the_wheel_ships_every_scene(wheel):
    with zipfile.ZipFile(wheel) as whl:
        # (the files, not the folder's own entry: uv's wheels list folders too)
        shipped = {Path(n).name: whl.read(n) for n in whl.namelist()
                   if n.startswith("pipeline/scenes/") and not n.endswith("/")}
    assert shipped == {p.name: p.read_bytes() for p in (ROOT / "configs").glob("*.toml")}
    assert "paper-2009.toml" in shipped


def test_the_wheel_ships_the_license(wheel):
    with zipfile.ZipFile(wheel) as whl:
        (meta,) = [n for n in whl.namelist() if n.endswith(".dist-info/METADATA")]
        head = whl.read(meta).decode().split("\n\n")[0].splitlines()
        (licence,) = [n for n in whl.namelist() if n.endswith(".dist-info/licenses/LICENSE")]
        assert whl.read(licence) == (ROOT / "LICENSE").read_bytes()
    assert "License-Expression: BSD-3-Clause" in head and "License-File: LICENSE" in head


SCENES_JSON = """
import json
import pipeline
from pipeline.config.loading import load_scene, shipped_scenes
def plain(scene):
    config = json.loads(json.dumps(scene.config, sort_keys=True, default=str))
    config["scene"].pop("extends", None)  # (the absolute path of the base: the install's, not the clone's)
    return config
print(json.dumps({"package": pipeline.__file__, "files": {n: str(p) for n, p in shipped_scenes().items()},
                  "scenes": {n: plain(load_scene(n)) for n in shipped_scenes()}}))
"""


def test_every_example_runs_from_an_empty_folder_on_the_installed_wheel(wheel, tmp_path):
    bin_dir = _install(wheel, None, tmp_path / "plain")
    cwd = _empty(tmp_path / "cwd")
    got = _python(bin_dir, SCENES_JSON, cwd)
    site = bin_dir.parent / "lib"
    assert Path(got["package"]).is_relative_to(site) and not Path(got["package"]).is_relative_to(ROOT)
    assert set(got["files"]) == {p.stem for p in (ROOT / "configs").glob("*.toml")}
    assert all(Path(p).is_relative_to(site) for p in got["files"].values())
    for name, config in got["scenes"].items():  # the same scene as the clone's file, bases merged alike
        here = json.loads(json.dumps(load_scene(ROOT / "configs" / f"{name}.toml").config, sort_keys=True,
                                     default=str))
        here["scene"].pop("extends", None)
        assert config == here, name
    assert got["scenes"]["paper-2009-identified"]["air_bearing"]["bulge"] == "ph-limit"  # from its base's base
    # without the cluster extra, dask's dashboard is the page asking for bokeh (what the extra adds)
    assert _python(bin_dir, DASHBOARD, cwd) == {"status": 200, "needs_bokeh": True}

    # each script copied out of the clone (as a user copies it), one numba cache for the three
    scripts = _empty(tmp_path / "scripts")
    env = {**_env(), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    results = {}
    for script in sorted(EXAMPLES.glob("*.py")):
        shutil.copy2(script, scripts / script.name)
        out = tmp_path / "out" / script.stem
        # (the folder as the argument, or for one script as HDI_EXAMPLES_OUT: the two ways each script's usage names)
        by_env = script.stem == "ensemble"
        args = [str(bin_dir / "python"), str(scripts / script.name)] + ([] if by_env else [str(out)])
        text = _run(args, cwd, env={**env, "HDI_EXAMPLES_OUT": str(out)} if by_env else env)
        results[script.stem] = json.loads(text.strip().splitlines()[-1])
        assert list(cwd.iterdir()) == []  # (it wrote only into the folder it was given)
    assert set(results) == {"quickstart", "ensemble", "open_mfdataset"}
    quick = results["quickstart"]
    assert quick["history_samples"] == 2401  # 0.6 ms at 0.25 us, both ends
    assert quick["protrusions"] == [9.5, 10.0, 10.5] and quick["sweep_fhm_bv"][1] == quick["fhm_bv_10nm"]
    assert all(0.01 < v < 100.0 for v in quick["sweep_fhm_bv"])  # BV [%] in light contact
    assert (tmp_path / "out" / "quickstart" / "quickstart.png").stat().st_size > 10_000
    assert (tmp_path / "out" / "quickstart" / "sweep.nc").is_file()
    ens = results["ensemble"]
    assert ens["realisations"] == 3 and len(ens["fhm_bv"]) == len(ens["protrusions"]) == 3
    for row, mean in zip(ens["fhm_bv"], ens["fhm_bv_mean"]):
        assert len(set(row)) == 3  # three records, three outcomes
        assert 0.01 < min(row) <= mean <= max(row) < 100.0
    assert all(0.0 <= p <= 1.0 for p in ens["touchdown_probability"])
    assert (tmp_path / "out" / "ensemble" / "ensemble.png").is_file()
    mf = results["open_mfdataset"]
    assert mf["dims"] == {"rms": 2, "protrusion": 3, "roughness": 1, "damping": 1} and mf["units"] == "%"
    low, high = mf["fhm_bv"]
    assert all(0.01 < a < b < 100.0 for a, b in zip(low, high))  # a larger DMW, a larger BV


def test_units_extra_quantifies_what_hdi_writes_for_a_shipped_scene(wheel, tmp_path):
    bin_dir = _install(wheel, "units", tmp_path / "units")
    cwd = _empty(tmp_path / "cwd")
    _run([str(bin_dir / "hdi"), "dmw", "paper-2009-identified", "-q"], cwd)  # by name, into results/<name>
    dmw = cwd / "results" / "paper-2009-identified" / "dmw.nc"
    got = _python(bin_dir, f"""
import json
import {", ".join(EXTRAS["units"])}
import xarray as xr
ds = xr.open_dataset({str(dmw)!r}, engine="netcdf4")
q = ds.pint.quantify()
d = q["displacement"].pint.to("m")
print(json.dumps({{"units": str(q["displacement"].pint.units), "ratio": float(d.max() / ds["displacement"].max())}}))
""", cwd)
    # tol: pint's factor 1e-9 against the literal, IEEE arithmetic alone: an ulp or two
    assert got["units"] == "nanometer" and got["ratio"] == pytest.approx(1e-9, rel=1e-12)


#: A notebook's cells, as a user of the installed wheel with the ``units`` extra runs them: a shipped scene by
#: name, its model in memory (no results folder), two protrusions with one history kept, the history quantified
#: with pint and plotted with its units on the axes (docs/datasets.md, "Variables, CF conventions and units")
NOTEBOOK = """
import json, os
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import cf_xarray.units, pint_xarray
import pipeline as hdi
scene = hdi.load_scene("paper-2009-identified", ["solver.duration_ms=0.6"])
model = hdi.build_model(scene, None)
ds = hdi.simulate(model, [9.0, 10.0], histories=[10.0])
q = ds.pint.quantify()
h = q["h_clearance"].isel(hist_protrusion=0)  # (the one kept: 10 nm; a quantified coordinate wants a quantity to .sel)
fig, ax = plt.subplots()
ax.plot(h["elapsed_time"].pint.to("ms").pint.magnitude, h.pint.to("nm").pint.magnitude)
ax.set_xlabel(f"elapsed time [{h['elapsed_time'].pint.to('ms').pint.units:~P}]")
ax.set_ylabel(f"clearance [{h.pint.units:~P}]")
fig.savefig("history.png", dpi=80)
print(json.dumps({"units": str(h.pint.units), "time_units": str(h["elapsed_time"].pint.units),
                  "samples": int(h.sizes["elapsed_time"]), "mean_nm": float(h.pint.to("nm").mean().pint.magnitude),
                  "steady_nm": float(ds["clearance"].sel(protrusion=10.0)), "png": os.path.getsize("history.png"),
                  "folders": sorted(os.listdir("."))}))
"""


def test_a_notebook_builds_a_model_in_memory_and_plots_a_quantified_history(wheel, tmp_path):
    bin_dir = _install(wheel, "units", tmp_path / "units")
    cwd = _empty(tmp_path / "cwd")
    got = _python(bin_dir, NOTEBOOK, cwd, env={**_env(), "NUMBA_CACHE_DIR": str(tmp_path / "numba")})
    assert got["units"] == "nanometer" and got["time_units"] == "second"
    assert got["samples"] == 2401  # 0.6 ms at 0.25 us, both ends
    # in light contact at 10 nm the history's mean clearance is negative (an interference), as its steady scalar
    assert got["mean_nm"] < 0.0 and got["steady_nm"] < 0.0 and abs(got["mean_nm"] - got["steady_nm"]) < 0.5
    assert got["png"] > 10_000
    assert got["folders"] == ["history.png"]  # in memory: no results folder written


#: Dask's dashboard page as a browser gets it: without bokeh >= 3.1 the scheduler serves a page that
#: says "Dask needs bokeh>=3.1.0" instead of the dashboard
DASHBOARD = """
import json, urllib.parse, urllib.request
from distributed import LocalCluster
with LocalCluster(n_workers=0, processes=False, dashboard_address="127.0.0.1:0") as cluster:
    port = urllib.parse.urlparse(cluster.dashboard_link).port  # (the link names the host's address)
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/status", timeout=60) as page:
        status, body = page.status, page.read().decode()
print(json.dumps({"status": status, "needs_bokeh": "Dask needs bokeh" in body}))
"""


def test_cluster_extra_serves_the_dashboard_and_writes_job_scripts(wheel, tmp_path):
    bin_dir = _install(wheel, "cluster", tmp_path / "cluster")
    cwd = _empty(tmp_path / "cwd")
    assert _python(bin_dir, DASHBOARD, cwd) == {"status": 200, "needs_bokeh": False}
    got = _python(bin_dir, f"""
import json
import {", ".join(EXTRAS["cluster"])}
from dask_jobqueue import SLURMCluster
# (docs/scaling.md's cluster.py; the job script is written without a batch system)
with SLURMCluster(cores=16, processes=16, memory="32GB", walltime="02:00:00", queue="compute",
                  account="my-project", job_extra_directives=["--exclusive"],
                  scheduler_options={{"dashboard_address": "127.0.0.1:0"}}) as slurm:
    script = slurm.job_script()
print(json.dumps({{"bokeh": bokeh.__version__, "script": script}}))
""", cwd)
    major, minor = (int(x) for x in got["bokeh"].split(".")[:2])
    assert (major, minor) >= (3, 1)
    assert "#SBATCH --exclusive" in got["script"] and "--nworkers 16" in got["script"]
    assert list(cwd.iterdir()) == []


#: tqdm's notebook bar, the one ``tqdm.auto`` gives the API's progress in a Jupyter kernel
#: (pipeline/progress.py): its widget, and the warnings tqdm gave while building it
WIDGET = """
import json, warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from tqdm.notebook import tqdm
    try:
        bar = tqdm(total=2, desc="simulate")
        bar.update(2)
        bar.close()
        import ipywidgets
        widget = isinstance(bar.container, ipywidgets.HBox) and type(bar.container).__name__
    except ImportError:  # (tqdm: "IProgress not found. Please update jupyter and ipywidgets.")
        widget = None
print(json.dumps({"widget": widget, "warnings": [str(w.message) for w in caught]}))
"""


def test_notebook_extra_gives_the_progress_widget(wheel, tmp_path):
    plain = _install(wheel, None, tmp_path / "plain")
    cwd = _empty(tmp_path / "cwd")
    assert _python(plain, WIDGET, cwd)["widget"] is None  # (no ipywidgets: no widget, what the extra adds)
    bin_dir = _install(wheel, "notebook", tmp_path / "notebook")
    got = _python(bin_dir, WIDGET, cwd)
    assert got["widget"] == "TqdmHBox" and not any("IProgress" in w for w in got["warnings"]), got
    assert list(cwd.iterdir()) == []
