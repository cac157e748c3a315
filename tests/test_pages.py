"""The HTML pages' templates (quadnav.pages): found where the package is installed, text
escaped, a missing value an error rather than an empty spot, figures at their PNG's size."""

from __future__ import annotations

import io

import jinja2
import pytest
from PIL import Image

from quadnav.pages import ENVIRONMENT, breakable, figure, render

PAGES = ("report.html", "tune.html", "grade.html", "summary.html", "compare.html",
         "viewer.html")


def test_every_page_template_is_found_and_compiles():
    assert set(PAGES) <= set(ENVIRONMENT.list_templates())
    for name in PAGES:
        ENVIRONMENT.get_template(name)


def test_text_is_escaped_and_a_missing_value_is_an_error():
    page = render("base.html", title="<script>alert('x')</script> & co")
    assert "<title>&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; co</title>" in page
    assert page.startswith("<!DOCTYPE html>") and page.endswith("</html>\n")
    with pytest.raises(jinja2.UndefinedError, match="title"):
        render("base.html")


def test_a_long_name_may_wrap_after_its_separators_and_stays_escaped():
    assert breakable("maps/a_b:c(<d>)") == "maps/<wbr>a_<wbr>b:<wbr>c(<wbr>&lt;d&gt;)"
    assert breakable("plain words") == "plain words"


def test_a_figure_is_shown_at_its_pngs_size_with_its_tooltips():
    buffer = io.BytesIO()
    Image.new("RGB", (37, 21), "white").save(buffer, format="PNG")
    shown = figure(buffer.getvalue(), 'the "caption"', [((0.25, 0.5, 0.125, 0.1), "a & b")])
    assert (shown["width"], shown["height"]) == (37, 21)
    html = ENVIRONMENT.get_template("macros.html").module.figure(shown)
    assert 'width="37" height="21" alt="the &#34;caption&#34;"' in html
    assert ('<span class="tooltip" title="a &amp; b" style="left: 25.000%; top: 50.000%; '
            'width: 12.500%; height: 10.000%"></span>') in html
    assert "<figcaption>the &#34;caption&#34;</figcaption>" in html
