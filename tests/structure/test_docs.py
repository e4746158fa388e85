"""The README is a short front door and the docs pages hold the rest: the README stays
under 250 lines, every relative link of the README and of docs/*.md reaches a file (and, for an
``#anchor`` into a markdown page, a heading of it, by GitHub's slug rule), and ``make readme`` writes the
generated comparison into the page that holds its markers."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from pipeline.analyses import narrative

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: ``[text](target)`` and ``![alt](target)``; the target up to the closing parenthesis or a title.
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def prose(text: str) -> str:
    """``text`` without its fenced code blocks (a ``#`` comment there is no heading, a link no link)."""
    return FENCE.sub("", text)


def slug(heading: str) -> str:
    """GitHub's anchor of a markdown heading: lower case, punctuation but ``-`` and ``_`` dropped,
    each space a hyphen."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    """The anchors of ``page``'s headings, repeated ones numbered as GitHub numbers them (``-1``, ...)."""
    seen: dict[str, int] = {}
    out = set()
    for line in prose(page.read_text(encoding="utf-8")).splitlines():
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            s = slug(m.group(1))
            out.add(s if s not in seen else f"{s}-{seen[s]}")
            seen[s] = seen.get(s, 0) + 1
    return out


def relative_links(page: Path) -> list[str]:
    """The links of ``page`` that point into the repository (not ``http:``, ``https:``, ``mailto:``)."""
    return [t for t in LINK.findall(prose(page.read_text(encoding="utf-8")))
            if not re.match(r"[a-z][a-z0-9+.-]*:", t)]


def test_slug_follows_githubs_rule():
    assert slug("Reproducing the paper: what we find") == "reproducing-the-paper-what-we-find"
    assert slug("What `make run` produces") == "what-make-run-produces"
    assert slug("Parameter studies: `hdi identify` and `hdi sensitivity`") == \
        "parameter-studies-hdi-identify-and-hdi-sensitivity"


def test_the_readme_is_a_short_front_door():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) < 250, f"README.md has {len(lines)} lines; move detail into docs/"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(page):
    broken = []
    for target in relative_links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading with that anchor in {dest.name}")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)


def test_the_readme_lists_the_docs_pages_and_they_exist():
    listed = {t.partition("#")[0] for t in relative_links(ROOT / "README.md") if t.startswith("docs/")
              and t.partition("#")[0].endswith(".md")}
    for name in ("cli", "datasets", "results", "scaling", "architecture", "performance", "model"):
        assert f"docs/{name}.md" in listed
    assert all((ROOT / p).is_file() for p in listed)


def test_make_readme_writes_the_page_that_holds_the_generated_section():
    target = re.search(r"^readme:.*\n\t.*--readme\s+(\S+)", (ROOT / "Makefile").read_text(), re.M).group(1)
    holders = [p.relative_to(ROOT).as_posix() for p in PAGES
               if narrative.README_BEGIN in p.read_text(encoding="utf-8")]
    assert holders == [target] == ["docs/results.md"]
    text = (ROOT / target).read_text(encoding="utf-8")
    assert text.index(narrative.README_BEGIN) < text.index(narrative.README_END)
    # the page's images are where `--readme` copies the report's figures: figures/ beside the page
    for name in narrative.README_FIGURES[:2]:
        assert f"](figures/{name})" in text


#: A path into the package as the pages write it: ``pipeline/model/assembly.py``, ``pipeline/analyses/``
#: (a component in capitals, ``pipeline/stages/NAME.py``, is a placeholder).
SOURCE_PATH = re.compile(r"(?<![\w./-])pipeline/[\w/]*(?:\.py)?")
#: A dotted name in the package: ``pipeline.model.forces.separation_at``, ``pipeline.analyses.plots.plot_*``.
DOTTED = re.compile(r"(?<![\w./-])pipeline(?:\.[A-Za-z_]\w*)+\*?")


def path_exists(path: str) -> bool:
    """Whether a ``pipeline/...`` path of a page is a file or folder of the repository (placeholders aside)."""
    if any(part.split(".")[0].isupper() for part in path.split("/")):
        return True
    return (ROOT / path.rstrip("/")).exists()


def resolves(dotted: str) -> bool:
    """Whether ``pipeline.a.b.c`` names a module of the package or an attribute of one (``pipeline.a.b_*``:
    an attribute of ``pipeline.a`` starting with ``b_``)."""
    import importlib
    prefix = dotted.endswith("*")
    parts = dotted.rstrip("*").split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        rest = parts[n:]
        if prefix and not rest:  # (a module named by its whole prefix: pipeline.stages.roughness*)
            return True
        for i, name in enumerate(rest):
            if prefix and i == len(rest) - 1:
                return any(a.startswith(name) for a in dir(obj))
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_path_into_the_package_exists(page):
    """A page that names ``pipeline/scene.py`` (moved to ``pipeline/config/scene.py``) or
    ``pipeline.scene.load`` sends its reader nowhere: every path and dotted name into ``pipeline`` resolves."""
    text = page.read_text(encoding="utf-8")
    missing = sorted({p for p in SOURCE_PATH.findall(text) if not path_exists(p)})
    missing += sorted({d for d in DOTTED.findall(text) if not resolves(d)})
    assert not missing, f"{page.relative_to(ROOT)}: no such path or name in the package: " + ", ".join(missing)


#: What a clone does not have: the project's issue tracker, its lab notes and its shared planning files.
#: (``/shared/...`` in a command line is a user's shared folder, not these.)
NOTES = re.compile(r"\bissue \d+|\blab (?:H\d|notes?|runs?|scans?|rounds?)\b|\bSPEC\.md|\bDESIGN\.md"
                   r"|until [^.]{0,60}\bmerged\b", re.I)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_page_sends_its_reader_to_notes_a_clone_lacks(page):
    """"lab H4", an issue's number or "until merged" point at notes outside the repository: a page states the
    measurement itself or links a docs page (the generated section of docs/results.md is left to
    ``make readme``)."""
    text = page.read_text(encoding="utf-8")
    if narrative.README_BEGIN in text:
        text = text[:text.index(narrative.README_BEGIN)] + text[text.index(narrative.README_END):]
    found = sorted({m.group(0) for m in NOTES.finditer(text)})
    assert not found, f"{page.relative_to(ROOT)}: cites notes a clone does not have: " + ", ".join(found)


def test_no_docstring_or_comment_of_the_package_cites_notes_a_clone_lacks():
    """The package's own text (docstrings, comments, messages) states what the code does and where it is
    documented, not the issue or lab note it came from: the history lives in docs/ and the commits."""
    found = []
    for path in sorted((ROOT / "pipeline").rglob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            hit = NOTES.search(line)
            if hit:
                found.append(f"{path.relative_to(ROOT)}:{number}: {hit.group(0)}")
    assert not found, "cites notes a clone does not have:\n" + "\n".join(found)


def test_the_readmes_commands_call_the_uv_that_make_installs():
    """uv is not on a new user's PATH: the README's commands name ``.bootstrap/bin/uv`` (the Makefile's), or
    say that a bare ``uv`` needs one on the PATH."""
    blocks = re.findall(r"^```sh\n(.*?)^```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S | re.M)
    lines = [line.split("#", 1)[0] for block in blocks for line in block.splitlines()]  # (not the comments)
    commands = [line for line in lines if re.search(r"(^|[\s;&|(])\S*uv\s", line)]
    assert commands, "the README shows no uv command"
    for line in commands:
        bare = re.findall(r"(?:^|[\s;&|(])(\S*)uv\s", line)
        assert all(prefix.endswith(".bootstrap/bin/") for prefix in bare), line


def test_the_two_shipped_k_are_explained_in_one_section_that_the_scene_and_the_results_link():
    section = "The two k of the shipped scenes"
    model = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    assert f"### {section}" in model
    text = model.split(f"### {section}", 1)[1].split("\n## ", 1)[0]
    for number in ("0.978", "1.0728", "(-0.8424, 2.9879]", "28.3 %", "32.8 %"):
        assert number in text, number
    assert section in (ROOT / "configs" / "paper-2009.toml").read_text(encoding="utf-8")
    assert f"model.md#{slug(section)}" in (ROOT / "docs" / "results.md").read_text(encoding="utf-8")
