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
from lerobot_factorworld.study.results.merge import CELL, merge_curve_rows, merge_results, merge_rows
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
    merged = merge_results(first, [second], plan, study="f1_ordering")
    (results, episodes), added = merged.written, merged.added
    assert results.read_bytes() == (F1 / "results.csv").read_bytes()
    assert added == len(read_results(second / "results.csv")) and merged.dropped == []
    merged, committed = pq.read_table(episodes), pq.read_table(F1 / "episodes.parquet")
    assert merged.select(committed.column_names).equals(committed)
    again = _part(tmp_path, "again", seeds - {min(seeds)})
    merge_results(again, [_part(tmp_path, "other", {min(seeds)})], plan, study="f1_ordering")
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
    for first, second in [("late", "early"), ("early", "late")]:
        parts = {}
        for name, keep in [
            ("early", lambda i: i < 2 or i == len(lines) - 2),
            ("late", lambda i: 2 <= i < len(lines) - 2),
        ]:
            folder = parts[name] = tmp_path / f"{first}_first" / name
            folder.mkdir(parents=True)
            shutil.copy(CURVE / "config.yaml", folder / "config.yaml")
            shutil.copy(CURVE / "results.csv", folder / "results.csv")
            (folder / "curve.csv").write_text(lines[0] + "".join(line for i, line in enumerate(lines[1:]) if keep(i)))
        merged = merge_results(parts[first], [parts[second]], plan, study="rt1_curve_pick")
        assert merged.added == 0 and parts[first] / "curve.csv" in merged.written and merged.notes == []
        assert (parts[first] / "curve.csv").read_bytes() == (CURVE / "curve.csv").read_bytes()
    rows = read_curve(CURVE / "curve.csv")
    assert merge_curve_rows([rows[2:], rows[:2]], plan, ["a", "b"]) == rows
    changed = [{**rows[0], "successes": rows[0]["successes"] + 1}]
    with pytest.raises(ValueError, match=rf"point {rows[0]['step']} differs between a and b in successes"):
        merge_curve_rows([rows, changed], plan, ["a", "b"])
    with pytest.raises(ValueError, match="is not in the study's plan"):
        merge_curve_rows([[{**rows[0], "step": "e" * 16}]], plan, ["a"])


def _doubled(train: dict) -> dict:
    """A method's ``train`` with its epochs, checkpoints and the links it extends (if any) twice as far apart."""
    doubled = {k: 2 * train[k] for k in ("epochs", "curve_every") if k in train}
    return {**train, **doubled, **({"extends": [2 * e for e in train["extends"]]} if train.get("extends") else {})}


def _flow(train: dict) -> str:
    """``train: {...}`` as the config's YAML writes a method's budget on one line."""
    value = lambda v: f"[{', '.join(f'{e:g}' for e in v)}]" if isinstance(v, list) else f"{v:g}"  # noqa: E731
    return "train: {" + ", ".join(f"{k}: {value(v)}" for k, v in train.items()) + "}"


def _f9_with_a_longer_rt1_budget():
    """F9's config with RT-1 trained twice its committed epochs (a checkpoint twice as far apart): RT-1's steps
    get new keys, the CNN's keep theirs. Returns the config and a map from each RT-1 cell to its new evaluation key."""
    cfg = load_config(F9 / "config.yaml")
    methods = [replace(m, train=_doubled(m.train)) if m.name == "rt1_small" else m for m in cfg.methods]
    longer = replace(cfg, methods=methods)
    keys = {
        tuple(str(s.meta[c]) for c in CELL): s.key
        for s in make_plan(longer).evaluations()
        if s.meta["method"] == "rt1_small"
    }
    return longer, keys


def test_a_changed_budget_s_old_rows_are_refused_with_the_way_out_or_dropped_on_request(tmp_path, capsys):
    """F9 with RT-1's budget changed: its committed RT-1 rows are no longer planned, and a new part holds the same
    cells under new keys. Merging refuses, naming ``--drop_unplanned=true``, and writes nothing; with it the old
    rows (their episodes and curve points) are left out and listed, the new ones added, and what became of the
    curve is said."""
    longer, keys = _f9_with_a_longer_rt1_budget()
    folder, new = tmp_path / "f9", tmp_path / "new"
    shutil.copytree(F9, folder)
    new.mkdir()
    lines = (F9 / "results.csv").read_text().splitlines(keepends=True)
    step = lines[0].rstrip("\n").split(",").index("step")
    rt1 = [line for line in lines[1:] if line.split(",")[1] == "rt1_small"]
    assert len(rt1) == len(keys) > 0
    renamed = []
    for line in rt1:
        values = next(csv.reader([line]))
        values[step] = keys[tuple(values[lines[0].split(",").index(c)] for c in CELL)]
        renamed.append(",".join(values) + "\n")
    (new / "results.csv").write_text(lines[0] + "".join(renamed))
    before = {name: (folder / name).read_bytes() for name in ("results.csv", "episodes.parquet", "curve.csv")}
    plan = make_plan(longer)
    with pytest.raises(ValueError, match="comes from two evaluation steps.*--drop_unplanned=true"):
        merge_results(folder, [new], plan, study=longer.name)
    assert {name: (folder / name).read_bytes() for name in before} == before  # refused: nothing written
    merged = merge_results(folder, [new], plan, study=longer.name, drop_unplanned=True)
    assert len(merged.dropped) == len(rt1) and merged.added == len(rt1)
    assert {r["step"] for r in read_results(folder / "results.csv")} == (
        {r["step"] for r in read_results(F9 / "results.csv") if r["method"] != "rt1_small"} | set(keys.values())
    )
    assert not (folder / "curve.csv").exists()  # every point was of the old training, and the new part has none
    assert merged.notes == [
        f"{new} has no curve.csv: the learning curves of its trainings are not in the merged one",
        f"removed {folder / 'curve.csv'}: the plan holds none of its points",
    ]
    kept = {r["step"] for r in read_results(F9 / "results.csv") if r["method"] != "rt1_small"}
    assert set(pq.read_table(folder / "episodes.parquet")["step"].to_pylist()) == kept  # old RT-1 episodes gone
    shutil.copytree(F9, folder, dirs_exist_ok=True)  # again, from the command line with the config's text changed
    text = (F9 / "config.yaml").read_text()
    committed = next(m for m in load_config(F9 / "config.yaml").methods if m.name == "rt1_small").train
    budget, doubled = _flow(committed), _flow(_doubled(committed))
    assert text.count(budget) == 1
    (tmp_path / "longer.yaml").write_text(text.replace(budget, doubled))
    main(
        [
            "merge-results",
            f"--into={folder}",
            f"--add=[{new}]",
            f"--config={tmp_path / 'longer.yaml'}",
            "--drop_unplanned=true",
        ]
    )
    out = capsys.readouterr().out.splitlines()
    assert sum(line.startswith("dropped ") and "method=rt1_small" in line for line in out) == len(rt1)
    assert f"removed {folder / 'curve.csv'}: the plan holds none of its points" in out
    assert out[-1].startswith(f"added {len(rt1)} evaluation(s)")
    # the hinted command names the given config: the folder's own config.yaml does not plan the new rows yet
    hint = out[-1].split("render it with: factorworld ")[1].split()
    assert hint[-1] == f"--config={tmp_path / 'longer.yaml'}"
    main(hint[:-1])  # without it the report reads the folder's old config.yaml, which describes the old budget
    assert doubled not in (folder / "config.yaml").read_text()
    main(hint)
    assert doubled in (folder / "config.yaml").read_text()  # and the report leaves the folder's config the new one


def test_a_wrong_config_is_refused_even_when_dropping_unplanned_rows(tmp_path):
    """Another study's config (or this study's name on another grid) plans none of a part's rows: refused, with
    or without ``drop_unplanned``, and nothing is written."""
    folder = tmp_path / "curve"
    shutil.copytree(F1.parent / "learning_curve", folder)
    before = (folder / "results.csv").read_bytes()
    other = load_config(CURVE / "config.yaml")
    with pytest.raises(ValueError, match="holds study learning_curve, but the config is of study rt1_curve_pick"):
        merge_results(folder, [], make_plan(other), study=other.name, drop_unplanned=True)
    same_name = replace(other, name="learning_curve")
    with pytest.raises(ValueError, match="the config plans none of the 6 rows of .*: is it this study's config"):
        merge_results(folder, [], make_plan(same_name), study="learning_curve", drop_unplanned=True)
    assert (folder / "results.csv").read_bytes() == before


def test_a_part_of_one_method_plans_its_steps_under_the_whole_study_s_keys(capsys):
    """``--only_methods``: F9 run for RT-1 alone (another machine runs the CNN) plans a subset of the whole study's
    steps, the same keys, so its rows merge beside the CNN's; the claims about the CNN (those that name no method
    are the first method's) are left out; an unknown name is one line naming the study's methods, before any work."""
    cfg = load_config(F9 / "config.yaml")
    part = cfg.only(["rt1_small"])
    whole, steps = make_plan(cfg), make_plan(part).steps
    assert {s.key for s in steps} < {s.key for s in whole.steps}
    assert {s.meta["method"] for s in steps if "method" in s.meta} == {"rt1_small"}
    assert [s.key for s in whole.steps if s.meta.get("method") == "rt1_small"] == [
        s.key for s in steps if s.meta.get("method") == "rt1_small"
    ]
    assert [c.method for c in part.claims] == ["rt1_small"] * sum(c.method == "rt1_small" for c in cfg.claims) > []
    assert [c.method for c in cfg.only(["bc_language"]).claims] == ["bc_language"] * sum(
        c.method is None for c in cfg.claims
    )
    with pytest.raises(SystemExit) as stop:
        main(["study", f"--config={F9 / 'config.yaml'}", "--only_methods=[rt1]", "--dry-run"])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2 and err == [
        "error: only_methods: unknown method(s) rt1; this study's methods: bc_language, rt1_small"
    ]
