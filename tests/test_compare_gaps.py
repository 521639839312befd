"""One factor's gap across two studies (``study/results/compare.py``, ``factorworld compare-gaps``): the point estimates are
the studies' own seed means, the difference's interval behaves (0 for a study against itself, away from 0 for a
large effect), bad input is refused naming the valid choices, and the command prints what docs/findings.md quotes."""

import subprocess
import sys
from pathlib import Path

import pytest

from lerobot_factorworld.study.results.compare import Side, compare_gaps
from lerobot_factorworld.study.results.rows import read_results

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"
PICK_PLACE = Side("bc", "pick-place")


def _row(seed: int, condition: str, successes: int, episodes: int = 40, method: str = "bc") -> dict:
    return {"method": method, "task": "pick-place", "n_train_envs": 5, "widths": "default", "seed": seed,
            "condition": condition, "success_rate": successes / episodes, "episodes": episodes}  # fmt: skip


def _study(train: int, shifted: int, seeds=(0, 1, 2)) -> list[dict]:
    gap = (train - shifted) / 40
    return [r for s in seeds for r in (_row(s, "train", train), {**_row(s, "light", shifted), "gap": gap})]


def test_the_gaps_are_each_studys_seed_mean_and_the_difference_theirs():
    first = read_results(RESULTS / "f7_object_texture_168px" / "results.csv")
    second = read_results(RESULTS / "f1_ordering" / "results.csv")
    result = compare_gaps(first, second, "object_texture", (PICK_PLACE, PICK_PLACE))
    assert result.seeds == (0, 1, 2) and result.episodes == ((40,), (20,))
    for rows, (gap, low, high) in ((first, result.gaps[0]), (second, result.gaps[1])):
        cells = [
            r
            for r in rows
            if r["method"] == PICK_PLACE.method
            and r["task"] == "pick-place"
            and r["condition"] == "object_texture"
            and r["seed"] in result.seeds
        ]
        assert gap == pytest.approx(sum(r["gap"] for r in cells) / len(cells)) and low < gap < high
    difference, low, high = result.difference
    assert difference == pytest.approx(result.gaps[0][0] - result.gaps[1][0]) and low < difference < high
    assert compare_gaps(first, second, "object_texture", (PICK_PLACE, PICK_PLACE)) == result  # deterministic


def test_a_study_against_itself_differs_by_nothing_and_a_large_effect_is_resolved():
    same = compare_gaps(_study(36, 20), _study(36, 20), "light", (PICK_PLACE, PICK_PLACE))
    assert same.difference[0] == 0.0 and same.difference[1] < 0 < same.difference[2]
    large = compare_gaps(_study(36, 4), _study(36, 34), "light", (PICK_PLACE, PICK_PLACE))
    assert large.difference[0] == pytest.approx(0.75) and large.difference[1] > 0.4
    reverse = compare_gaps(_study(36, 34), _study(36, 4), "light", (PICK_PLACE, PICK_PLACE))
    assert reverse.difference[0] == pytest.approx(-0.75) and reverse.difference[2] < -0.4  # first minus second
    only_shared = compare_gaps(_study(36, 4), _study(36, 34, seeds=(1, 2, 3)), "light", (PICK_PLACE, PICK_PLACE))
    assert only_shared.seeds == (1, 2)
    at_n20 = [{**r, "n_train_envs": 20} for r in _study(36, 34)]  # each side is its study's only N: they still pair
    # they pair by seed as before; each cell's episode draws come from its identity, N included, so the interval
    # moves by bootstrap noise only
    at_20 = compare_gaps(_study(36, 4), at_n20, "light", (PICK_PLACE, PICK_PLACE))
    assert at_20.seeds == large.seeds and at_20.difference[0] == large.difference[0]
    assert at_20.difference[1:] == pytest.approx(large.difference[1:], abs=0.02)


def test_bad_input_is_refused_naming_the_choices():
    study = _study(36, 20)
    with pytest.raises(ValueError, match="no cell of method 'bc_x'.*its methods: bc; its factors: light"):
        compare_gaps(study, study, "light", (Side("bc_x", "pick-place"), PICK_PLACE))
    with pytest.raises(ValueError, match="share no training seed"):
        compare_gaps(study, _study(36, 20, seeds=(5,)), "light", (PICK_PLACE, PICK_PLACE))
    two_n = [*study, {**_row(0, "train", 30), "n_train_envs": 20}]
    with pytest.raises(ValueError, match=r"cells at N = \[5, 20\]; choose one"):
        compare_gaps(two_n, study, "light", (PICK_PLACE, PICK_PLACE))


# The commands docs/findings.md quotes (first folder, second folder, extra flags), with what each prints last.
QUOTED = [
    ("f7_object_texture_168px", "f1_ordering", ["--factor=object_texture"], "+0.092 [-0.067, +0.250]"),
    ("f7_object_texture_colours", "f7_object_texture_images", ["--factor=object_texture"], "+0.075 [-0.217, +0.333]"),
    ("f8_out_of_domain_language", "f8_out_of_domain", ["--factor=floor_texture", "--method=bc_lang",
     "--second_method=bc"], "+0.175 [-0.100, +0.450]"),
]  # fmt: skip


@pytest.mark.slow
def test_the_command_prints_the_differences_findings_quotes_and_refuses_in_one_line():
    command = [str(Path(sys.executable).with_name("factorworld")), "compare-gaps"]
    findings = " ".join((ROOT / "docs" / "findings.md").read_text().split())  # line breaks as spaces
    for a, b, flags, printed in QUOTED:
        folders = [f"--first={RESULTS / a}", f"--second={RESULTS / b}"]
        proc = subprocess.run(
            [*command, *folders, "--task=pick-place", *flags], capture_output=True, text=True, timeout=120
        )
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip().splitlines()[-1] == f"difference (first minus second): {printed}"
        assert printed in findings and f"--first=docs/results/{a} --second=docs/results/{b}" in findings, a
    folders = [f"--first={RESULTS / 'f7_object_texture_168px'}", f"--second={RESULTS / 'f1_ordering'}"]
    bad = subprocess.run([*command, *folders, "--factor=gravity", "--task=pick-place"], capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    assert (
        bad.returncode == 2
        and bad.stderr.count("\n") == 1
        and "its factors: object_texture, table_texture" in bad.stderr
    )
