"""The documentation: a short README whose links reach real pages, every page of docs/ in
the site's navigation, a strict mkdocs build (broken links, missing pages and
docstrings mkdocstrings cannot read are errors), and the Python the README and docs/ show
run as written, with every alternative argument their comments offer."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_the_readme_is_short_and_its_links_reach_real_files():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    targets = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", readme)
    assert targets and all((ROOT / target).is_file() for target in targets), targets


def test_every_page_is_in_the_navigation():
    nav = (ROOT / "mkdocs.yml").read_text()
    pages = {str(path.relative_to(DOCS)) for path in DOCS.rglob("*.md")}
    assert {page for page in pages if page not in nav} == set()


def test_the_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocs", reason="the documentation tools are in quadnav[docs]")
    result = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d",
                             str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                            env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=300)
    assert result.returncode == 0, result.stderr
    api = (tmp_path / "site" / "api" / "planning" / "index.html").read_text()
    assert "register_planner" in api and "make_problem" in api


#: A ```python block of a page, its code.
PYTHON_BLOCK = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)
#: A comment offering another value of a keyword argument: ``# or planner="ompl:BITstar"``.
OFFER = re.compile(r'#\s*or (\w+)=("[^"]*"|[^,\s]+)')
#: The ```python blocks of the README and each page of docs/ that has some, by path.
PYTHON_PAGES = {page.relative_to(ROOT).as_posix(): blocks
                for page in [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
                if (blocks := PYTHON_BLOCK.findall(page.read_text()))}


def offered_variants(block: str) -> list[tuple[str, str]]:
    """For each line of ``block`` whose comment offers ``# or NAME=VALUE``: the offer, and
    the block up to that line with the line's own ``NAME=...`` argument set to ``VALUE``
    (the line must pass ``NAME=`` itself, so a reader sees where the value goes)."""
    lines = block.splitlines()
    variants = []
    for number, line in enumerate(lines):
        code, _, comment = line.partition("#")
        for name, value in OFFER.findall("#" + comment) if comment else []:
            given = re.compile(rf"\b{name}=(\"[^\"]*\"|[^,)\s]+)")
            assert given.search(code), f"{line.strip()!r}: offers {name}= but passes none"
            variant = [*lines[:number], given.sub(f"{name}={value}", code)]
            variants.append((f"{name}={value}", "\n".join(variant)))
    return variants


def test_the_readme_and_library_pages_show_python():
    assert {"README.md", "docs/library.md", "docs/trajectories.md"} <= set(PYTHON_PAGES)


@pytest.mark.parametrize("page", sorted(PYTHON_PAGES))
def test_the_python_of_a_page_runs_as_written(page, tmp_path, monkeypatch):
    """A page's ```python blocks run in order in one namespace, in an empty folder."""
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for block in PYTHON_PAGES[page]:
        exec(compile(block, page, "exec"), namespace)


def test_the_alternatives_the_snippets_comments_offer_run(tmp_path, monkeypatch):
    """``# or planner="ompl:BITstar"`` beside a call: the call with that argument runs."""
    monkeypatch.chdir(tmp_path)
    variants = [(page, *variant) for page, blocks in PYTHON_PAGES.items() for block in blocks
                for variant in offered_variants(block)]
    assert {page for page, _, _ in variants} >= {"README.md", "docs/library.md"}
    for page, offer, code in variants:
        if "ompl:" in offer:
            pytest.importorskip("ompl", reason="OMPL's planners are in quadnav[ompl]")
        exec(compile(code, f"{page} with {offer}", "exec"), {})
