"""``factorworld merge-results``: a study made in parts as one results.csv and episodes.parquet, on F1's committed
results split by seed into two parts (what a study run over two sessions looks like)."""

from __future__ import annotations

import csv
import shutil
from dataclasses import replace
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.report.write import load_config
from lerobot_factorworld.study.results.curve import read_curve
from lerobot_factorworld.study.results.merge import merge_curve_rows, merge_results, merge_rows
from lerobot_factorworld.study.results.rows import read_results

F1 = Path(__file__).resolve().parents[1] / "docs" / "results" / "f1_ordering"
F9 = Path(__file__).resolve().parents[1] / "docs" / "results" / "f9_pick"  # two methods, one with a learning curve
CURVE = Path(__file__).resolve().parents[1] / "docs" / "results" / "rt1_curve_pick"  # one training, five checkpoints


def _part(tmp_path: Path, name: str, seeds: set[int]) -> Path:
    """F1's committed rows and episodes of ``seeds`` in a folder of their own, with its config."""
    folder = tmp_path / name
    folder.mkdir()
    shutil.copy(F1 / "config.yaml", folder / "config.yaml")
    with open(F1 / "results.csv", newline="") as f:
        lines = f.read().splitlines(keepends=True)
    rows = [line for line in lines[1:] if int(next(csv.reader([line]))[5]) in seeds]
    (folder / "results.csv").write_text(lines[0] + "".join(rows))
    table = pq.read_table(F1 / "episodes.parquet")
    pq.write_table(
        table.filter(pc.is_in(table["seed"], value_set=pa.array(sorted(seeds)))),
        folder / "episodes.parquet",
    )
    return folder


@pytest.fixture(scope="module")
def plan():
    return make_plan(load_config(F1 / "config.yaml"))


def test_two_parts_merge_back_into_the_committed_bytes_in_either_order(tmp_path, plan):
    seeds = {int(r["seed"]) for r in read_results(F1 / "results.csv")}
    assert len(seeds) >= 2
    first, second = _part(tmp_path, "first", {min(seeds)}), _part(tmp_path, "second", seeds - {min(seeds)})
    merged = merge_results(first, [second], plan)
    (results, episodes), added = merged.written, merged.added
    assert results.read_bytes() == (F1 / "results.csv").read_bytes()
    assert added == len(read_results(second / "results.csv")) and merged.dropped == []
    merged, committed = pq.read_table(episodes), pq.read_table(F1 / "episodes.parquet")
    assert merged.select(committed.column_names).equals(committed)
    again = _part(tmp_path, "again", seeds - {min(seeds)})
    merge_results(again, [_part(tmp_path, "other", {min(seeds)})], plan)
    assert (again / "results.csv").read_bytes() == (F1 / "results.csv").read_bytes()


def test_a_step_in_both_parts_merges_once_and_must_hold_the_same_numbers(plan):
    rows = read_results(F1 / "results.csv")
    assert merge_rows([rows, rows[:3]], plan, ["a", "b"]) == rows  # the same evaluation twice: once
    changed = [dict(r) for r in rows[:1]]
    changed[0]["successes"] += 1
    with pytest.raises(ValueError, match=rf"step {rows[0]['step']} .* differs between a and b in successes: compare"):
        merge_rows([rows, changed], plan, ["a", "b"])
    provenance = [{**rows[0], "commit": "0" * 40, "source_hash": "1" * 12}]  # made elsewhere: still the same result
    assert merge_rows([rows, provenance], plan, ["a", "b"]) == rows


def test_two_grids_or_two_studies_under_one_name_are_refused(plan):
    rows = read_results(F1 / "results.csv")
    other_step = [{**rows[0], "step": "f" * 16}]
    with pytest.raises(ValueError, match="comes from two evaluation steps"):
        merge_rows([rows, other_step], plan, ["a", "b"])
    with pytest.raises(ValueError, match="the parts hold different studies"):
        merge_rows([rows, [{**rows[0], "study": "other"}]], plan, ["a", "b"])
    unplanned = [{**r, "step": "e" * 16} for r in rows[:1]]
    with pytest.raises(ValueError, match="is not in the study's plan"):
        merge_rows([unplanned], plan, ["a"])


def test_the_command_merges_and_refuses_in_one_line_writing_nothing(tmp_path, capsys):
    seeds = {int(r["seed"]) for r in read_results(F1 / "results.csv")}
    first, second = _part(tmp_path, "first", {min(seeds)}), _part(tmp_path, "second", seeds - {min(seeds)})
    before = (first / "results.csv").read_bytes()
    with pytest.raises(SystemExit) as exit_info:
        main(["merge-results", f"--into={first}", f"--add=[{tmp_path / 'missing'}]"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: add ") and "is not a study folder" in err[0]
    assert (first / "results.csv").read_bytes() == before
    main(["merge-results", f"--into={first}", f"--add=[{second}]"])
    out = capsys.readouterr().out
    assert f"wrote {first / 'results.csv'} and {first / 'episodes.parquet'}" in out and "factorworld report" in out
    assert (first / "results.csv").read_bytes() == (F1 / "results.csv").read_bytes()


def test_a_learning_curve_made_in_parts_merges_back_into_its_committed_bytes(tmp_path):
    """RT-1's committed pick curve split by checkpoint (the grid's last point, the ``train`` evaluation, in the
    first part with the early ones): merging the parts in either order writes the committed ``curve.csv``."""
    plan = make_plan(load_config(CURVE / "config.yaml"))
    lines = (CURVE / "curve.csv").read_text().splitlines(keepends=True)
    results = read_results(CURVE / "results.csv")
    assert len(lines) - 1 >= 3 and len(results) == 1
    parts = {}
    for name, keep in [("early", lambda i: i < 2 or i == len(lines) - 2), ("late", lambda i: 2 <= i < len(lines) - 2)]:
        folder = parts[name] = tmp_path / name
        folder.mkdir()
        shutil.copy(CURVE / "config.yaml", folder / "config.yaml")
        shutil.copy(CURVE / "results.csv", folder / "results.csv")
        (folder / "curve.csv").write_text(lines[0] + "".join(line for i, line in enumerate(lines[1:]) if keep(i)))
    merged = merge_results(parts["late"], [parts["early"]], plan)
    assert merged.added == 0 and parts["late"] / "curve.csv" in merged.written
    assert (parts["late"] / "curve.csv").read_bytes() == (CURVE / "curve.csv").read_bytes()
    rows = read_curve(CURVE / "curve.csv")
    assert merge_curve_rows([rows[2:], rows[:2]], plan, ["a", "b"]) == rows
    changed = [{**rows[0], "successes": rows[0]["successes"] + 1}]
    with pytest.raises(ValueError, match=rf"point {rows[0]['step']} differs between a and b in successes"):
        merge_curve_rows([rows, changed], plan, ["a", "b"])
    with pytest.raises(ValueError, match="is not in the study's plan"):
        merge_curve_rows([[{**rows[0], "step": "e" * 16}]], plan, ["a"])


def test_rows_a_changed_config_no_longer_plans_are_refused_or_dropped_on_request(tmp_path, capsys):
    """F9 whose config drops RT-1 (as a changed training budget would re-key it): its rows, episodes and curve
    points are refused by default; ``--drop_unplanned=true`` leaves them out, lists each, and keeps the rest."""
    cfg = load_config(F9 / "config.yaml")
    kept = [m for m in cfg.methods if m.name != "rt1_small"]
    assert len(kept) == len(cfg.methods) - 1 and cfg.curve_methods()
    plan = make_plan(replace(cfg, methods=kept, claims=[c for c in cfg.claims if c.method != "rt1_small"]))
    folder = tmp_path / "f9"
    shutil.copytree(F9, folder)
    before = {name: (folder / name).read_bytes() for name in ("results.csv", "episodes.parquet", "curve.csv")}
    with pytest.raises(ValueError, match="is not in the study's plan: .* --drop_unplanned=true"):
        merge_results(folder, [], plan)
    assert {name: (folder / name).read_bytes() for name in before} == before  # refused: nothing written
    merged = merge_results(folder, [], plan, drop_unplanned=True)
    rows = read_results(folder / "results.csv")
    committed = read_results(F9 / "results.csv")
    assert {r["method"] for r in rows} == {m.name for m in kept}
    assert len(merged.dropped) == sum(r["method"] == "rt1_small" for r in committed) > 0 and merged.added == 0
    assert not (folder / "curve.csv").exists()  # every point was RT-1's
    episodes = pq.read_table(folder / "episodes.parquet")
    assert set(episodes["step"].to_pylist()) == {r["step"] for r in rows}
