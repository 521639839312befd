"""Settings that name local files: made absolute when a config is read, since steps run in their own folders.

A policy setting or ``lerobot-train`` flag named ``*_path`` or ``*_root`` is a path; one named
``*weights_path`` names a weights file that must exist before a study starts (weights are never downloaded).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

PATH_SUFFIXES = ("_path", "_root")  # settings named like this are local paths: resolved when the config is read
WEIGHTS_SUFFIX = "weights_path"  # ... and these name weight files that must exist before a study starts


def is_path_setting(name: str) -> bool:
    """A policy setting or ``lerobot-train`` flag that names a local file or folder."""
    return name.endswith(PATH_SUFFIXES)


def absolute_path(value: str) -> str:
    """``value`` made absolute against the directory the command runs from (steps run elsewhere)."""
    return os.path.abspath(os.path.expanduser(value))


def map_policy_paths(policy: dict[str, Any], convert: Callable[[str], str]) -> dict[str, Any]:
    """The policy settings with ``convert`` applied to every path-like value (``*_path``, ``*_root``, nested too)."""
    out: dict[str, Any] = {}
    for name, value in policy.items():
        if isinstance(value, dict):
            out[name] = map_policy_paths(value, convert)
        elif isinstance(value, str) and value and is_path_setting(name):
            out[name] = convert(value)
        else:
            out[name] = value
    return out


def resolve_policy_paths(policy: dict[str, Any]) -> dict[str, Any]:
    """The policy settings with every path-like value made absolute."""
    return map_policy_paths(policy, absolute_path)


def split_flag(arg: str) -> tuple[str, str] | None:
    """``--a.b_path=x`` -> (``a.b_path``, ``x``); ``None`` for anything that is not ``--name=value``."""
    if not arg.startswith("--") or "=" not in arg:
        return None
    name, _, value = arg[2:].partition("=")
    return name, value


def map_arg_paths(args: list[str], convert: Callable[[str], str]) -> list[str]:
    """``lerobot-train`` flags with ``convert`` applied to path-like values (``--x.y_path=...``, ``--x.y_root=...``)."""
    out = []
    for arg in args:
        flag = split_flag(arg)
        if flag and flag[1] and is_path_setting(flag[0]):
            arg = f"--{flag[0]}={convert(flag[1])}"
        out.append(arg)
    return out


def resolve_arg_paths(args: list[str]) -> list[str]:
    """``lerobot-train`` flags with path-like values made absolute."""
    return map_arg_paths(args, absolute_path)


def policy_paths(policy: dict[str, Any], prefix: str = "") -> dict[str, str]:
    """Dotted setting name -> path, for every path-like policy setting (nested too)."""
    out: dict[str, str] = {}
    for name, value in policy.items():
        if isinstance(value, dict):
            out.update(policy_paths(value, f"{prefix}{name}."))
        elif isinstance(value, str) and value and is_path_setting(name):
            out[prefix + name] = value
    return out
