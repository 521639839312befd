"""The package's import graph stays layered (docs/architecture.md): the import-linter contracts in
pyproject.toml hold, every one of them is checked, their layers are the documented ones and cover the package,
and the configuration as written (not a test's own selection) really fails on an upward import, on one policy
importing the other, and on an unexplained import inside a function."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
PACKAGE = "lerobot_factorworld"


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


def _contracts() -> list[dict]:
    return tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]


def _text(out: subprocess.CompletedProcess) -> str:
    """import-linter's report with its line wrapping undone."""
    return " ".join(out.stdout.split())


def test_every_contract_is_checked_and_kept():
    out = _lint_imports(REPO)
    assert out.returncode == 0, out.stdout[-3000:]
    kept = re.search(r"Contracts: (\d+) kept, (\d+) broken\.", _text(out))
    assert kept, out.stdout[-3000:]
    assert int(kept.group(1)) == len(_contracts()) > 0 and kept.group(2) == "0"
    assert {c["type"] for c in _contracts()} == {"layers", "independence", "forbidden"}


def _documented_layers() -> list[set[str]]:
    """docs/architecture.md's layer table, bottom first: each layer's top-level modules (``core/`` -> core,
    ``tasks.py`` -> tasks; the files named in parentheses are inside them)."""
    rows = re.findall(r"^\| \d+[a-z]?\. [^|]+\| ([^|]+) \|", (REPO / "docs" / "architecture.md").read_text(), re.M)
    named = [re.findall(r"`([^`]+)`", re.sub(r"\([^)]*\)", "", row)) for row in rows]
    return [{name.rstrip("/").removesuffix(".py") for name in names} for names in named]


def test_the_layers_are_the_documented_ones_and_hold_every_module_once():
    (layers,) = [c["layers"] for c in _contracts() if c.get("containers") == [PACKAGE]]
    configured = [set(layer.split(" | ")) for layer in reversed(layers)]  # bottom first, as the docs
    assert configured == _documented_layers()
    modules = [m for layer in configured for m in layer]
    package = REPO / PACKAGE
    found = {p.stem for p in package.glob("*.py") if p.name != "__init__.py"}
    found |= {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    assert sorted(modules) == sorted(found)  # every module in exactly one layer


def test_one_policy_importing_the_other_breaks_the_independence_contract(tmp_path):
    (independence,) = [c for c in _contracts() if c["type"] == "independence"]
    assert independence["modules"] == [f"{PACKAGE}.policies.bc", f"{PACKAGE}.policies.rt1"]
    root = _copy(tmp_path)
    module = root / PACKAGE / "policies" / "bc" / "augment.py"
    module.write_text(module.read_text() + "\nfrom ..rt1 import presets  # bc reaching into rt1\n")
    out = _lint_imports(root)
    assert out.returncode != 0
    text = _text(out)
    kept = len(_contracts()) - 1
    assert f"{independence['name']} BROKEN" in text and f"Contracts: {kept} kept, 1 broken." in text
    assert f"{PACKAGE}.policies.bc is not allowed to import {PACKAGE}.policies.rt1" in text


def test_an_upward_import_breaks_the_layer_contract(tmp_path):
    root = _copy(tmp_path)
    low = root / "lerobot_factorworld" / "core" / "splits.py"
    low.write_text(low.read_text() + "\nfrom ..study import paper  # an arrow from the bottom layer to the study\n")
    out = _lint_imports(root)
    assert out.returncode != 0
    assert "lerobot_factorworld.core is not allowed to import lerobot_factorworld.study" in out.stdout


def test_the_statistics_library_imports_nothing_of_the_package(tmp_path):
    """``stats`` names every other top-level module of the package as forbidden to it (so a module added later and
    left out of the layers is caught too), and an import of even the lowest layer breaks that contract."""
    (forbidden,) = [c for c in _contracts() if c["type"] == "forbidden"]
    assert forbidden["source_modules"] == [f"{PACKAGE}.stats"]
    package = REPO / PACKAGE
    found = {p.stem for p in package.glob("*.py") if p.name != "__init__.py"}
    found |= {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    assert sorted(forbidden["forbidden_modules"]) == sorted(f"{PACKAGE}.{m}" for m in found - {"stats"})
    root = _copy(tmp_path)
    module = root / PACKAGE / "stats" / "ranks.py"
    module.write_text(module.read_text() + "\nfrom ..core import rng  # the library reaching into the package\n")
    out = _lint_imports(root)
    assert out.returncode != 0
    text = _text(out)
    assert f"{forbidden['name']} BROKEN" in text
    assert f"{PACKAGE}.stats is not allowed to import {PACKAGE}.core" in text
    assert f"{PACKAGE}.stats.ranks -> {PACKAGE}.core.rng" in text


def test_a_family_package_imported_below_its_layer_breaks_the_contract(tmp_path):
    root = _copy(tmp_path)
    env = root / "lerobot_factorworld" / "envs" / "factor_env.py"
    env.write_text(env.read_text() + "\nfrom ..pick import catalog  # a lower layer naming a family\n")
    out = _lint_imports(root)
    assert out.returncode != 0 and "not allowed to import lerobot_factorworld.pick" in out.stdout


def _ruff(root: Path, *paths: Path) -> subprocess.CompletedProcess:
    """``ruff check`` as ``make lint`` runs it: the rules are the ones pyproject.toml selects."""
    return subprocess.run(
        [str(BIN / "ruff"), "check", "--no-cache", "--output-format=concise", *map(str, paths)],
        cwd=root,
        capture_output=True,
        text=True,
    )


def test_an_unexplained_import_inside_a_function_fails_ruff(tmp_path):
    root = _copy(tmp_path)
    module = root / PACKAGE / "core" / "io.py"
    assert _ruff(root, module).returncode == 0
    module.write_text(module.read_text() + "\n\ndef late():\n    import json\n\n    return json\n")
    out = _ruff(root, module)
    assert out.returncode != 0 and re.findall(r"\bPLC0415\b", out.stdout) == ["PLC0415"], out.stdout
    explained = module.read_text().replace("import json\n", "import json  # noqa: PLC0415 - a reason\n")
    module.write_text(explained)
    assert _ruff(root, module).returncode == 0
    tests = root / "tests"  # deferred imports are the tests' and scripts' to choose
    tests.mkdir()
    (tests / "test_late.py").write_text("def test_late():\n    import json\n\n    assert json\n")
    assert _ruff(root, tests / "test_late.py").returncode == 0


def test_the_study_subpackages_hold_every_study_module_once_in_the_documented_order():
    (layers,) = [c["layers"] for c in _contracts() if c.get("containers") == [f"{PACKAGE}.study"]]
    configured = [set(layer.split(" | ")) for layer in reversed(layers)]
    study = REPO / PACKAGE / "study"
    found = {p.stem for p in study.glob("*.py") if p.name != "__init__.py"}
    found |= {p.name for p in study.iterdir() if (p / "__init__.py").is_file()}
    assert sorted(m for layer in configured for m in layer) == sorted(found)
    # the study package's docstring lists them in the same order, bottom first
    doc = (study / "__init__.py").read_text()
    order = [doc.index(f"``{m}``") for layer in configured for m in sorted(layer)]
    assert [doc.index(f"``{sorted(layer)[0]}``") for layer in configured] == sorted(
        doc.index(f"``{sorted(layer)[0]}``") for layer in configured
    )
    assert len(order) == len(found)


def test_a_plan_module_importing_the_results_breaks_the_study_contract(tmp_path):
    root = _copy(tmp_path)
    low = root / PACKAGE / "study" / "plan" / "grid.py"
    low.write_text(low.read_text() + "\nfrom ..results import aggregate  # the plan reaching up to the results\n")
    out = _lint_imports(root)
    assert out.returncode != 0
    text = _text(out)
    assert f"{PACKAGE}.study.plan is not allowed to import {PACKAGE}.study.results" in text
    assert f"{PACKAGE}.study.plan.grid -> {PACKAGE}.study.results.aggregate" in text
