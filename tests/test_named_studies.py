"""Studies by name: the quick study and every finding's config ship inside the package, resolve by name from
any folder (a path still works), ``factorworld configs`` lists them with their cost, and a wheel installed
into a fresh virtual environment runs them outside the repository, where LeRobot finds the env plugin."""

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.plan.named import STUDIES_DIR, resolve_study_config, study_names

ROOT = Path(__file__).resolve().parents[1]


def test_every_config_of_the_checkout_ships_in_the_package():
    shipped = {p.relative_to(STUDIES_DIR) for p in STUDIES_DIR.rglob("*.yaml")}
    in_checkout = {p.relative_to(ROOT / "configs" / "study") for p in (ROOT / "configs" / "study").rglob("*.yaml")}
    assert shipped == in_checkout and len(shipped) >= 15
    assert {"quick", "findings/f1_ordering", "findings/f9_pick"} <= set(study_names())


def test_a_name_a_file_name_and_a_path_resolve(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # outside the checkout
    assert resolve_study_config("quick") == str(STUDIES_DIR / "quick.yaml")
    assert resolve_study_config("findings/f3_pairs.yaml") == str(STUDIES_DIR / "findings" / "f3_pairs.yaml")
    assert resolve_study_config("configs/study/quick.yaml") == str(STUDIES_DIR / "quick.yaml")
    own = tmp_path / "quick.yaml"  # a file of that name here wins over the packaged one
    own.write_text("name: mine\n")
    assert resolve_study_config("quick.yaml") == "quick.yaml"


def test_an_unknown_name_is_one_line_naming_the_valid_ones(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(["study", "--config", "quik", "--dry-run"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no packaged study of that name" in err[0] and "findings/f1_ordering, " in err[0]


def test_study_by_name_from_another_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    main(["study", "--config", "quick", "--dry-run"])
    assert "study 'quick' in outputs/study/quick" in capsys.readouterr().out


@pytest.mark.slow
def test_factorworld_configs_lists_every_name_with_its_cost(capsys):
    main(["configs"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines[1:]] == study_names()
    quick = next(line for line in lines if line.startswith("quick "))
    assert quick.split()[1] == "12" and quick.split()[2].endswith("h")


@pytest.mark.slow
def test_a_wheel_in_a_fresh_environment_runs_a_study_by_name_and_lerobot_finds_the_env(tmp_path):
    """Installed as LeRobot users install a plugin: the built wheel in a fresh venv (from uv's local cache, no
    network), used from a folder outside the repository."""
    uv = [sys.executable, "-m", "uv"]
    if subprocess.run([*uv, "--version"], capture_output=True).returncode != 0:
        uv = [shutil.which("uv") or "uv"]
    env = {**os.environ, "UV_PYTHON_DOWNLOADS": "never", "MUJOCO_GL": "egl"}
    env.pop("VIRTUAL_ENV", None)
    # a fresh venv has no bytecode: where the machine forbids writing it, each of its commands below would
    # compile torch and LeRobot from source again (about 20 s each)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    wheels, source = tmp_path / "wheels", tmp_path / "source"
    # built from a copy of the checkout's files (tracked or not ignored): setuptools' build/ folder in the checkout
    # keeps files deleted since, which would end up in the wheel
    listed = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    for name in filter(None, listed.split("\0")):
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    subprocess.run(
        [*uv, "build", "--wheel", "--out-dir", str(wheels), str(source)], check=True, capture_output=True, env=env
    )
    venv = tmp_path / "venv"
    subprocess.run([*uv, "venv", "--quiet", str(venv), "-p", sys.executable], check=True, env=env)
    (wheel,) = wheels.glob("*.whl")
    with zipfile.ZipFile(wheel) as archive:  # every packaged config, subfolders too
        packaged = {Path(n).relative_to("lerobot_factorworld/studies") for n in archive.namelist()
                    if n.startswith("lerobot_factorworld/studies/") and n.endswith(".yaml")}  # fmt: skip
    assert packaged == {p.relative_to(STUDIES_DIR) for p in STUDIES_DIR.rglob("*.yaml")}
    subprocess.run(
        [*uv, "pip", "install", "--quiet", "--offline", "-p", str(venv / "bin" / "python"), str(wheel)],
        check=True,
        env=env,
    )
    away = tmp_path / "elsewhere"
    away.mkdir()
    study = subprocess.run(
        [str(venv / "bin" / "factorworld"), "study", "--config", "quick", "--dry-run"],
        cwd=away, capture_output=True, text=True, env=env,
    )  # fmt: skip
    assert study.returncode == 0, study.stderr
    assert "study 'quick' in outputs/study/quick" in study.stdout
    lerobot = subprocess.run(
        [str(venv / "bin" / "lerobot-eval"), "--env.type=factorworld", "--help"],
        cwd=away, capture_output=True, text=True, env=env,
    )  # fmt: skip
    assert lerobot.returncode == 0, lerobot.stderr
    assert "factorworld}" in lerobot.stdout and "--env.quality" in lerobot.stdout
