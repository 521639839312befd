"""Every ``factorworld`` command refuses a bad setting with one ``error: ...`` line that names the valid
choices, a non-zero exit status and no traceback, before any work starts (draccus-level errors too:
unknown keys, wrong types, unreadable YAML)."""

import subprocess
import sys
from pathlib import Path

import pytest

from lerobot_factorworld.cli import main

FACTORWORLD = Path(sys.executable).with_name("factorworld")
REPO = Path(__file__).resolve().parents[1]
VALID_TASKS = "valid tasks: pick-place, basketball"
VALID_CAMERAS = "valid cameras: front, side, top, far"


def refusal(argv: list[str], capsys) -> tuple[int, str]:
    """Run the CLI in-process; return its exit status and its whole stderr."""
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    captured = capsys.readouterr()
    assert captured.out == "", captured.out
    return exit_info.value.code, captured.err


def assert_one_line(err: str, expected: str) -> None:
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    assert expected in lines[0], lines[0]


@pytest.fixture
def yaml_files(tmp_path):
    files = {
        "broken": "task: [pick-place\n",
        "list": "- task\n- n_envs\n",
        "unknown": "task: pick-place\nbogus: 1\nsampling:\n  n_distractor: 2\n",
        "wrong_type": "n_envs: five\n",
        "bad_value": "cameras: front,wrist\n",
        "empty": "",
    }
    for name, text in files.items():
        (tmp_path / f"{name}.yaml").write_text(text)
    (tmp_path / "plain_file").write_text("not a folder")
    (tmp_path / "no_images").mkdir()
    (tmp_path / "no_images" / "readme.txt").write_text("no textures here")
    return tmp_path


COLLECT_CASES = [
    (["--task=pick-plac"], "unknown task 'pick-plac'; " + VALID_TASKS),
    (["--task=pick-place,door-opn"], "unknown task 'door-opn'"),
    (["--task=pick-place,pick-place"], "pick-place given more than once"),
    (["--task="], "no task given; " + VALID_TASKS),
    (["--cameras=front,wrist"], VALID_CAMERAS),
    (["--cameras=front,front"], "each at most once"),
    (["--demos=0"], "demos must be at least 1, got 0"),
    (["--demos=3", "--n_envs=5"], "demos (3) must be at least n_envs (5)"),
    (["--demos_per_env=0"], "demos_per_env must be at least 1"),
    (["--n_envs=-1"], "n_envs must be at least 1, got -1"),
    (["--image_size=4"], "image_size must be at least 8 pixels (and at most"),
    (["--image_size=100000"], "image_size must be at least 8 pixels (and at most"),
    (["--quality=ultra"], "unknown quality 'ultra'; valid: fast, full"),
    (["--split=test"], "unknown split 'test'; valid splits: train, eval"),
    (["--seed=-1"], "seed must be at least 0"),
    (["--action_noise=-0.1"], "action_noise must be a finite number >= 0"),
    (["--max_episode_steps=0"], "max_episode_steps must be at least 1"),
    (["--max_attempts=0"], "max_attempts must be at least 1"),
    (["--workers=-2"], "workers must be at least 0"),
    (["--episodes_per_shard=0"], "episodes_per_shard must be at least 1"),
    (["--start_method=thread"], "unknown start_method 'thread'; valid: auto, fork"),
    (["--mode=replace"], "unknown mode 'replace'; valid: new, overwrite, append"),
    (["--repo_id=nope"], "repo_id must look like 'user/name'"),
    (["--repo_id=me/bad name"], "bad repo_id 'me/bad name'"),
    (["--factors=[lighting]"], "unknown factor(s) 'lighting'; valid factors: object_pos"),
    (["--factors=[light,light]"], "light given more than once"),
    (["--task=door-open", "--factors=[object_shape]"], "factor 'object_shape' does not apply to task 'door-open'"),
    (["--sampling.widths={{camera_pos: huge}}"], "valid widths: narrow, medium, wide"),
    (["--sampling.n_distractors=9"], "n_distractors must be in [0, 5]"),
    (["--sampling.rgb_fraction=2"], "rgb_fraction must be in [0, 1]"),
    (["--sampling.texture_folder={tmp}/missing"], "does not exist"),
    (["--sampling.shape_folder={tmp}/no_images"], "no shape files found"),
    (["--root={tmp}/plain_file"], "root {tmp}/plain_file is a file, not a folder"),
    (["--root={tmp}/plain_file/dataset"], "its parent {tmp}/plain_file is a file"),
    # draccus-level: unknown keys, wrong types, stray arguments, config files
    (["--n_env=3"], "unknown setting(s) --n_env (did you mean --n_envs?); valid settings: --action_noise"),
    (["--sampling.n_distractor=2"], "did you mean --sampling.n_distractors?"),
    (["--n_envs=abc"], "bad value for --n_envs: Couldn't parse 'abc' into an int"),
    (["--n_envs=1.5"], "bad value for --n_envs"),
    (["--use_videos=maybe"], "bad value for --use_videos: Couldn't parse 'maybe' into a bool"),
    (["--factors=light"], "bad value for --factors: expected a list such as [a,b]"),
    (["--sampling.widths=wide"], "bad value for --sampling.widths: expected a mapping such as {{a: b}}"),
    (["--sampling=other.yaml"], "bad value for --sampling: expected its settings as --sampling.<setting>=value"),
    (["pick-place"], "unrecognized arguments: pick-place; settings are given as --key=value"),
    (["--task"], "argument --task: expected one argument"),
    (["--config_path={tmp}/missing.yaml"], "--config_path {tmp}/missing.yaml does not exist"),
    (["--config_path={tmp}/broken.yaml"], "is not valid YAML"),
    (["--config_path={tmp}/list.yaml"], "must hold a mapping of settings"),
    (["--config_path={tmp}/empty.yaml"], "is empty"),
    (["--config_path={tmp}/unknown.yaml"], "unknown setting(s) --bogus, --sampling.n_distractor (did you mean"),
    (["--config_path={tmp}/wrong_type.yaml"], "bad value for --n_envs: Couldn't parse 'five' into an int"),
    (["--config_path={tmp}/bad_value.yaml"], VALID_CAMERAS),
]


@pytest.mark.parametrize(("args", "expected"), COLLECT_CASES, ids=[" ".join(a) for a, _ in COLLECT_CASES])
def test_collect_refuses_each_bad_setting_in_one_line(args, expected, yaml_files, capsys):
    root = yaml_files / "never_created"
    argv = ["collect", f"--root={root}", "--repo_id=local/x", *[a.format(tmp=yaml_files) for a in args]]
    if any(a.startswith("--root=") for a in args):
        argv = [a for a in argv if a != f"--root={root}"]
    status, err = refusal(argv, capsys)
    assert status == 2
    assert_one_line(err, expected.format(tmp=yaml_files))
    assert not root.exists() and not Path(f"{root}.parts").exists()


OTHER_CASES = [
    (["sample", "--task=nope"], "unknown task 'nope'; " + VALID_TASKS),
    (["sample", "--n=0"], "n must be at least 1"),
    (["sample", "--split=holdout"], "unknown split 'holdout'; valid splits: train, eval"),
    (["sample", "--seed=-3"], "seed must be at least 0"),
    (["sample", "--factors=[shape]"], "unknown factor(s) 'shape'; valid factors:"),
    (["sample", "--task=basketball", "--factors=[object_shape]"], "factor 'object_shape' does not apply"),
    (["sample", "--out={tmp}"], "out {tmp} is a folder; give a file path"),
    (["sample", "--n=many"], "bad value for --n"),
    (["sample", "--nn=2"], "unknown setting(s) --nn (did you mean --n?)"),
    (["contact-sheet", "--camera=wrist"], VALID_CAMERAS),
    (["contact-sheet", "--task=door"], "unknown task 'door'"),
    (["contact-sheet", "--n_values=0"], "n_values must be at least 1"),
    (["contact-sheet", "--image_size=0"], "image_size must be at least 8 pixels (and at most"),
    (["contact-sheet", "--quality=best"], "unknown quality 'best'; valid: fast, full"),
    (["contact-sheet", "--split=test"], "unknown split 'test'"),
    (["contact-sheet", "--out={tmp}/sheet.txt"], "unsupported extension; valid: .png, .jpg"),
    (["contact-sheet", "--out={tmp}/plain_file/sheet.png"], "its parent {tmp}/plain_file is a file"),
    (["contact-sheet", "--config_path={tmp}/unknown.yaml"], "unknown setting(s) --bogus"),
    (["tasks", "--task=pick-place"], "factorworld tasks takes no settings"),
    (["factors", "extra"], "factorworld factors takes no settings"),
    (["cameras", "--all"], "factorworld cameras takes no settings"),
    (["rt1-presets", "--preset=small"], "factorworld rt1-presets takes no settings"),
    (["colect"], "unknown command 'colect'; valid commands: tasks, factors, cameras, sample, contact-sheet, collect"),
]


@pytest.mark.parametrize(("argv", "expected"), OTHER_CASES, ids=[" ".join(a) for a, _ in OTHER_CASES])
def test_every_other_command_refuses_bad_settings_in_one_line(argv, expected, yaml_files, capsys):
    status, err = refusal([a.format(tmp=yaml_files) for a in argv], capsys)
    assert status == 2
    assert_one_line(err, expected.format(tmp=yaml_files))
    assert sorted(p.name for p in yaml_files.iterdir()) == sorted(  # nothing was written
        ["broken.yaml", "list.yaml", "unknown.yaml", "wrong_type.yaml", "bad_value.yaml", "empty.yaml"]
        + ["plain_file", "no_images"]
    )


def test_the_shipped_configs_parse(tmp_path):
    from lerobot_factorworld.cli import SampleConfig
    from lerobot_factorworld.contact_sheet import ContactSheetConfig
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.datasets.collect import CollectConfig

    for cls, name in (
        (CollectConfig, "collect_pick_place"),
        (ContactSheetConfig, "contact_sheet"),
        (SampleConfig, "sample_train_envs"),
    ):
        cfg = parse_config(cls, [f"--config_path={REPO / 'configs' / f'{name}.yaml'}", "--seed=7"])
        assert isinstance(cfg, cls) and cfg.seed == 7


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["collect", "--bogus=1"], "unknown setting(s) --bogus"),
        # each a new process importing the command (seconds): a refusal while parsing (above) and one raised by a
        # setting's own check (below); the other refusals run in process (the tables above)
        pytest.param(
            ["collect", "--sampling.texture_folder=/nonexistent/textures"], "does not exist", marks=pytest.mark.slow
        ),
    ],
)
def test_the_installed_command_prints_one_line_and_no_traceback(args, expected):
    out = subprocess.run([str(FACTORWORLD), *args], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert out.returncode == 2 and out.stdout == ""
    assert_one_line(out.stderr, expected)


def test_the_program_ends_without_collecting_what_it_imported():
    """``factorworld`` (the console script and ``python -m``) is ``run``: ``main`` and then ``gc.freeze()``,
    so the interpreter's last collection skips every object torch and LeRobot made (seconds at exit)."""
    assert "import run" in FACTORWORLD.read_text()  # the installed console script
    code = "import gc, sys; from lerobot_factorworld import cli; sys.argv = ['factorworld', 'tasks']; cli.run(); "
    code += "print('frozen', gc.get_freeze_count())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert int(out.split("frozen ")[-1]) > 1000, out
