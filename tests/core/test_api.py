"""The public API (pipeline.api, re-exported by the package): the calls the stages make, so a model built
from Python simulates exactly as the stages do. (The plot panels that take and return axes:
analyses/plots/.)"""

from __future__ import annotations

import numpy as np
import pytest

import pipeline as hdi
from pipeline.cli_checks import OptionError
from pipeline.config.scene import SceneError
from pipeline.io import DatasetError

#: Flying only (no interface tables to make), short runs, three protrusions [nm].
FLYING = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
          "sweep.protrusion_nm={start=4.0, stop=5.0, step=0.5}", "sweep.batch_size=3"]


@pytest.fixture(scope="module")
def flying(paper_config):
    return hdi.load_scene(paper_config, FLYING)


def test_the_package_exports_the_api():
    assert {"load_scene", "build_model", "simulate", "open_dataset", "run_stage", "run"} <= set(dir(hdi))
    # (the model's simulate behind the command line's checks of a protrusion: tests/scenarios/test_faults.py)
    assert hdi.simulate is __import__("pipeline.api", fromlist=["simulate"]).simulate
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        hdi.nope


def test_help_and_dir_show_the_api_and_import_it_lazily():
    import pydoc
    import subprocess
    import sys
    assert hdi.__all__ == list(hdi.API) and set(hdi.API) <= set(dir(hdi))
    text = pydoc.render_doc(hdi, renderer=pydoc.plaintext)
    functions = text[text.index("\nFUNCTIONS\n"):]
    for name in hdi.API:
        assert f"\n    {name}(" in functions, name  # (each call, with its signature)
        assert f"``{name}(" in hdi.__doc__, name  # (the package docstring names each call)
    # (a fresh interpreter: importing the package and listing its names import no API, no xarray)
    code = "import sys, pipeline; dir(pipeline); pipeline.__all__; print('pipeline.api' in sys.modules, 'xarray' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.split() == ["False", "False"]


def test_load_scene_takes_a_list_a_string_or_a_dict(paper_config):
    listed = hdi.load_scene(paper_config, ["contact.k=0.5", "tfc.protrusion_nm=9.25"])
    assert (listed["contact"]["k"], listed["tfc"]["protrusion_nm"]) == (0.5, 9.25)
    one = hdi.load_scene(paper_config, "contact.k=0.5")  # (once read character by character)
    assert one.overrides == ["contact.k=0.5"] and one["contact"]["k"] == 0.5
    for form in ({"contact.k": 0.5, "tfc.protrusion_nm": 9.25}, {"contact": {"k": 0.5}, "tfc": {"protrusion_nm": 9.25}},
                 {"contact.k": np.float64(0.5), "tfc": {"protrusion_nm": 9.25}}):
        scene = hdi.load_scene(paper_config, form)
        assert scene.overrides == listed.overrides and scene.hash == listed.hash, form
    # a float written back exactly (repr), and a table as an inline table
    odd = hdi.load_scene(paper_config, {"contact.k": 0.1 + 0.2, "sweep.protrusion_nm": {"start": 9.5, "stop": 10.5,
                                                                                        "step": 0.5}})
    assert odd["contact"]["k"] == 0.1 + 0.2 and odd.overrides[0] == "contact.k=0.30000000000000004"
    assert dict(odd["sweep"]["protrusion_nm"]) == {"start": 9.5, "stop": 10.5, "step": 0.5}
    with pytest.raises(SceneError, match=r"overrides = 5: expected a list of \"section.key=value\" strings"):
        hdi.load_scene(paper_config, 5)
    with pytest.raises(SceneError, match=r"overrides\['contact'\] = 0.5: expected \"section.key\": value"):
        hdi.load_scene(paper_config, {"contact": 0.5})
    with pytest.raises(SceneError, match=r"overrides 'contact.k' = <object .*got object"):
        hdi.load_scene(paper_config, {"contact.k": object()})
    with pytest.raises(SceneError, match=r"--set solver.duration_ms=-1.0: solver.duration_ms"):  # (as --set is)
        hdi.load_scene(paper_config, {"solver": {"duration_ms": -1.0}})


def test_a_scene_is_read_only_and_replace_validates(paper_config):
    import copy
    import pickle
    scene = hdi.load_scene(paper_config)
    before = scene.hash
    with pytest.raises(TypeError, match=r"read-only: scene\['contact'\] cannot be changed in place; vary it with "
                                        r"scene.replace\(contact=\{key: value\}\)"):
        scene["contact"]["k"] = "abc"
    for change in (lambda: scene["contact"].update(k=1.0), lambda: scene["contact"].pop("k"),
                   lambda: scene.config.__setitem__("contact", {}), lambda: scene["sweep"]["protrusion_nm"].clear()):
        with pytest.raises(TypeError, match="read-only"):
            change()
    assert scene.hash == before and scene["contact"]["k"] is None
    varied = scene.replace(contact={"k": 0.5}, tfc={"protrusion_nm": 9.0})
    assert (varied["contact"]["k"], varied["tfc"]["protrusion_nm"], scene["contact"]["k"]) == (0.5, 9.0, None)
    assert varied.hash == hdi.load_scene(paper_config, {"contact.k": 0.5, "tfc.protrusion_nm": 9.0}).hash
    with pytest.raises(TypeError, match="read-only"):
        varied["tfc"]["protrusion_nm"] = 1.0
    with pytest.raises(SceneError, match=r"scene.replace\(contact=\{'k': 'abc'\}\): contact.k = 'abc': expected a number"):
        scene.replace(contact={"k": "abc"})
    with pytest.raises(SceneError, match=r"unknown key contact.kk"):
        scene.replace(contact={"kk": 0.5})
    with pytest.raises(SceneError, match=r"scene.replace\(contact=0.5\): expected a dict"):
        scene.replace(contact=0.5)
    # (sent to dask workers and copied whole: still read-only, the same identity)
    for copied in (pickle.loads(pickle.dumps(scene)), copy.deepcopy(scene)):
        assert copied.hash == before
        with pytest.raises(TypeError, match="read-only"):
            copied["contact"]["k"] = 0.5


def test_a_distributed_client_is_a_scheduler(flying, tmp_path):
    """A client of an in-process cluster runs the sweep's fan-out: the synchronous sweep's numbers, bit for bit."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        path = hdi.run_stage("sweep", flying, tmp_path / "client", scheduler=client)
        with pytest.raises(OptionError, match="^scheduler: not used by stage 'dmw'; only by sweep"):
            hdi.run_stage("dmw", flying, tmp_path / "dmw", scheduler=client)
    with pytest.raises(OptionError, match="the client is closed"):
        hdi.run_stage("sweep", flying, tmp_path / "closed", scheduler=client)
    sync = hdi.run_stage("sweep", flying, tmp_path / "sync", scheduler="synchronous")
    got, want = hdi.open_dataset(path.parent, "sweep"), hdi.open_dataset(sync.parent, "sweep")
    assert got["fhm_bv"].values.tobytes() == want["fhm_bv"].values.tobytes() and got["fhm_bv"].size == 3


def test_a_model_from_python_simulates_as_the_stages_do(flying, tmp_path):
    """In memory, from a results folder, and the simulate and sweep stages: the same numbers, bit for bit."""
    delta = float(flying["tfc"]["protrusion_nm"])
    mem = hdi.simulate(hdi.build_model(flying), [delta, 4.5], histories=[delta])
    folder = hdi.simulate(hdi.build_model(flying, tmp_path), [delta, 4.5])
    assert mem["fhm_bv"].values.tobytes() == folder["fhm_bv"].values.tobytes()
    assert (tmp_path / "dmw.nc").is_file() and not (tmp_path / "interface.nc").exists()  # (flying: no tables)
    summary = hdi.run_stage("simulate", flying, tmp_path).parent / "summary.nc"
    assert hdi.open_dataset(tmp_path, summary.name)["fhm_bv"].values.tobytes() == mem["fhm_bv"][:1].values.tobytes()
    history = hdi.histories_of(mem).sel(protrusion=delta)
    assert history["separation"].shape == (history.sizes["elapsed_time"],) == (2401,)  # 0.6 ms at 0.25 us
    assert np.array_equal(history["separation"].values, hdi.open_dataset(tmp_path, "simulate")["separation"][0].values)
    sweep = hdi.open_dataset(hdi.run_stage("sweep", flying, tmp_path, scheduler="synchronous").parent, "sweep")
    assert sweep["fhm_bv"].sel(protrusion=4.5).values.ravel().tobytes() == mem["fhm_bv"][1:].values.tobytes()
    assert 1.0 < float(mem["fhm_bv"][1]) < 50.0  # flying: FHM [%] of a 0.27-nm DMW over a few nm


def test_k_given_is_used_without_a_calibration(paper_config, tmp_path):
    scene = hdi.load_scene(paper_config, ["solver.duration_ms=0.6", "solver.transient_ms=0.2"])
    assert scene["contact"]["k"] is None  # (without k the calibration would run first)
    sim = hdi.simulation_inputs(scene, tmp_path, k=0.7)
    assert (sim.k, sim.k_source) == (0.7, "option k") and not (tmp_path / "calibration.nc").exists()
    assert sim.model(scene).k == 0.7 and (tmp_path / "interface.nc").is_file()


def test_bad_input_raises_the_errors_the_command_line_reports(flying, paper_config, tmp_path):
    with pytest.raises(SceneError, match="solver.duration_ms"):
        hdi.load_scene(paper_config, ["solver.duration_ms=-1"])
    with pytest.raises(DatasetError, match=r"sweep\.nc: dataset does not exist \(run `hdi sweep` first\)"):
        hdi.open_dataset(tmp_path, "sweep")
    with pytest.raises(ValueError, match="stage 'report' writes no dataset"):
        hdi.open_dataset(tmp_path, "report")
    with pytest.raises(ValueError, match="expected a stage"):
        hdi.open_dataset(tmp_path, "swep")
    with pytest.raises(ValueError, match="unknown stage 'swep'"):
        hdi.run_stage("swep", flying, tmp_path)
    with pytest.raises(OptionError, match="^workers = 0: expected a positive number"):
        hdi.run_stage("sweep", flying, tmp_path, workers=0)
    assert list(tmp_path.iterdir()) == []  # (refused before anything was written)


def test_the_api_is_no_part_of_any_stage_code_key():
    """The package's ``__init__`` names the API (a lazy import the key's scan sees): were the API keyed, every
    stage would be keyed on what the API imports: editing the simulation would recompute the DMW record."""
    from pipeline import code_version, runner
    for name in runner.registry():
        found = code_version.modules(f"pipeline.stages.{name}")
        assert "pipeline" in found and "pipeline.api" not in found, name
    assert "pipeline.model.simulation" not in code_version.modules("pipeline.stages.dmw")


def test_simulate_refuses_duplicates_histories_off_its_protrusions_and_workers(flying):
    """simulate(model, [9.0], histories=[10.0]) kept no history, silently; [9.0, 9.0] returned a duplicated
    index; workers=2 was a TypeError. Each is now one line naming the Python argument, before any run."""
    model = hdi.build_model(flying, progress=False)
    with pytest.raises(OptionError, match=r"^histories: 10 nm not among the protrusions \(9 nm\); expected "
                                          r"protrusions that are simulated$"):
        hdi.simulate(model, [9.0], histories=[10.0])
    with pytest.raises(OptionError, match=r"^protrusions: 9 nm given more than once; expected each protrusion once"):
        hdi.simulate(model, [9.0, 4.5, 9.0])
    with pytest.raises(OptionError, match=r"^workers = 2: simulate runs its protrusions one after another in this "
                                          r"process .*run_stage\(\"sweep\", scene, out, workers=\.\.\.\)"):
        hdi.simulate(model, [9.0], workers=2)
    kept = hdi.simulate(model, [4.5], histories=[4.5 + 1e-12], progress=False)  # (to the grid's tolerance)
    assert kept.sizes["hist_protrusion"] == 1 and kept.sizes["protrusion"] == 1


def test_a_model_built_in_memory_says_what_it_computes_without_claiming_files(flying, caplog):
    """build_model(scene, None) said "dmw: wrote dmw.nc" and wrote nothing; now it says it computed the record
    in memory, and no line claims a file."""
    import logging
    with caplog.at_level(logging.INFO, logger="pipeline"):
        hdi.build_model(flying.replace(dmw={"seed": 7}))
    lines = [r.getMessage() for r in caplog.records]
    assert "dmw: computing (in memory)" in lines, lines
    assert any(ln.startswith("dmw: computed in memory, no file kept: the disk's dynamic microwaviness, synthesised "
                             "or measured (") for ln in lines), lines
    assert not any("wrote" in ln or ".nc" in ln for ln in lines), lines


def test_run_stage_errors_name_the_python_arguments(flying, tmp_path):
    """They named the command line's options ("--out ...: is a file", "--workers 'two'")."""
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(OptionError, match=rf"^out = '{afile}': is a file; expected a folder$"):
        hdi.run_stage("sweep", flying, afile)
    with pytest.raises(OptionError, match=r"^workers = 'two': expected a positive integer"):
        hdi.run_stage("sweep", flying, tmp_path / "o", workers="two")
    with pytest.raises(OptionError, match=r"^workers: not used by stage 'dmw'; only by sweep"):
        hdi.run_stage("dmw", flying, tmp_path / "o", workers=2)
    # the command line's own messages are unchanged
    from pipeline.cli_checks import check_options
    with pytest.raises(OptionError, match=rf"^--out {afile}: is a file"):
        check_options("sweep", flying, out=afile)
    with pytest.raises(OptionError, match=r"^--workers: not used by `hdi dmw`"):
        check_options("dmw", flying, workers=2)


def test_a_big_job_from_python_asks_for_yes_true(paper_config, tmp_path):
    """A job beyond a size limit asks for the argument yes=True from Python, --yes on the command line."""
    from pipeline.cli_checks import check_options
    big = hdi.load_scene(paper_config, ["sweep.protrusion_nm={start=0.0, stop=15.0, step=0.0001}"])
    with pytest.raises(OptionError, match=r"exceed [\d,]+; pass yes=True to run them anyway$"):
        hdi.run_stage("sweep", big, tmp_path / "o")
    with pytest.raises(OptionError, match=r"exceed [\d,]+; pass --yes to run them anyway$"):
        check_options("sweep", big, out=tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_open_dataset_checks_a_stages_output_and_reads_a_users_own_subset_unchecked(tmp_path):
    import xarray as xr
    from damage import edit_value
    from pipeline import io
    ds = xr.Dataset({"displacement": io.var(np.sin(np.arange(9000) * 0.01), "elapsed_time", "nm", "DMW")},
                    coords={"elapsed_time": io.var(np.arange(9000) * 2.5e-7, "elapsed_time", "s", "time")})
    io.write_dataset(ds, tmp_path / "dmw.nc", stage="dmw")
    hdi.open_dataset(tmp_path, "dmw").isel(elapsed_time=slice(0, 10)).to_netcdf(tmp_path / "mine.nc")
    assert hdi.open_dataset(tmp_path, "mine.nc").displacement.size == 10   # (its checksums: the whole record's)
    edit_value(tmp_path / "dmw.nc", "displacement", (0,), 3.0)
    with pytest.raises(io.DatasetDamaged, match=r"dmw\.nc: variable 'displacement': values differ"):
        hdi.open_dataset(tmp_path, "dmw")
