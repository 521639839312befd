"""The docs show what the code says (one source of truth)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_factor_docs_match_the_cli():
    cli = subprocess.run(
        [sys.executable, "-m", "lerobot_factorworld.cli", "factors"], capture_output=True, text=True, check=True
    )
    docs = (ROOT / "docs" / "factors.md").read_text()
    assert cli.stdout.strip() in docs, "docs/factors.md is stale: regenerate it with `factorworld factors`"


def test_readme_opens_with_the_two_commands_and_ci_runs_the_test_one():
    readme = (ROOT / "README.md").read_text()
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line and not line.startswith("#")]
    assert ci[-1] == "make test"
    head = readme[:1500]
    assert "make demo" in head and "make test" in head


def test_config_files_parse_with_their_commands():
    import draccus

    from lerobot_factorworld.cli import SampleConfig
    from lerobot_factorworld.contact_sheet import ContactSheetConfig
    from lerobot_factorworld.datasets.collect import CollectConfig

    for name, cls in (
        ("contact_sheet.yaml", ContactSheetConfig),
        ("sample_train_envs.yaml", SampleConfig),
        ("collect_pick_place.yaml", CollectConfig),
    ):
        cfg = draccus.parse(cls, config_path=str(ROOT / "configs" / name), args=[])
        assert cfg.task == "pick-place"
