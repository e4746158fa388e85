"""The API reference (docs/api/, ``make docs``) builds inside ``make test``'s pytest session without a
warning; it documents every call of pipeline/api.py and every physics module, and its gallery every script
of docs/examples/ and docs/experiments/ with the committed figures it shows. Every public function of
pipeline/physics/ has the numpydoc sections of the project's standard: Parameters (where it takes any),
Returns with a unit in brackets (where it returns something), and References."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import subprocess
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "docs" / "api"


def _sphinx_build(out: Path) -> subprocess.CompletedProcess:
    """``make docs``'s command (warnings are errors, all reported), into ``out``."""
    return subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q",
                           str(SOURCE), str(out)], cwd=ROOT, capture_output=True, text=True, timeout=600)


def test_the_api_reference_builds_without_a_warning(tmp_path):
    """A fresh build (``-E`` is implied by the empty output folder): 11.8 s at load ~5 on the 2-core machine,
    40 s at load ~8, 9-12 s of CPU."""
    done = _sphinx_build(tmp_path / "html")
    assert done.returncode == 0 and "WARNING" not in done.stderr and "ERROR" not in done.stderr, done.stderr
    page = (tmp_path / "html" / "physics.html").read_text(encoding="utf-8")
    # the reference holds the laws themselves, with their sections (numpydoc renders them as field lists)
    assert "pipeline.physics.asperity_statistics.plasticity_index" in page and "Parameters" in page
    assert "References" in page
    api = (tmp_path / "html" / "api.html").read_text(encoding="utf-8")
    assert "pipeline.api.simulate" in api and "pipeline.api.build_model" in api


def test_a_docstring_that_sphinx_cannot_read_fails_the_build(tmp_path):
    """The build's -W is real: a page with a malformed directive stops it (exit code not 0, the warning
    named), so the check above cannot pass by building nothing."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "index.rst").write_text("Broken\n======\n\n.. automodule:: pipeline.physics.no_such_module\n",
                                   encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q",
                           "-c", str(SOURCE), str(src), str(tmp_path / "html")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode != 0 and "no_such_module" in done.stderr


def _physics_modules() -> list[str]:
    import pipeline.physics as physics
    return sorted(f"pipeline.physics.{m.name}" for m in pkgutil.iter_modules(physics.__path__))


def test_the_reference_lists_every_api_call_every_physics_module_and_every_gallery_script():
    import pipeline.api as api
    physics = set(re.findall(r"^\.\. automodule:: (\S+)$", (SOURCE / "physics.rst").read_text(), re.M))
    assert physics == set(_physics_modules())
    members = re.search(r":members: (.+)$", (SOURCE / "api.rst").read_text(), re.M).group(1)
    assert {m.strip() for m in members.split(",")} == set(api.__all__)
    gallery = (SOURCE / "gallery.rst").read_text()
    scripts = {f"../{p.parent.name}/{p.name}" for folder in ("examples", "experiments")
               for p in (ROOT / "docs" / folder).glob("*.py")}
    assert set(re.findall(r"^\.\. literalinclude:: (\S+)$", gallery, re.M)) == scripts
    for image in re.findall(r"^\.\. image:: (\S+)$", gallery, re.M):
        assert (SOURCE / image).resolve().is_file(), image


def _python_function(obj: object) -> object | None:
    """The Python function behind ``obj``: itself, a numba dispatcher's ``py_func``, a static or class method's
    function (``None``: not a function)."""
    obj = getattr(obj, "__func__", obj)                       # staticmethod, classmethod
    obj = getattr(obj, "py_func", obj)                        # numba's @njit
    return obj if inspect.isfunction(obj) else None


#: Return annotations of a property that is a physical quantity (a number or an array of numbers); a property
#: that returns a law or another object (a registry entry's ``behaviour``) is not one.
QUANTITY = ("float", "np.ndarray", "numpy.ndarray", "tuple[float, float]")


def public_physics_functions() -> list[tuple[str, object]]:
    """``(qualified name, function)`` of every public function of pipeline/physics/ (the package's
    ``__init__`` included; numba-compiled ones by their Python function), every public method of its public
    classes and every public property of theirs that is a quantity (:data:`QUANTITY`), each defined in
    pipeline/physics/; a function defined under a private name and bound to a public one anywhere in
    pipeline/physics/ (a re-exported helper) counts under its public name."""
    found, seen = [], set()
    for name in ["pipeline.physics", *_physics_modules()]:
        mod = importlib.import_module(name)
        for n, obj in vars(mod).items():
            func = _python_function(obj)
            if n.startswith("_") or not getattr(func or obj, "__module__", "").startswith("pipeline.physics"):
                continue
            defined_here = getattr(func or obj, "__module__", None) == name
            if func is not None and (defined_here or func.__name__.startswith("_")) and id(func) not in seen:
                seen.add(id(func))
                found.append((f"{name}.{n}", func))
            elif inspect.isclass(obj) and defined_here:
                for m, f in vars(obj).items():
                    if m.startswith("_"):
                        continue
                    if _python_function(f) is not None:
                        found.append((f"{name}.{n}.{m}", _python_function(f)))
                    elif isinstance(f, property) and inspect.signature(f.fget).return_annotation in QUANTITY:
                        found.append((f"{name}.{n}.{m}", f.fget))
    return found


#: A unit in brackets: ``[nm]``, ``[N m-1]``, ``[1]`` (dimensionless) or ``[-]`` (a label, a count, a flag)
UNIT = re.compile(r"\[[^\]\s][^\]]*\]")


def missing_sections(func: object) -> list[str]:
    """The sections of the standard that ``func``'s docstring lacks (numpydoc's parser reads them)."""
    from numpydoc.docscrape import FunctionDoc
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc = FunctionDoc(func)
    sig = inspect.signature(func)
    params = [p for p in sig.parameters if p not in ("self", "cls")]
    lacks = []
    if params and not doc["Parameters"]:
        lacks.append("Parameters")
    returns_nothing = sig.return_annotation in (None, "None")
    text = " ".join(f"{r.name} {r.type} {' '.join(r.desc)}" for r in doc["Returns"] + doc["Yields"])
    if not returns_nothing and not doc["Returns"] and not doc["Yields"]:
        lacks.append("Returns")
    elif not returns_nothing and not UNIT.search(text):
        lacks.append("a [unit] in Returns")
    if not doc["References"]:
        lacks.append("References")
    return lacks


def test_every_public_physics_function_has_parameters_returns_with_a_unit_and_references():
    functions = public_physics_functions()
    assert len(functions) > 100
    lacking = {name: missing_sections(f) for name, f in functions}
    lacking = {name: what for name, what in lacking.items() if what}
    assert not lacking, f"{len(lacking)} of {len(functions)} public physics functions lack sections:\n" + "\n".join(
        f"{name}: {', '.join(what)}" for name, what in sorted(lacking.items()))


def test_the_collection_sees_compiled_functions_quantity_properties_and_re_exported_helpers(monkeypatch):
    from pipeline.physics import air_bearing, bulge_bearing, isbl
    monkeypatch.setattr(isbl, "gauss_density", isbl._gauss, raising=False)    # a private helper made public
    functions = dict(public_physics_functions())
    assert functions["pipeline.physics.isbl.gauss_density"] is isbl._gauss and missing_sections(isbl._gauss)
    assert functions["pipeline.physics.bulge_bearing.ph_force_stiffness"] is bulge_bearing.ph_force_stiffness.py_func
    assert functions["pipeline.physics.isbl.Interface.w_c"] is isbl.Interface.w_c.fget
    assert functions["pipeline.physics.air_bearing.Slider.mass_matrix"] is air_bearing.Slider.mass_matrix.fget
    assert "pipeline.physics.air_bearing.RearLaw.behaviour" not in functions          # a law, not a quantity
    assert "pipeline.physics.isbl.lennard_jones_force" not in functions           # imported: checked at home
    assert "pipeline.physics.adhesion.lennard_jones_force" in functions


def test_the_docstring_check_sees_a_missing_section():
    def law(x: float) -> float:
        """A law [paper].

        Returns
        -------
        float
            Something.
        """
        return x

    assert missing_sections(law) == ["Parameters", "a [unit] in Returns", "References"]

    def silent(x: float) -> None:
        """Checks x.

        Parameters
        ----------
        x : a length [m]

        References
        ----------
        [GW66] (docs/model.md).
        """

    assert missing_sections(silent) == []
