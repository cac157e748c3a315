"""Every quadnav command line written in the README and docs/ runs as written.

The commands of each page are run in the page's order (a later one reads what an earlier
one wrote) in a fresh folder, in-process through ``quadnav.cli.main.main``. A command
shown with its output (``$ quadnav ...`` followed by lines) must give that output: an
error or warning line word for word and number for number (each number to within a step
of its last digit and a little more, as another CPU, BLAS build or numba target changes
last digits), any other line with the same words (its numbers may differ, as planning
runs against the clock); one shown without output must succeed. A code block whose first
line is ``# file: NAME`` is a file the commands read, written into the folder first. Lines
with placeholders (MAP, DIR, FILE, [optional parts], A|B) are synopses and are only read
by the real parser (a Ray cluster's ``HEAD:6379`` is a placeholder too). The Blender
command is only read too: tests/test_blender.py runs it as written (with both renders) on a
run folder of its own and checks the scene object by object.

Course maps are fetched as a user fetches them, by the page's own ``quadnav maps fetch``: each
page runs with an empty cache of its own, its downloads served on loopback from
../shared/maps (tests/coursemaps.py). Without that folder, the commands that fetch or read a
fetched course map are skipped (the page says which); the rest run, shipped worlds included.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from coursemaps import course_files, dead_url, serving

from quadnav.cli.main import build_parser, main
from quadnav.world.courses import CACHE_ENV, PREFIX, URL_ENV, catalogue

ROOT = Path(__file__).resolve().parents[1]
SHARED_MAPS = ROOT.parent / "shared" / "maps"
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A synopsis, not a command: upper-case placeholders, optional parts, alternatives.
PLACEHOLDER = re.compile(r"(?<![/\w.])[A-Z][A-Z0-9_]*\b(?!=)|\[|\.\.\.|\|(?!\s*head)")
#: A number, not a digit of a name (``rbe595``, ``map1``, ``10x10x10``: those are words).
NUMBER = re.compile(r"(?<![A-Za-z_])-?\d[\d,]*(?:\.\d+)?")
#: How far a number printed in an error or warning line may be from the documented one,
#: beyond a step of the documented number's last digit (a value on the other side of a
#: rounding boundary), relative to its size: another CPU, BLAS build or numba target
#: changes the last digits of what is computed, and no documented example may hinge on
#: them (pick examples with a clear margin).
NUMBER_SLACK = 2e-3
#: An error line of quadnav, or of one of its commands' parsers (``quadnav fly: error:``).
ERROR_LINE = re.compile(r"quadnav[\w ]*: error: ")


@dataclass
class DocCommand:
    """One command line of a page and the output written under it (may be empty)."""

    line: str
    output: list[str] = field(default_factory=list)

    @property
    def argv(self) -> list[str]:
        """The command's arguments after ``quadnav``, up to any ``| head``."""
        return shlex.split(self.line.split(" | ")[0])[1:]

    @property
    def is_interrupted(self) -> bool:
        """Shown stopped by Ctrl-C (``^C`` in its output): only parsed, as a test cannot
        press Ctrl-C at the moment shown (tests/test_batch_resume.py does it for real)."""
        return any(line.startswith("^C") for line in self.output)

    @property
    def shows_a_usage_error(self) -> bool:
        """Shown refused by its command's parser, as an example of a bad flag: an error line
        that names the command (``quadnav fly: error: unrecognized arguments: ...``)."""
        return any(re.match(r"quadnav [\w ]+: error: ", line) for line in self.output)

    @property
    def is_synopsis(self) -> bool:
        return bool(PLACEHOLDER.search(self.line.removeprefix("quadnav")))

    @property
    def needs_fetched_map(self) -> bool:
        """Whether it fetches course maps or reads one that quadnav does not ship."""
        argv = self.argv
        return argv[:2] in (["maps", "fetch"], ["map", "fetch"]) or any(
            catalogue()[arg.removeprefix(PREFIX)].shipped is None for arg in argv
            if arg.startswith(PREFIX) and arg.removeprefix(PREFIX) in catalogue())


def _commands(page: Path) -> list[DocCommand]:
    """The ``quadnav ...`` lines of the page's code blocks in order (continuation lines
    joined, comments and ``&&`` chains split off), each with the output lines that follow
    a ``$ quadnav`` line up to the next ``$`` line or the end of the block."""
    found: list[DocCommand] = []
    block, pending, taking = None, "", False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            block, taking = (line[3:].strip() if block is None else None), False
            continue
        if block is None:
            continue
        if taking and not line.startswith("$ "):
            found[-1].output.append(line)
            continue
        text = pending + line.strip()
        if text.endswith("\\"):
            pending = text[:-1] + " "
            continue
        pending = ""
        taking = text.startswith("$ quadnav")
        for part in re.split(r"\s(?:&&|;)\s", text.removeprefix("$ ")):
            part = part.split(" #")[0].strip()
            if part.startswith("quadnav ") or part == "quadnav":
                found.append(DocCommand(part))
    return found


#: A code block that is a file the page's commands read: its first line ``# file: NAME``
#: (a comment of the file too), then the rest of the file.
FILE_BLOCK = re.compile(r"^```\w*\n(# file: ([\w.-]+).*?\n.*?)^```", re.DOTALL | re.MULTILINE)


def _files(page: Path) -> dict[str, str]:
    """The files a page shows whole (:data:`FILE_BLOCK`), their text by name: written into
    the page's folder before its commands run."""
    return {match.group(2): match.group(1) for match in FILE_BLOCK.finditer(page.read_text())}


PAGE_COMMANDS = {page.name: _commands(page) for page in PAGES}
PAGE_FILES = {page.name: _files(page) for page in PAGES}
RUNNABLE = {name: [c for c in commands if not c.is_synopsis]
            for name, commands in PAGE_COMMANDS.items()}
#: Pages run, each once: a page whose command lines are those of an earlier page
#: (docs/index.md repeats the README's quick start) is covered by that page's run.
PAGES_RUN = [name for i, (name, commands) in enumerate(RUNNABLE.items()) if commands and all(
    [c.line for c in commands] != [c.line for c in other] for other in
    list(RUNNABLE.values())[:i])]


def _masked(line: str) -> str:
    return NUMBER.sub("#", line.strip())


def _value(number: str) -> float:
    return float(number.replace(",", ""))


def _tolerance(number: str) -> float:
    """How far a value may be from the documented ``number`` (its text) and still read
    as it: a step of its last digit plus :data:`NUMBER_SLACK` of it. A whole number is
    read to 3 significant digits (quadnav writes measured values with ``%.3g``, so ``3``
    may stand for 3.00; a count or an index of 1 or 2 digits stays exact)."""
    whole, _, decimals = number.lstrip("-").replace(",", "").partition(".")
    step = 10.0 ** (-len(decimals) if decimals else len(whole.lstrip("0") or "0") - 3)
    return step + NUMBER_SLACK * abs(_value(number))


def _says(documented: str, printed: str) -> bool:
    """Whether the ``printed`` line says the ``documented`` one: the same words, and each
    number within the :func:`_tolerance` of the documented one."""
    if _masked(documented) != _masked(printed):
        return False
    numbers = zip(NUMBER.findall(documented), NUMBER.findall(printed), strict=True)
    return all(abs(_value(got) - _value(shown)) <= _tolerance(shown) for shown, got in numbers)


def _check_output(command: DocCommand, code: int, out: str, err: str) -> None:
    """The documented output against what the command printed."""
    documented = [line for line in command.output if line.strip() and line.strip() != "..."]
    error = [line for line in documented if ERROR_LINE.match(line)]
    assert code == (2 if error else 0), f"{command.line}: exit {code}\n{err[-2000:]}"
    printed = out.splitlines() + err.splitlines()
    for line in documented:
        if ERROR_LINE.match(line) or line.startswith("quadnav: warning:"):
            assert any(_says(line, p) for p in printed), (
                f"{command.line}: documented\n  {line}\nprinted\n{err}")
        else:
            assert _masked(line) in {_masked(p) for p in printed}, (
                f"{command.line}: documented\n  {line}\nprinted\n{out}")


def test_the_pages_have_commands_to_run():
    assert sum(map(len, RUNNABLE.values())) > 25
    assert set(PAGES_RUN) >= {
        "README.md", "flying.md", "batch.md", "tello.md", "track.md", "seeing.md"}


def test_a_command_with_a_placeholder_is_a_synopsis():
    assert DocCommand("quadnav fly MAP -o DIR").is_synopsis
    assert DocCommand("quadnav report runs/a [-o FILE]").is_synopsis
    assert not DocCommand("quadnav fly forest:seed=3 -o runs/forest3 --html").is_synopsis


@pytest.fixture(scope="module")
def course_maps_url():
    """The base URL of a loopback server of ../shared/maps laid out as ``quadnav maps fetch``
    downloads them, or None when the folder is absent."""
    if not SHARED_MAPS.is_dir():
        yield None
        return
    with serving(course_files(SHARED_MAPS)) as url:
        yield url


#: A documented error line (docs/flying.md) and what another machine may print for it.
REFUSAL = ("quadnav: error: the tello vehicle cannot fly this trajectory: speed 9.82 m/s "
           "exceeds the limit 7.2 m/s at t = 1.25 s (with 10% kept for control); the same "
           "path flies within every limit at --speed 6.57 --accel 7.86 or less")


def test_a_documented_number_may_differ_in_its_last_digit():
    # Rounded the other way (9.815 on one machine, 9.825 on another), a peak a sample
    # later, a value written with 3 digits that another machine writes with 3 more.
    for shown, printed in (("9.82", "9.83"), ("1.25 s", "1.24 s"), ("7.2 m/s", "7.2049 m/s"),
                           ("--speed 6.57", "--speed 6.56")):
        assert _says(REFUSAL, REFUSAL.replace(shown, printed)), printed
    assert _says("thrust-to-weight ratio 2 exceeds", "thrust-to-weight ratio 2.01 exceeds")


def test_a_documented_line_with_a_number_clearly_off_or_other_words_is_not_printed():
    for shown, printed in (("9.82", "9.91"), ("--accel 7.86", "--accel 7.7"),
                           ("--speed 6.57", "--speed 6"), ("10%", "11%"),
                           ("the tello", "the rbe595"), ("exceeds", "is below")):
        assert not _says(REFUSAL, REFUSAL.replace(shown, printed)), printed
    # Digits of a name are words; a one- or two-digit whole number is exact.
    assert not _says("map rbe595/map1.txt", "map rbe596/map1.txt")
    assert not _says("map rbe595/map1.txt", "map rbe595/map2.txt")
    assert not _says("maze.json:12: blocks[3]", "maze.json:13: blocks[3]")
    assert not _says("maze.json:12: blocks[3]", "maze.json:12: blocks[4]")
    command = DocCommand("quadnav fly --speed 10 --accel 20", [REFUSAL])
    _check_output(command, 2, "", REFUSAL.replace("1.25", "1.26") + "\n")
    with pytest.raises(AssertionError, match="documented"):
        _check_output(command, 2, "", REFUSAL.replace("7.86", "8.3") + "\n")


@pytest.mark.parametrize("page", PAGES_RUN)
def test_the_commands_of_a_page_run_as_written(page, tmp_path, monkeypatch, capsys,
                                               course_maps_url):
    commands = RUNNABLE[page]
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "course-cache"))
    monkeypatch.setenv(URL_ENV, course_maps_url or dead_url())
    (tmp_path / "work").mkdir()
    (tmp_path / "work" / "examples").symlink_to(ROOT / "examples")  # as in a checkout
    for name, text in PAGE_FILES[page].items():
        (tmp_path / "work" / name).write_text(text)
    monkeypatch.chdir(tmp_path / "work")
    skipped = []
    for command in commands:
        if not command.shows_a_usage_error:
            build_parser(command.argv).parse_args(command.argv)  # a bad flag fails here first
        if command.is_interrupted or command.argv[0] == "blender":
            continue
        if course_maps_url is None and command.needs_fetched_map:
            skipped.append(command.line)
            continue
        capsys.readouterr()
        try:
            code = main(command.argv)
        except SystemExit as usage_error:  # argparse's, for a documented bad flag
            code = usage_error.code
        out, err = capsys.readouterr()
        _check_output(command, code, out, err)
    if skipped:
        pytest.skip(f"the course maps are not at {SHARED_MAPS} to serve: ran the other "
                    f"commands; skipped the {len(skipped)} that fetch or read a fetched "
                    f"course map: {'; '.join(skipped)}")
