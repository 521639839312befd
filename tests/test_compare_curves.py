"""Two studies' learning curves side by side (``study/results/compare_curves.py``, ``factorworld compare-curves``):
points matched by epochs or by gradient step, each difference paired episode by episode where both points kept
their outcomes and the studies share their episode seeds, bad input refused in one line naming the choices."""

import re
import shutil
from pathlib import Path

import pytest

from lerobot_factorworld.stats.proportions import newcombe_independent, paired_gap, two_sided_z
from lerobot_factorworld.study.results.compare_curves import CurveSide, curve_comparison_lines
from lerobot_factorworld.study.results.curve import CURVE_FILE, read_curve, write_curve

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "docs" / "results" / "rt1_curve_pick_160" / "config.yaml"  # any published config: its start_seed


def _point(epochs: float, steps: int, outcomes: str, method: str = "rt1_small", seed: int = 0) -> dict:
    k, n = outcomes.count("1"), len(outcomes)
    return {"study": "s", "method": method, "policy": "rt1", "task": "pick", "n_train_envs": 10, "seed": seed,
            "widths": "default", "epochs": epochs, "steps": steps, "episodes": n, "successes": k,
            "success_rate": k / n, "ci_low": 0.0, "ci_high": 1.0, "step": f"{epochs:016.0f}", "stages": "",
            "trained_on": "", "outcomes": outcomes}  # fmt: skip


CURVE = [_point(16, 17010, "11" + "0" * 28), _point(32, 34020, "111000" + "0" * 24)]  # 2, then 3 of 30
CONTROL = [_point(8, 17010, "1" * 5 + "0" * 25), _point(16, 34020, "1" * 9 + "0" * 21)]  # 5, then 9 of 30


def _bools(outcomes: str) -> list[bool]:
    return [o == "1" for o in outcomes]


def _cell(difference: tuple[float, float, float]) -> str:
    return f"{difference[0]:+.2f} [{difference[1]:+.2f}, {difference[2]:+.2f}]"


def test_points_at_one_budget_are_compared_episode_by_episode():
    first, second = CurveSide("control", CONTROL), CurveSide("curve", CURVE)
    by_steps = "\n".join(curve_comparison_lines(first, second, match="steps"))
    for mine, theirs in zip(CONTROL, CURVE):  # 8 epochs of twice the frames against 16: one gradient step
        paired = paired_gap(_bools(mine["outcomes"]), _bools(theirs["outcomes"]))
        assert f"| {mine['epochs']:g} ({mine['steps']}) | {theirs['epochs']:g} ({theirs['steps']}) |" in by_steps
        assert f"| {_cell(paired)} |" in by_steps
    assert "matched by steps" in by_steps and "for paired samples: episode i of one point" in by_steps
    # by epochs only 16 is shared: the control's second point against the curve's first
    by_epochs = "\n".join(curve_comparison_lines(first, second))
    only = paired_gap(_bools(CONTROL[1]["outcomes"]), _bools(CURVE[0]["outcomes"]))
    assert by_epochs.count("\n| 16 (34020) | 16 (17010) |") == 1 and "\n| 8 (" not in by_epochs
    assert f"| {_cell(only)} |" in by_epochs
    # other episode seeds (or a curve without outcomes): two independent samples, said so
    apart = "\n".join(curve_comparison_lines(first, second, match="steps", paired=False))
    assert f"| {_cell(newcombe_independent(9, 30, 3, 30))} |" in apart and "do not pair" in apart
    old = CurveSide("curve", [{**p, "outcomes": ""} for p in CURVE])
    assert "for two independent samples;" in "\n".join(curve_comparison_lines(first, old, match="steps"))


def test_a_family_declared_as_one_finding_is_compared_alone_at_its_bonferroni_level():
    first, second = CurveSide("control", CONTROL), CurveSide("curve", CURVE)
    lines = curve_comparison_lines(first, second, match="steps", family=[8, 16])
    both = "\n".join(lines)
    z = two_sided_z(1 - 0.05 / 2)  # 97.5%: two points share the family's 5%
    assert (z, two_sided_z(1 - 0.05 / 3)) == pytest.approx((2.24140, 2.39398), abs=1e-5)  # normal tables
    for outside in (0.0, 1.0):
        with pytest.raises(ValueError, match="confidence must be in"):
            two_sided_z(outside)
    cells = [paired_gap(_bools(a["outcomes"]), _bools(b["outcomes"]), z) for a, b in zip(CONTROL, CURVE)]
    for cell in cells:
        assert f"| {_cell(cell)} |" in both
    assert cells[0][1] < paired_gap(_bools(CONTROL[0]["outcomes"]), _bools(CURVE[0]["outcomes"]))[1]  # wider
    assert "| first - second [97.5%, Bonferroni over 2] |" in lines[2]
    resolved = ["above" if low > 0 else "below" if high < 0 else "not" for _, low, high in cells]
    assert resolved == ["not", "above"]  # 5 of 30 vs 1 of 30 is not resolved at 97.5%; 9 vs 3 with 6 discordant is
    assert (
        "As one finding (2 points, each interval at 97.5%): first above second at 16 epochs; not resolved at 8 epochs."
        in both
    )
    assert "Bonferroni-corrected over the 2 points named as one finding" in lines[-1]
    one = "\n".join(curve_comparison_lines(first, second, match="steps", family=[16]))
    assert "\n| 8 (" not in one and "[95%, Bonferroni over 1]" in one  # one point: its own 95%
    with pytest.raises(
        ValueError, match="the family names epochs 12, not a point of control matched in curve by steps; valid: 8, 16"
    ):
        curve_comparison_lines(first, second, match="steps", family=[8, 12])
    with pytest.raises(ValueError, match="the family names no epochs; name some of control's matched by steps: 8, 16"):
        curve_comparison_lines(first, second, match="steps", family=[])


def test_a_method_task_or_budget_the_curves_lack_is_refused_naming_the_choices():
    two = CurveSide("two", CURVE + [_point(16, 17010, "0" * 30, method="bc")])
    with pytest.raises(ValueError, match="two's curve has methods bc, rt1_small: name one with --method"):
        curve_comparison_lines(two, CurveSide("curve", CURVE))
    with pytest.raises(ValueError, match="curve's curve has no method 'act'; valid: rt1_small"):
        curve_comparison_lines(CurveSide("curve", CURVE, method="act"), CurveSide("curve", CURVE))
    with pytest.raises(ValueError, match="share no checkpoint by steps"):
        curve_comparison_lines(CurveSide("a", CURVE[:1]), CurveSide("b", CONTROL[1:]), match="steps")
    with pytest.raises(ValueError, match="unknown match 'order'; valid: epochs, steps"):
        curve_comparison_lines(CurveSide("a", CURVE), CurveSide("b", CURVE), match="order")


def test_the_command_reads_two_folders_and_pairs_only_studies_of_one_episode_seed(tmp_path, run_main):
    from lerobot_factorworld.cli import main

    folders = {}
    for name, rows, start in (("control", CONTROL, 1000), ("curve", CURVE, 1000), ("shifted", CURVE, 2000)):
        folder = folders[name] = tmp_path / name
        folder.mkdir()
        write_curve(rows, folder / CURVE_FILE)
        config = CONFIG.read_text()
        (folder / "config.yaml").write_text(config.replace("eval:\n", f"eval:\n  start_seed: {start}\n", 1))
    leading_zeros = write_curve([_point(16, 17010, "0" * 29 + "1")], tmp_path / CURVE_FILE)
    assert read_curve(leading_zeros)[0]["outcomes"] == "0" * 29 + "1"  # text, never a number
    argv = ["factorworld", "compare-curves", f"--first={folders['control']}", "--match=steps"]
    same = run_main([*argv, f"--second={folders['curve']}"], main)
    assert same.returncode == 0, same.stderr
    assert f"| {_cell(paired_gap(_bools(CONTROL[0]['outcomes']), _bools(CURVE[0]['outcomes'])))} |" in same.stdout
    finding = run_main([*argv, f"--second={folders['curve']}", "--family=[16]"], main)
    assert finding.returncode == 0 and "As one finding (1 point," in finding.stdout and "| 8 (" not in finding.stdout
    other = run_main([*argv, f"--second={folders['shifted']}"], main)
    assert f"| {_cell(newcombe_independent(5, 30, 2, 30))} |" in other.stdout and "do not pair" in other.stdout
    refused = run_main([*argv, f"--second={folders['curve']}", "--method=act"], main)
    assert refused.returncode == 2 and refused.stderr.strip().splitlines() == [
        f"error: {folders['control']}'s curve has no method 'act'; valid: rt1_small"
    ]
    shutil.rmtree(folders["curve"])
    missing = run_main([*argv, f"--second={folders['curve']}"], main)
    assert missing.returncode == 2 and len(missing.stderr.strip().splitlines()) == 1 and "second" in missing.stderr


def test_the_comparisons_docs_rt1_quotes_are_what_the_command_prints_from_the_committed_curves(run_main):
    """docs/rt1.md quotes ``compare-curves`` on committed curves: each quoted block's table rows are the command's own."""
    from lerobot_factorworld.cli import main

    doc = (ROOT / "docs" / "rt1.md").read_text()
    quotes = re.findall(r"```bash\n(factorworld compare-curves [^\n]+)\n```\n```\n(.*?)\n```\n", doc, re.S)
    assert len(quotes) >= 6, "docs/rt1.md quotes the language's and the demos' comparisons, on 30 and on 120 episodes"
    assert any("--family=" in command for command, _ in quotes), "and the declared finding's"
    for command, quoted in quotes:
        argv = [arg.replace("docs/results", str(ROOT / "docs" / "results")) for arg in command.split()]
        printed = run_main(argv, main)
        assert printed.returncode == 0, printed.stderr
        rows = [line for line in printed.stdout.splitlines() if line.startswith("| ") and "epochs (step)" not in line]
        assert (
            rows
            and [line for line in quoted.splitlines() if line.startswith("| ") and "epochs (step)" not in line] == rows
        ), command
        findings = [line for line in quoted.splitlines() if line.startswith("As one finding")]
        assert findings == [line for line in printed.stdout.splitlines() if line.startswith("As one finding")], command
        assert "for paired samples" in printed.stdout  # both studies play the same episode seeds
