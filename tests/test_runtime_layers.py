"""The layers hold at run time, not only in the import contract: a gymnasium user who builds a scene loads no
study, policy, torch or LeRobot module (families are loaded by entry point, which the contract cannot see), and
writing a study's report (``factorworld report``, ``sync-docs``) loads no policy, torch or LeRobot module (its
config is read without LeRobot's policy checks, which the contract cannot see either: they import it lazily)."""

import json
import os
import subprocess
import sys
from pathlib import Path

from lerobot_factorworld.families import family_of
from lerobot_factorworld.family_reports.pick import PICK_REPORT
from lerobot_factorworld.study.report.family_report import NO_REPORT, report_of

SCENE_ONLY = """
import json, sys
import lerobot_factorworld as fw
from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs, shift_configs

SamplingOptions()
for task in ("pick-place", "pick"):
    train = sample_configs(task, n=2, seed=0)
    tests = shift_configs(train, "camera_pos", n=2, seed=1)
    env = FactorWorldEnv(task, tests, cameras=("front",), image_size=16)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
heavy = ("torch", "lerobot", "lerobot_factorworld.study", "lerobot_factorworld.policies", "lerobot_factorworld.family_reports")
print(json.dumps(sorted(m for m in sys.modules if any(m == h or m.startswith(h + ".") for h in heavy))))
"""


def test_a_scene_loads_no_study_policy_torch_or_lerobot_module():
    out = subprocess.run(
        [sys.executable, "-c", SCENE_ONLY],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MUJOCO_GL": "egl"},
    )
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


# a small committed study with a task family's report part (pick's, by entry point): report.md, report.html, plots
REPORTED = Path(__file__).resolve().parents[1] / "docs" / "results" / "pick"

REPORT_ONLY = """
import json, shutil, sys
from pathlib import Path
from lerobot_factorworld.cli import main

study, out = Path(sys.argv[1]), Path(sys.argv[2])
main(["report", f"--results={study / 'results.csv'}", f"--config={study / 'config.yaml'}", f"--out={out / 'report'}"])
shutil.copytree(study, out / "root" / "docs" / "results" / study.name)  # a checkout holding this one study
main(["sync-docs", "--check", f"--root={out / 'root'}"])
heavy = ("torch", "lerobot", "transformers", "sentence_transformers", "accelerate", "lerobot_factorworld.policies")
print(json.dumps(sorted(m for m in sys.modules if any(m == h or m.startswith(h + ".") for h in heavy))))
"""


def test_a_report_and_sync_docs_load_no_policy_torch_or_lerobot_module(tmp_path):
    """``factorworld report`` and ``sync-docs --check`` (over a checkout of one committed study, as the whole
    sync takes a minute) in one fresh process: nothing of the training stack (3 s and 600 MB at import)."""
    out = subprocess.run(
        [sys.executable, "-c", REPORT_ONLY, str(REPORTED), str(tmp_path)],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MUJOCO_GL": "egl"},
    )
    lines = out.stdout.strip().splitlines()
    assert lines[0].startswith(f"wrote {tmp_path / 'report' / 'report.md'} and ")
    assert lines[1] == "every committed report and fenced table is current"
    assert json.loads(lines[-1]) == []


def test_a_study_report_still_finds_the_pick_report_part():
    """The pick family's report part is reached by its entry point, from the study."""
    assert report_of(family_of("pick")) is PICK_REPORT
    assert report_of(family_of("pick-place")) is NO_REPORT
    assert PICK_REPORT.report_files == ("pick_breakdowns.csv",)
