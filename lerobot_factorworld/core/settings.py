"""One way for every ``factorworld`` command to read its settings: :func:`parse_config`.

draccus parses ``--key=value`` flags (and an optional ``--config_path`` YAML file) into the command's
dataclass, whose ``__post_init__`` validates every field (see :mod:`lerobot_factorworld.core.checks`).
Whatever goes wrong (an unknown key, a value of the wrong type, an unreadable YAML file, an invalid
value) comes out as one :class:`SettingError` whose message is a single line naming the valid choices;
``cli.main`` prints it as ``error: ...`` and exits with status 2 before any work has started, with no
traceback. Without this, draccus wraps validation errors into 40-line tracebacks.

Adding a command (e.g. ``factorworld study``) takes three steps::

    @dataclass
    class StudyConfig:
        config: str = ""

        def __post_init__(self) -> None:  # raise ValueError / FileNotFoundError naming the valid choices
            check_input_file(self.config, "config")

    def cmd_study(args: list[str]) -> None:
        cfg = parse_config(StudyConfig, args, "study")  # everything is valid from here on
        ...

and ``COMMANDS["study"] = cmd_study`` in :mod:`lerobot_factorworld.cli`.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
import typing
from pathlib import Path
from typing import Any

import draccus
from draccus import cfgparsing
from draccus.argparsing import ArgumentParser
from draccus.utils import DecodingError, DraccusException, ParsingError

CONFIG_PATH_FLAG = "--config_path"
HELP_FLAGS = ("-h", "--help")
LIST_DECODING_ERROR = "is not of a valid input for a list type"  # draccus's message for a non-list value


class SettingError(ValueError):
    """A bad command-line setting, already reduced to one line that says what is valid."""


def parse_config[T](cls: type[T], args: list[str], command: str = "") -> T:
    """Parse and validate ``cls`` from ``args`` (``--key=value`` and ``--config_path=file.yaml``).

    ``--help`` prints draccus's help and exits 0. Any other failure raises :class:`SettingError`.
    """
    prog = f"factorworld {command}".strip()
    if any(arg in HELP_FLAGS for arg in args):
        return draccus.parse(cls, args=args, prog=prog)
    parser = ArgumentParser(config_class=cls, exit_on_error=False, prog=prog)
    parser.parser.error = _raise_setting_error  # argparse would print its usage block and exit
    flags = sorted(f for f in parser.parser._option_string_actions if f not in HELP_FLAGS)
    _check_flags(args, flags)
    config_path = _config_path(args)
    if config_path is not None:
        _check_config_file(cls, config_path, flags)
    try:
        return parser.parse_args(args)
    except Exception as err:  # draccus wraps validation errors: report their innermost cause
        raise SettingError(one_line(describe(err, flags))) from None


def describe(err: BaseException, flags: list[str] | None = None) -> str:
    """The message that matters in a (draccus-wrapped) parsing or validation error."""
    if isinstance(err, DecodingError):
        key = ".".join(err.key_path)
        if err.message.startswith("Failed when parsing") and err.__cause__ is not None:
            cause = describe(err.__cause__, flags)  # e.g. a nested config (sampling) refused its values
            if LIST_DECODING_ERROR in cause or isinstance(err.__cause__, (AttributeError, TypeError)):
                cause = f"expected {_expected(err.message, key)}"  # a value of the wrong shape
            return f"bad value for --{key}: {cause}"
        unknown = re.findall(r"`([^`]+)`", err.message) if err.message.startswith("The fields") else []
        if unknown:  # unknown keys inside a nested mapping (e.g. --sampling='{bogus: 1}')
            return _unknown_message([f"--{key + '.' if key else ''}{k}" for k in unknown], flags or [])
        return f"bad value for --{key}: {err.message}" if key else err.message
    if isinstance(err, ParsingError) and err.__cause__ is not None:
        return describe(err.__cause__, flags)
    if isinstance(err, DraccusException) and str(err).startswith("unrecognized arguments"):
        return f"{err}; settings are given as --key=value; valid settings: {', '.join(flags or [])}"
    return str(err) or type(err).__name__


def _expected(message: str, key: str) -> str:
    """What a field takes, from draccus's "... into field "X.y" of type T." message."""
    match = re.search(r"of type (.*?)\.\s+Underlying", message, re.DOTALL)
    kind = match.group(1) if match else ""
    if kind.startswith("list"):
        return "a list such as [a,b]"
    if kind.startswith("dict"):
        return "a mapping such as {a: b}"
    if kind.startswith("<class"):  # a nested config
        return f"its settings as --{key}.<setting>=value"
    return kind or "another kind of value"


def one_line(message: str) -> str:
    return re.sub(r"\s*\n\s*", " ", message).strip()


def _raise_setting_error(message: str) -> typing.NoReturn:
    raise SettingError(message)


def _check_flags(args: list[str], flags: list[str]) -> None:
    unknown = [arg.split("=", 1)[0] for arg in args if arg.startswith("--") and arg.split("=", 1)[0] not in flags]
    if unknown:
        raise SettingError(_unknown_message(unknown, flags))


def _unknown_message(unknown: list[str], flags: list[str]) -> str:
    hints = []
    for key in unknown:
        close = difflib.get_close_matches(key, flags, n=1)
        hints.append(f"{key} (did you mean {close[0]}?)" if close else key)
    return f"unknown setting(s) {', '.join(hints)}; valid settings: {', '.join(flags)}"


def _config_path(args: list[str]) -> str | None:
    for i, arg in enumerate(args):
        if arg.startswith(CONFIG_PATH_FLAG + "="):
            return arg.split("=", 1)[1]
        if arg == CONFIG_PATH_FLAG:
            if i + 1 >= len(args):
                raise SettingError(f"{CONFIG_PATH_FLAG} needs a YAML file: {CONFIG_PATH_FLAG}=file.yaml")
            return args[i + 1]
    return None


def _check_config_file(cls: type, path: str, flags: list[str]) -> None:
    """The YAML file exists, parses to a mapping, and names only settings ``cls`` has."""
    file = Path(path).expanduser()
    if not file.is_file():
        raise SettingError(f"{CONFIG_PATH_FLAG} {path} " + ("is not a file" if file.exists() else "does not exist"))
    try:
        with file.open(encoding="utf-8") as stream:
            content = cfgparsing.load_config(stream, file=str(file))
    except Exception as err:
        cause = err.__cause__ or err
        raise SettingError(one_line(f"{CONFIG_PATH_FLAG} {path} is not valid YAML: {cause}")) from None
    if content is None:
        raise SettingError(f"{CONFIG_PATH_FLAG} {path} is empty; it must hold a mapping of settings (key: value)")
    if not isinstance(content, dict):
        raise SettingError(
            f"{CONFIG_PATH_FLAG} {path} must hold a mapping of settings (key: value), not a list or value"
        )
    unknown = [f"--{key}" for key in _unknown_keys(cls, content)]
    if unknown:
        raise SettingError(f"in {path}: " + _unknown_message(unknown, flags))


def _unknown_keys(cls: type, content: dict[str, Any], prefix: str = "") -> list[str]:
    hints = typing.get_type_hints(cls)
    names = {f.name: hints.get(f.name) for f in dataclasses.fields(cls) if f.init}
    unknown = []
    for key, value in content.items():
        if key not in names:
            unknown.append(f"{prefix}{key}")
        elif dataclasses.is_dataclass(names[key]) and isinstance(value, dict):
            unknown += _unknown_keys(names[key], value, f"{prefix}{key}.")
    return unknown
