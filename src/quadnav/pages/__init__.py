"""The HTML pages quadnav writes (the run report, the batch summary and leaderboard, the
tuning and grading pages, the 3D viewer), rendered from the Jinja2 templates in
``pages/templates`` with autoescape on: the callers hand over plain data (text, numbers,
lists, dictionaries) and the templates hold all the markup.

``base.html`` is the page every report-like page extends (its style inline, so a page
opens offline on its own), ``macros.html`` the shared table and embedded figure.
"""

from __future__ import annotations

import base64
import re
import struct
from collections.abc import Sequence
from typing import Any

from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape
from markupsafe import Markup

#: Where a long text may wrap: after each of these characters.
BREAK_AFTER = re.compile(r"(?<=[/_:(])")


def breakable(text: str) -> Markup:
    """``text`` escaped, with a ``<wbr>`` after each ``/``, ``_``, ``:`` and ``(``, so a
    long path, plug-in spec or column name fits a narrow column (the ``breakable``
    filter)."""
    return Markup("<wbr>").join(BREAK_AFTER.split(str(text)))


ENVIRONMENT = Environment(
    loader=PackageLoader("quadnav.pages", "templates"),
    autoescape=select_autoescape(("html", "j2")),
    undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True,
    keep_trailing_newline=True)
ENVIRONMENT.filters["breakable"] = breakable


def render(template: str, /, **context: Any) -> str:
    """The page ``template`` (a file name in ``pages/templates``) rendered with
    ``context``."""
    return ENVIRONMENT.get_template(template).render(**context)


def figure(png: bytes, caption: str,
           tooltips: Sequence[tuple[tuple[float, float, float, float], str]] = ()
           ) -> dict[str, Any]:
    """What the ``figure`` macro shows: the PNG (base64, with its size in pixels from its
    IHDR chunk) and its caption; each of ``tooltips``, ``((left, top, width, height),
    text)`` with the box in fractions of the image from its top left corner, shows
    ``text`` when the pointer rests on that part of the image (a shortened label's full
    wording), at any size the image is shown."""
    width, height = struct.unpack(">II", png[16:24])
    return {"data": base64.b64encode(png).decode("ascii"), "width": width, "height": height,
            "caption": caption,
            "tooltips": [{"left": left, "top": top, "width": wide, "height": high,
                          "text": text} for (left, top, wide, high), text in tooltips]}
