"""Plug-in points by name: a :class:`Registry` each of planners, trajectory methods,
references, controllers, winds, built-in worlds and vehicle presets, which a user adds to
in their own process (:meth:`Registry.register`, :meth:`Registry.unregister`) or which an
installed package declares as entry points, so the ``quadnav`` command and batch workers
know them too::

    [project.entry-points."quadnav.planners"]
    mine = "my_package.my_module:plan_mine"

Listing a registry imports nothing: a built-in given as a :class:`Lazy` (OMPL's planners,
which need an optional wheel) and an entry point are imported when first asked for, and an
entry point that cannot be imported names itself in one line then, leaving the others be.

A plug-in may also be named where it is, without registering it (:func:`parse_spec`,
:meth:`Registry.load`): ``module.path:Name`` (an importable module) or ``path/to/file.py:Name``
(a file, loaded by path), optionally followed by keyword arguments that are Python literals,
``my_wind.py:Gusty(speed=3.0, axis=[1, 0, 0])`` (read with :func:`ast.literal_eval`, never
evaluated). A name and its arguments travel between processes as the text itself: a batch
worker loads the plug-in again from it.
"""

from __future__ import annotations

import ast
import hashlib
import importlib
import importlib.util
import inspect
import sys
import traceback
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path
from types import MappingProxyType, ModuleType
from typing import Any, Generic, TypeVar

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.inputfiles import special_file
from quadnav.signals import interrupt_behind

Plugin = TypeVar("Plugin")
#: quadnav's own folder: frames in it are left out of a plug-in's traceback.
_PACKAGE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class OptionalWheel:
    """An optional package a built-in plug-in needs, installed by one of quadnav's extras.

    Attributes:
        module: the name it is imported by ("ompl").
        label: what messages call it ("OMPL").
        extra: the quadnav extra that installs it ("ompl").
    """

    module: str
    label: str
    extra: str

    def missing(self) -> bool:
        """Whether it is not installed."""
        return importlib.util.find_spec(self.module) is None


@dataclass(frozen=True)
class Lazy:
    """A built-in plug-in imported on first use: the object ``target`` (``module:name``)
    names, or, given ``args``, what that object returns when called with them.

    Attributes:
        target: ``module.path:Name``.
        args: the arguments of a factory; none: the target is the plug-in itself.
        needs: the optional package it needs, checked before it is imported.
    """

    target: str
    args: tuple[Any, ...] = ()
    needs: OptionalWheel | None = None


class Registry(Generic[Plugin]):
    """Plug-ins by name: the built-in ones, then those of installed packages' entry points in
    ``group``, then those registered here. Listing the names imports nothing; an entry
    given as a :class:`Lazy` (or its ``module:name`` text) or by an entry point is
    imported the first time it is asked for, and one that cannot be imported says so in one
    line (:class:`PluginError`) without disturbing the others.

    Args:
        kind: what the plug-ins are, for messages ("planner").
        group: the entry-point group ("quadnav.planners").
        builtins: the built-in plug-ins by name, in the order they are listed: each the
            plug-in itself, or a :class:`Lazy` or ``module:name`` text naming it.
        located: how a plug-in named where it is is written, for messages.
        expects: the type of every registered plug-in; None: any function or class.
    """

    def __init__(self, kind: str, group: str, builtins: Mapping[str, Plugin | Lazy | str],
                 located: str = "module:NAME or file.py:NAME",
                 expects: type | None = None) -> None:
        self.kind = kind
        self.group = group
        self.located = located
        self.expects = expects
        self._entries: dict[str, Plugin | Lazy | EntryPoint] = {
            name: Lazy(entry) if isinstance(entry, str) else entry
            for name, entry in builtins.items()}
        self._found_entry_points = False

    def _names(self) -> dict[str, Plugin | Lazy | EntryPoint]:
        """Every entry by name; the entry points of installed packages are found (not
        loaded) the first time."""
        if not self._found_entry_points:
            self._found_entry_points = True
            for point in entry_points(group=self.group):
                self._entries.setdefault(point.name, point)
        return self._entries

    def register(self, name: str, plugin: Plugin, replace: bool = False) -> None:
        """Make ``plugin`` known as ``name`` in this process. QuadnavError for a name that
        is empty or holds a space or a colon, for something not callable (or not of the
        type the registry :attr:`expects`), or for a name taken (unless ``replace``)."""
        if not name or any(c.isspace() or c == ":" for c in name):
            raise QuadnavError(f"{self.kind} name {name!r}: expected a word without spaces "
                               "or colons")
        if self.expects is None and not callable(plugin):
            raise QuadnavError(f"{self.kind} {name!r}: expected a function, got {plugin!r}")
        if self.expects is not None and not isinstance(plugin, self.expects):
            raise QuadnavError(f"{self.kind} {name!r}: expected a {self.expects.__name__}, "
                               f"got {plugin!r}")
        if name in self._names() and not replace:
            raise QuadnavError(f"{self.kind} {name!r} is already registered")
        self._entries[name] = plugin

    def unregister(self, name: str) -> None:
        """Forget the plug-in ``name`` in this process; QuadnavError if there is none."""
        if name not in self._names():
            raise self.unknown(name)
        del self._entries[name]

    def names(self) -> list[str]:
        """Every name known, the built-in ones first."""
        return list(self._names())

    def __contains__(self, name: object) -> bool:
        return name in self._names()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def get(self, name: str) -> Plugin:
        """The plug-in called ``name``, imported if it was not yet. QuadnavError naming the
        choices if there is none; :class:`PluginError` naming it when it cannot be
        imported (an optional package missing, an installed package's entry point that
        raised)."""
        if name not in self._names():
            raise QuadnavError(f"unknown {self.kind} {name!r}; expected one of "
                               f"{', '.join(self.names())}")
        entry = self._entries[name]
        if isinstance(entry, Lazy):
            entry = self._entries[name] = self._load_lazy(name, entry)
        elif isinstance(entry, EntryPoint):
            entry = self._entries[name] = self._load_entry_point(name, entry)
        return entry

    def _load_lazy(self, name: str, lazy: Lazy) -> Plugin:
        if lazy.needs is not None and lazy.needs.missing():
            raise PluginError(f"{self.kind} {name!r} needs the optional {lazy.needs.label} "
                              f"wheel: python -m pip install 'quadnav[{lazy.needs.extra}]'")
        found = load_target(lazy.target, self.kind)
        return found(*lazy.args) if lazy.args else found

    def _load_entry_point(self, name: str, point: EntryPoint) -> Plugin:
        try:
            return point.load()
        except Exception as error:
            _stop_behind(error)
            raise PluginError(f"{self.kind} {name!r} from package entry point {point.value} "
                              f"could not be loaded: {type(error).__name__}: {error}",
                              details=user_traceback(error)) from None

    def is_located(self, text: str) -> bool:
        """Whether ``text`` says where its plug-in is (``where:Name``, :func:`parse_spec`)
        rather than naming an entry: a name before the colon that built-in entries use as
        their prefix (``ompl:`` of ``ompl:RRTstar``) is not a place."""
        spec = parse_spec(text, self.kind)
        prefixes = {name.partition(":")[0] for name in self._entries if ":" in name}
        return spec.is_located and spec.target.partition(":")[0] not in prefixes

    def unknown(self, text: str) -> QuadnavError:
        """The error for ``text``, which names no entry: the names known, and how a plug-in
        named where it is is written."""
        names = f"one of {', '.join(self.names())}, or " if self.names() else ""
        return QuadnavError(f"unknown {self.kind} {text!r}; expected {names}{self.located}")

    def load(self, text: str) -> tuple[Any, Mapping[str, Any]]:
        """What ``text`` names (a registered name, ``module:Name`` or ``file.py:Name``, see
        :func:`parse_spec`) and the keyword arguments it gives. QuadnavError (a
        :class:`PluginError` for the user's own code) when it cannot be found or loaded."""
        spec = parse_spec(text, self.kind)
        if spec.target in self:
            return self.get(spec.target), spec.kwargs
        if self.is_located(text):
            return load_target(spec.target, self.kind), spec.kwargs
        raise self.unknown(spec.target)


class PluginError(QuadnavError):
    """A plug-in that could not be loaded or that failed while it ran: one line for the user,
    plus, when the plug-in's own code raised, that code's traceback (:attr:`details`), which
    the command line prints once above the line.

    Attributes:
        details: the traceback of the plug-in's own exception, or None.
        exit_code: the command's exit code: 2 for a plug-in that cannot be used (bad input),
            1 for a flight that failed because of it.
    """

    def __init__(self, message: str, details: str | None = None, exit_code: int = 2) -> None:
        super().__init__(message)
        self.details = details
        self.exit_code = exit_code


@dataclass(frozen=True)
class PluginSpec:
    """A plug-in as a user names it.

    Attributes:
        text: the text as given.
        target: a registered name, ``module.path:Name`` or ``path/to/file.py:Name``.
        kwargs: the keyword arguments given after it (Python literals), read-only.
    """

    text: str
    target: str
    kwargs: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    @property
    def is_located(self) -> bool:
        """Whether :attr:`target` says where the plug-in is (``where:Name``) rather than
        naming a registered one."""
        return ":" in self.target


def parse_spec(text: str, kind: str = "plug-in") -> PluginSpec:
    """``text`` read as ``TARGET`` or ``TARGET(key=literal, ...)``; QuadnavError naming it
    and what was expected for anything else (positional arguments, a value that is not a
    literal, a missing parenthesis)."""
    text = text.strip()
    target, _, arguments = text.partition("(")
    target = target.strip()
    expected = (f"{kind} {text!r}: expected NAME, module:NAME or path/to/file.py:NAME, "
                "optionally with keyword arguments that are literals: NAME(key=value, ...)")
    if not target or any(c.isspace() for c in target) or target.count(":") > 1 or (
            ":" in target and not all(target.split(":"))):
        raise QuadnavError(expected)
    if not arguments:
        return PluginSpec(text, target)
    try:
        call = ast.parse(f"f({arguments}", mode="eval").body
    except SyntaxError:
        raise QuadnavError(expected) from None
    if not isinstance(call, ast.Call) or call.args or any(k.arg is None for k in call.keywords):
        raise QuadnavError(f"{kind} {text!r}: give its arguments by keyword, key=value")
    kwargs: dict[str, Any] = {}
    for keyword in call.keywords:
        try:
            kwargs[str(keyword.arg)] = ast.literal_eval(keyword.value)
        except ValueError:
            raise QuadnavError(
                f"{kind} {text!r}: the value of {keyword.arg} is not a literal (expected a "
                f"number, string, True/False/None, or a list, tuple or dict of them, got "
                f"{ast.unparse(keyword.value)})") from None
    return PluginSpec(text, target, MappingProxyType(kwargs))


def load_target(target: str, kind: str = "plug-in") -> Any:
    """The object ``module.path:Name`` or ``path/to/file.py:Name`` names (``Name`` may be
    dotted: ``Outer.Inner``). A file is loaded by path, once per process. QuadnavError when
    the module or file is not there or lacks the name; :class:`PluginError` with the user
    code's traceback when loading it raised."""
    where, _, name = target.partition(":")
    module = _load_file(where, kind) if where.endswith(".py") else _import(where, kind)
    found: Any = module
    for part in name.split("."):
        if not hasattr(found, part):
            defined = sorted(n for n, v in vars(module).items()
                             if not n.startswith("_") and getattr(v, "__module__", None)
                             == module.__name__)
            raise QuadnavError(f"{kind} {target}: {where} has no {name!r}"
                               + (f" (it defines {', '.join(defined)})" if defined else ""))
        found = getattr(found, part)
    return found


def _import(name: str, kind: str) -> ModuleType:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as error:
        if error.name is not None and name.startswith(error.name):
            raise QuadnavError(f"{kind} {name}: no module named {error.name!r} (is it "
                               "installed, or did you mean path/to/file.py?)") from None
        raise _raised_while_loading(name, kind, error) from None
    except Exception as error:
        raise _raised_while_loading(name, kind, error) from None


def _load_file(path: str, kind: str) -> ModuleType:
    file = Path(path).expanduser().resolve()
    if not file.is_file():
        what = special_file(file)
        raise QuadnavError(f"{kind} {path}: " + (f"{what}, not a Python file" if what
                                                  else "no such file"))
    # One module per file, under a name unlikely to collide, kept in sys.modules so that
    # the file's classes pickle and its own relative lookups work.
    name = f"quadnav_plugin_{file.stem}_{hashlib.sha1(str(file).encode()).hexdigest()[:8]}"
    if name in sys.modules:
        return sys.modules[name]
    loader_spec = importlib.util.spec_from_file_location(name, file)
    if loader_spec is None or loader_spec.loader is None:
        raise QuadnavError(f"{kind} {path}: not a Python file")
    module = importlib.util.module_from_spec(loader_spec)
    sys.modules[name] = module
    try:
        loader_spec.loader.exec_module(module)
    except Exception as error:
        del sys.modules[name]
        raise _raised_while_loading(path, kind, error) from None
    return module


def _stop_behind(error: Exception) -> None:
    """Raise the Ctrl-C or stop signal that cut a plug-in's loading short and became
    ``error`` (the RuntimeError of a class whose ``__set_name__`` it interrupted, an
    import's ImportError): a stop, not a broken plug-in."""
    interrupt = interrupt_behind(error)
    if interrupt is not None:
        raise interrupt


def _raised_while_loading(where: str, kind: str, error: Exception) -> PluginError:
    """The error of a plug-in that raised ``error`` while it loaded (a stop behind it is
    raised instead: :func:`_stop_behind`)."""
    _stop_behind(error)
    return PluginError(f"{kind} {where}: {type(error).__name__} while loading it: {error}",
                       details=user_traceback(error))


def user_traceback(error: BaseException) -> str | None:
    """The traceback of ``error`` without quadnav's own frames: what the plug-in's author
    needs to see; None when none of it is the plug-in's (it was called with arguments it
    does not take, say) and the error is one line, which the message already holds."""
    frames = [frame for frame in traceback.extract_tb(error.__traceback__)
              if not frame.filename.startswith("<frozen ")
              and not Path(frame.filename).resolve().is_relative_to(_PACKAGE)]
    only = traceback.format_exception_only(type(error), error)
    if not frames and len("".join(only).splitlines()) <= 1:
        return None
    lines = ["Traceback (most recent call last):\n", *traceback.format_list(frames), *only]
    return "".join(lines).rstrip("\n")


def literal_arrays(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """``kwargs`` with every non-empty list or tuple of numbers (nested to any depth, as
    long as it is rectangular) turned into a float64 numpy array: the form numerical code,
    rotorpy's classes among it, does arithmetic on (``2 * np.pi * freq``). Other values are
    passed as they are."""
    return {key: np.array(value, dtype=np.float64) if _numbers(value) else value
            for key, value in kwargs.items()}


def _numbers(value: Any) -> bool:
    """Whether ``value`` is a non-empty, rectangular list or tuple of numbers (not bools),
    nested to any depth."""
    if not isinstance(value, list | tuple) or not value:
        return False
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        return True
    return (all(_numbers(v) for v in value)
            and len({np.shape(v) for v in value}) == 1)


def check_call(kind: str, text: str, function: Callable, positional: tuple[str, ...],
               kwargs: Mapping[str, Any]) -> None:
    """QuadnavError (exit 2) unless ``function`` can be called with the arguments named
    ``positional`` (``("world", "start", "goal", "margin")``: how quadnav calls it) and
    ``kwargs``; a function whose signature Python cannot read passes."""
    try:
        parameters = inspect.signature(function)
    except (TypeError, ValueError):
        return
    try:
        parameters.bind(*positional, **kwargs)
    except TypeError as error:
        call = ", ".join([*positional, *(f"{key}=..." for key in kwargs)])
        name = getattr(function, "__name__", kind)
        raise QuadnavError(f"{kind} {text}: cannot be called as {name}({call}): "
                           f"{error}") from None


def takes_keyword(function: Callable, name: str) -> bool:
    """Whether ``function`` has a parameter called ``name`` that can be given by keyword
    (False when Python cannot read its signature)."""
    try:
        parameter = inspect.signature(function).parameters.get(name)
    except (TypeError, ValueError):
        return False
    return parameter is not None and parameter.kind in (
        inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)


def raised_in(kind: str, text: str, where: str | None, error: Exception,
              exit_code: int = 1) -> PluginError:
    """The :class:`PluginError` for ``error``, raised by the plug-in ``text`` (in ``where``,
    e.g. ``"update(0.5)"``, when given), with its own traceback: exit 1 by default, a
    flight or plan that failed because of the plug-in."""
    place = f": {where}" if where else ""
    return PluginError(f"{kind} {text}{place} raised {type(error).__name__}: {error}",
                       details=user_traceback(error), exit_code=exit_code)
