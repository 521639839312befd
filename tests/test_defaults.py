"""One home for every default: the image size, the observation camera, the demonstrations' action noise and the
render quality are each defined once and imported everywhere else (the episode limits live in ``tasks.py``'s
rows). A second literal definition of one of them anywhere in the package fails here."""

import ast
from pathlib import Path

from lerobot_factorworld.experts import DEFAULT_ACTION_NOISE
from lerobot_factorworld.scene.build import DEFAULT_QUALITY
from lerobot_factorworld.scene.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE

PACKAGE = Path(__file__).resolve().parents[1] / "lerobot_factorworld"
# (the setting's name contains, the default's literal values, its home module)
DEFAULTS = [
    ("image_size", {DEFAULT_IMAGE_SIZE, (DEFAULT_IMAGE_SIZE, DEFAULT_IMAGE_SIZE)}, "scene/cameras.py"),
    ("camera", {DEFAULT_CAMERAS[0], DEFAULT_CAMERAS, ",".join(DEFAULT_CAMERAS)}, "scene/cameras.py"),
    ("action_noise", {DEFAULT_ACTION_NOISE}, "experts.py"),
    ("quality", {DEFAULT_QUALITY}, "scene/build.py"),
]


def _literal(node: ast.AST):
    try:
        return ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        return None


def _settings(tree: ast.AST):
    """(name, value node, line) of every assignment, annotated field, keyword argument and parameter default."""
    for node in ast.walk(tree):
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
            yield node.target.id, node.value, node.lineno
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    yield target.id, node.value, node.lineno
        elif isinstance(node, ast.keyword) and node.arg:
            yield node.arg, node.value, node.value.lineno
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            positional = args.posonlyargs + args.args
            for arg, default in zip(positional[len(positional) - len(args.defaults) :], args.defaults):
                yield arg.arg, default, default.lineno
            for arg, default in zip(args.kwonlyargs, args.kw_defaults):
                if default is not None:
                    yield arg.arg, default, default.lineno


def second_definitions(root: Path = PACKAGE) -> list[str]:
    found = []
    for path in sorted(root.rglob("*.py")):
        relative = path.relative_to(root).as_posix()
        for name, value, line in _settings(ast.parse(path.read_text(), str(path))):
            literal = _literal(value)
            if literal is None or isinstance(literal, bool):
                continue
            for setting, values, home in DEFAULTS:
                if setting in name.lower() and _hashable(literal) in values and relative != home:
                    found.append(f"{relative}:{line}: {name} = {literal!r} (the default lives in {home})")
    return found


def _hashable(value):
    return tuple(value) if isinstance(value, list) else value


def test_every_default_has_one_home():
    assert second_definitions() == []


def test_a_second_literal_definition_is_found(tmp_path):
    (tmp_path / "collect.py").write_text(
        "from dataclasses import dataclass\n"
        "@dataclass\nclass Settings:\n    image_size: int = 84\n    cameras: str = 'front'\n"
        "def run(action_noise=0.002, *, quality='fast'):\n    pass\n"
    )
    assert len(second_definitions(tmp_path)) == 4
