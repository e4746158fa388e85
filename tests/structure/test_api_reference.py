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


def public_physics_functions() -> list[tuple[str, object]]:
    """``(qualified name, function)`` of every public function of pipeline/physics/ and every public method
    of its public classes, each defined in its module (not an imported name)."""
    found = []
    for name in _physics_modules():
        mod = importlib.import_module(name)
        for n, obj in vars(mod).items():
            if n.startswith("_") or getattr(obj, "__module__", None) != name:
                continue
            if inspect.isfunction(obj):
                found.append((f"{name}.{n}", obj))
            elif inspect.isclass(obj):
                found += [(f"{name}.{n}.{m}", f) for m, f in vars(obj).items()
                          if not m.startswith("_") and inspect.isfunction(f)]
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
