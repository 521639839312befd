"""The package's import graph stays layered (docs/architecture.md): the import-linter contract in
pyproject.toml holds, and it really fails on an upward import or an unexplained import inside a function."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _copy(tmp_path: Path) -> Path:
    """The package and its lint settings in a scratch folder (edits there never touch the checkout)."""
    shutil.copytree(
        REPO / "lerobot_factorworld",
        tmp_path / "lerobot_factorworld",
        ignore=shutil.ignore_patterns("__pycache__", "*.json", "*.png"),
    )
    shutil.copy(REPO / "pyproject.toml", tmp_path / "pyproject.toml")
    return tmp_path


def _lint_imports(root: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(root)}  # the copy shadows the installed package
    return subprocess.run([str(BIN / "lint-imports"), "--no-cache"], cwd=root, env=env, capture_output=True, text=True)


def test_the_layer_contracts_hold():
    out = _lint_imports(REPO)
    assert out.returncode == 0, out.stdout[-3000:]
    assert "0 broken" in out.stdout


def test_an_upward_import_breaks_the_layer_contract(tmp_path):
    root = _copy(tmp_path)
    low = root / "lerobot_factorworld" / "core" / "splits.py"
    low.write_text(low.read_text() + "\nfrom ..study import metrics  # an arrow from the bottom layer to the study\n")
    out = _lint_imports(root)
    assert out.returncode != 0
    assert "lerobot_factorworld.core is not allowed to import lerobot_factorworld.study" in out.stdout


def test_a_family_package_imported_below_its_layer_breaks_the_contract(tmp_path):
    root = _copy(tmp_path)
    env = root / "lerobot_factorworld" / "envs" / "factor_env.py"
    env.write_text(env.read_text() + "\nfrom ..pick import catalog  # a lower layer naming a family\n")
    out = _lint_imports(root)
    assert out.returncode != 0 and "not allowed to import lerobot_factorworld.pick" in out.stdout


def test_an_unexplained_import_inside_a_function_fails_ruff(tmp_path):
    root = _copy(tmp_path)
    module = root / "lerobot_factorworld" / "core" / "io.py"
    module.write_text(module.read_text() + "\n\ndef late():\n    import json\n\n    return json\n")
    out = subprocess.run(
        [str(BIN / "ruff"), "check", "--no-cache", "--select", "PLC0415", str(module)],
        cwd=root,
        capture_output=True,
        text=True,
    )
    assert out.returncode != 0 and "PLC0415" in out.stdout
