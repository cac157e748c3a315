"""The documentation: a short README whose links reach real pages, every page of docs/ in
the site's navigation, and a strict mkdocs build (broken links, missing pages and
docstrings mkdocstrings cannot read are errors)."""

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
