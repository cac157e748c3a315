"""Plug-ins named where they are: ``module:Name``, ``path/to/file.py:Name``, with literal
keyword arguments, and the one line a user gets for each mistake."""

from __future__ import annotations

import pickle

import pytest

from quadnav.control.registry import CONTROLLERS
from quadnav.errors import QuadnavError
from quadnav.plugins import PluginError, load_target, parse_spec

WIND = '''
import numpy as np

class Gusty:
    """A wind of ``speed`` m/s along ``axis``."""

    def __init__(self, speed=1.0, axis=(1.0, 0.0, 0.0)):
        self.wind = speed * np.asarray(axis, dtype=float)

    def update(self, t, position):
        return self.wind
'''


@pytest.fixture
def wind_file(tmp_path):
    path = tmp_path / "my_wind.py"
    path.write_text(WIND)
    return path


def test_a_spec_gives_its_target_and_literal_keyword_arguments():
    spec = parse_spec("my_wind.py:Gusty(speed=3.0, axis=[0, 1, 0], name='x', on=True)")
    assert spec.target == "my_wind.py:Gusty" and spec.is_located
    assert dict(spec.kwargs) == {"speed": 3.0, "axis": [0, 1, 0], "name": "x", "on": True}
    assert parse_spec("cascade").target == "cascade" and not parse_spec("cascade").is_located
    assert dict(parse_spec("pkg.mod:Name()").kwargs) == {}


@pytest.mark.parametrize(("text", "words"), [
    ("my.py:Ctl(1, 2)", "give its arguments by keyword, key=value"),
    ("my.py:Ctl(k=__import__('os').getcwd())", "the value of k is not a literal"),
    ("my.py:Ctl(k=x)", "the value of k is not a literal (expected a number, string, "
                       "True/False/None, or a list, tuple or dict of them, got x)"),
    ("my.py:Ctl(k=1", "expected NAME, module:NAME or path/to/file.py:NAME"),
    ("a:b:c", "expected NAME, module:NAME or path/to/file.py:NAME"),
    ("my.py:", "expected NAME, module:NAME or path/to/file.py:NAME"),
    ("", "expected NAME, module:NAME or path/to/file.py:NAME"),
])
def test_a_malformed_spec_is_one_line_that_says_what_was_expected(text, words):
    with pytest.raises(QuadnavError, match=r"^controller ") as caught:
        parse_spec(text, "controller")
    assert words in str(caught.value) and "\n" not in str(caught.value)


def test_a_file_and_a_module_load_by_path_and_by_name(wind_file):
    found = load_target(f"{wind_file}:Gusty")
    assert found(speed=2.0).update(0.0, None).tolist() == [2.0, 0.0, 0.0]
    assert load_target(f"{wind_file}:Gusty") is found  # loaded once per process
    assert pickle.loads(pickle.dumps(found(speed=2.0))).wind.tolist() == [2.0, 0.0, 0.0]
    assert load_target("quadnav.control.se3:se3_controller").__name__ == "se3_controller"
    factory, kwargs = CONTROLLERS.load("quadnav.control.se3:se3_controller")
    assert factory.__name__ == "se3_controller" and dict(kwargs) == {}
    assert CONTROLLERS.load("se3")[0] is CONTROLLERS.get("se3")


def test_what_cannot_be_loaded_is_named(wind_file, tmp_path):
    with pytest.raises(QuadnavError, match=r"no\.py: no such file"):
        load_target(f"{tmp_path}/no.py:Gusty", "wind")
    with pytest.raises(QuadnavError, match=r"has no 'Windy' \(it defines Gusty\)"):
        load_target(f"{wind_file}:Windy", "wind")
    with pytest.raises(QuadnavError, match="no module named 'not_a_module'"):
        load_target("not_a_module.sub:Name", "wind")
    with pytest.raises(QuadnavError, match="unknown controller 'pid'; expected one of "
                                           "cascade, se3"):
        CONTROLLERS.load("pid")


def test_a_file_that_raises_while_loading_shows_its_own_traceback_once(tmp_path):
    broken = tmp_path / "broken.py"
    broken.write_text("import math\n\ndef helper():\n    return 1 / 0\n\nhelper()\n")
    with pytest.raises(PluginError) as caught:
        load_target(f"{broken}:Ctl", "controller")
    error = caught.value
    assert str(error) == (f"controller {broken}: ZeroDivisionError while loading it: "
                          "division by zero")
    assert error.exit_code == 2
    assert error.details.splitlines()[0] == "Traceback (most recent call last):"
    assert "return 1 / 0" in error.details and "quadnav" not in error.details.replace(
        str(tmp_path), "")
