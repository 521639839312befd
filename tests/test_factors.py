"""Factor registry, values and sampling: one source of truth, clear errors, seeded determinism."""

import ast
import json
from collections import Counter
from pathlib import Path

import draccus
import numpy as np
import pytest
from PIL import Image

import lerobot_factorworld
from lerobot_factorworld import FACTORS, TASKS, FactorValues, SceneConfig, SceneObject, load_configs, save_configs
from lerobot_factorworld.assets import DEFAULT_TABLE_TEXTURE, asset_family, split_names
from lerobot_factorworld.assets.scenes import scene_assets, scene_shape_families
from lerobot_factorworld.factors import registry, values
from lerobot_factorworld.factors.registry import (
    PAPER_STUDY_FACTORS,
    factor_range,
    support_matrix,
    support_matrix_markdown,
    validate_value,
)
from lerobot_factorworld.protocol import sampling
from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs, shift_configs
from lerobot_factorworld.tasks import get_task

PAPER_FACTORS = (
    "object_pos",
    "arm_pos",
    "camera_pos",
    "table_pos",
    "object_size",
    "object_shape",
    "object_texture",
    "table_texture",
    "floor_texture",
    "light",
    "distractors",
)


def test_eleven_factors_named_as_in_the_paper():
    assert tuple(FACTORS) == PAPER_FACTORS
    assert len([t for t in TASKS.values() if not t.family]) == 20  # the public Factor World's; + the pick family


def test_continuous_ranges_follow_the_paper_table():
    for width, radius in (("narrow", 0.025), ("medium", 0.05), ("wide", 0.075)):
        low, high = FACTORS["camera_pos"].range(width)
        assert np.allclose(low, -radius) and np.allclose(high, radius) and len(low) == 7
    assert FACTORS["table_pos"].range("medium") == ((-0.05, -0.05, -0.05), (0.05, 0.05, 0.025))
    assert FACTORS["table_pos"].range("wide") == ((-0.075, -0.075, -0.05), (0.075, 0.075, 0.025))
    assert FACTORS["object_pos"].range("narrow") == ((-0.05, -0.05), (0.05, 0.05))
    assert FACTORS["object_pos"].range("medium") == ((-0.1, -0.075), (0.1, 0.075))
    assert FACTORS["light"].range() == ((0.2, 0.2), (0.8, 0.8))


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda: SceneConfig("pick-plcae"), "valid tasks: pick-place"),
        (lambda: FactorValues.from_dict({"lighting": (0.5, 0.5)}), "valid factors: object_pos"),
        (lambda: FactorValues(light=(0.9, 0.5)), "outside its range [0.2, 0.8]"),
        (lambda: FactorValues(camera_pos=(0.0,) * 6), "expects 7 numbers"),
        (lambda: FactorValues(table_texture="wood.png"), "starting with one of proc:"),
        (lambda: FactorValues(table_texture="rgb:1.5,0,0"), "three components in [0, 1]"),
        (lambda: SceneConfig("pick-place", split="test"), "valid splits: train, eval"),
        (lambda: SceneConfig("door-open", FactorValues(object_size=1.1)), "does not apply to task 'door-open'"),
        (lambda: SceneConfig("drawer-close", FactorValues(object_pos=(0.0, 0.05))), "stays solvable"),
        (lambda: FACTORS["light"].range("wide"), "valid widths: paper"),
        (lambda: SamplingOptions(widths={"camera_pos": "huge"}), "valid widths: narrow, medium, wide"),
        (lambda: SamplingOptions(texture_folder="/nonexistent/textures"), "/nonexistent/textures"),
        (lambda: sample_configs("pick-place", 2, split="holdout"), "valid splits: train, eval"),
        (lambda: SamplingOptions(asset_split="scene"), "valid asset splits: family, variant"),
    ],
)
def test_bad_input_gets_a_clear_error(make, fragment):
    with pytest.raises((ValueError, FileNotFoundError)) as err:
        make()
    assert fragment in str(err.value)


def test_support_matrix_marks_object_factors_of_fixtures():
    matrix = support_matrix()
    assert matrix["pick-place"]["object_shape"] and matrix["pick-place"]["object_size"]
    assert not matrix["door-open"]["object_size"] and not matrix["door-open"]["object_shape"]
    assert all(row["object_texture"] and row["object_pos"] for row in matrix.values())
    assert "| door-open |" in support_matrix_markdown()


def test_config_is_a_value_that_saves_loads_and_compares(tmp_path):
    configs = sample_configs("pick-place", 3, seed=4, factors=PAPER_STUDY_FACTORS + ("object_size",))
    path = save_configs(configs, tmp_path / "envs.json")
    loaded = load_configs(path)
    assert loaded == configs and hash(loaded[0]) == hash(configs[0])
    assert configs[0] != configs[1]
    assert "camera_pos" in str(configs[0]) and configs[0].env_id == "pick-place/train/000"
    assert json.loads(path.read_text())[0]["task"] == "pick-place"


def test_sampling_is_seeded_and_factors_are_independent():
    a = sample_configs("door-open", 4, seed=7, factors=("light", "table_texture"))
    b = sample_configs("door-open", 4, seed=7, factors=("light", "table_texture"))
    c = sample_configs("door-open", 4, seed=8, factors=("light", "table_texture"))
    only_light = sample_configs("door-open", 4, seed=7, factors=("light",))
    assert a == b and a != c
    assert [x.factors.light for x in a] == [x.factors.light for x in only_light]


def test_train_and_eval_draw_from_disjoint_asset_splits():
    train = sample_configs("pick-place", 20, seed=0, factors=("table_texture", "object_shape", "distractors"))
    tests = shift_configs(train, ("table_texture", "object_shape"), 20, seed=1)
    train_tex, eval_tex = set(split_names("texture", "train")), set(split_names("texture", "eval"))
    assert not train_tex & eval_tex
    seen, shifted = _images(c.factors.table_texture for c in train), _images(c.factors.table_texture for c in tests)
    assert seen and shifted  # the default share draws images and flat colours (tests/test_rgb_textures.py)
    assert seen <= train_tex and shifted <= eval_tex
    assert {c.factors.object_shape for c in tests} <= set(split_names("shape", "eval"))
    # a shifted environment keeps every other factor of its training environment
    assert all(t.factors.distractors == train[j % 20].factors.distractors for j, t in enumerate(tests))


def test_task_limits_narrow_the_sampling_range():
    low, high = factor_range(get_task("drawer-close"), "object_pos", "medium")
    assert high[1] == 0.02 and low == (-0.1, -0.075)


def test_user_texture_folder_gets_the_same_split_mechanism(tmp_path):
    rng = np.random.default_rng(0)
    for i in range(6):
        Image.fromarray(rng.integers(0, 255, (16, 16, 3), dtype=np.uint8)).save(tmp_path / f"t{i}.png")
    options = SamplingOptions(texture_folder=str(tmp_path), rgb_fraction=0.0)
    train = sample_configs("pick-place", 5, factors=("table_texture",), options=options)
    evals = sample_configs("pick-place", 5, split="eval", factors=("table_texture",), options=options)
    train_names = {c.factors.table_texture for c in train}
    assert all(n.startswith("file:") for n in train_names)
    assert not train_names & {c.factors.table_texture for c in evals}


def test_rgb_textures_are_drawn_when_asked():
    options = SamplingOptions(rgb_fraction=1.0)
    configs = sample_configs("pick-place", 3, factors=("floor_texture",), options=options)
    assert all(c.factors.floor_texture.startswith("rgb:") for c in configs)


def _families(names) -> set[str]:
    return {asset_family(n) for n in names}


def _images(names) -> set[str]:
    """The image textures among texture values (the others are flat ``rgb:`` colours, which no split holds)."""
    return {n for n in names if not n.startswith("rgb:")}


IMAGES_ONLY = SamplingOptions(rgb_fraction=0.0)
"""Image textures only: for the tests of the asset splits and of the rules between image textures."""


def test_default_sampling_and_shifts_hold_whole_families_out():
    assert SamplingOptions().asset_split == "family"
    train = sample_configs("pick-place", 20, seed=0, factors=("table_texture", "object_shape"))
    tests = shift_configs(train, ("table_texture", "object_shape"), 40, seed=1)
    for factor, kind in (("table_texture", "texture"), ("object_shape", "shape")):
        seen, shifted = (
            _images(getattr(c.factors, factor) for c in train),
            _images(getattr(c.factors, factor) for c in tests),
        )
        assert set(seen) <= set(split_names(kind, "train", mode="family"))
        assert set(shifted) <= set(split_names(kind, "eval", mode="family"))
        assert not _families(shifted) & _families(split_names(kind, "train"))  # unseen kinds, not new variants
    # the per-variant split stays selectable, also as a flag (draccus: --sampling.asset_split=variant)
    variant = draccus.parse(SamplingOptions, args=["--asset_split=variant"])
    assert variant == SamplingOptions(asset_split="variant")
    redrawn = _images(
        c.factors.table_texture for c in shift_configs(train, "table_texture", 40, seed=1, options=variant)
    )
    assert redrawn <= set(split_names("texture", "eval", mode="variant"))
    assert _families(redrawn) & _families(split_names("texture", "train"))


def _flat_texture_folder(root: Path, n: int = 4) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """n random images (each its own family); returns the folder's (train, eval) names (2 and 2 for n=4)."""
    root.mkdir()
    rng = np.random.default_rng(0)
    for i in range(n):
        Image.fromarray(rng.integers(0, 255, (8, 8, 3), dtype=np.uint8)).save(root / f"t{i}.png")
    return split_names("texture", "train", root), split_names("texture", "eval", root)


def test_object_texture_never_equals_table_texture(tmp_path, monkeypatch):
    folder = tmp_path / "textures"
    train, evals = _flat_texture_folder(folder)
    options = SamplingOptions(texture_folder=str(folder), rgb_fraction=0.0)
    both = sample_configs("door-open", 30, seed=3, factors=("object_texture", "table_texture"), options=options)
    tables = [c.factors.table_texture for c in both]
    objects_alone = [
        c.factors.object_texture for c in sample_configs("door-open", 30, 3, "train", ("object_texture",), options)
    ]
    assert tables == [
        c.factors.table_texture for c in sample_configs("door-open", 30, 3, "train", ("table_texture",), options)
    ]
    assert sum(o == t for o, t in zip(objects_alone, tables)) >= 5  # drawn alone, they would clash often
    for config, alone in zip(both, objects_alone):
        other = next(n for n in train if n != config.factors.table_texture)  # two train textures: the rule decides
        assert config.factors.object_texture == other
        assert alone == other or alone == config.factors.table_texture  # only clashing draws changed
    # the default table (Meta-World's wood) counts too
    assert DEFAULT_TABLE_TEXTURE in split_names("texture", "train")
    monkeypatch.setattr(sampling, "DEFAULT_TABLE_TEXTURE", train[0])
    assert {
        c.factors.object_texture for c in sample_configs("door-open", 10, 1, "train", ("object_texture",), options)
    } == {train[1]}
    monkeypatch.undo()
    # shifts: the shifted texture avoids the inherited one, which stays exactly as in training
    for fixed, shifted in (("object_texture", "table_texture"), ("table_texture", "object_texture")):
        base = [SceneConfig("door-open", FactorValues(**{fixed: name})) for name in evals]
        out = shift_configs(base, shifted, 10, seed=2, options=options)
        assert [getattr(c.factors, fixed) for c in out] == [evals[j % 2] for j in range(10)]
        assert all(c.factors.object_texture != c.factors.table_texture for c in out)
    pair = shift_configs(both, ("object_texture", "table_texture"), 20, seed=5, options=options)
    assert all(c.factors.object_texture != c.factors.table_texture for c in pair)


def test_object_and_table_textures_differ_in_default_studies():
    train = sample_configs("pick-place", 100, seed=0)
    assert all(c.factors.object_texture not in (c.factors.table_texture, None) for c in train)
    for shift in ("object_texture", "table_texture", ("object_texture", "table_texture")):
        for split in ("train", "eval"):
            tests = shift_configs(
                train, shift, 100, seed=1, split=split, options=SamplingOptions(asset_split="variant")
            )
            assert all(c.factors.object_texture != c.factors.table_texture for c in tests)


@pytest.mark.parametrize("task", ["pick-place", "basketball", "bin-picking"])
def test_distractors_never_share_the_task_objects_family(task):
    family = get_task(task).object_family
    assert family in _families(split_names("shape", "train"))  # the pool holds look-alikes: the rule drops them
    for mode in ("family", "variant"):
        options = SamplingOptions(n_distractors=5, asset_split=mode)
        train = sample_configs(task, 12, seed=0, factors=("distractors",), options=options)
        assert train == sample_configs(task, 12, seed=0, factors=("distractors",), options=options)
        tests = shift_configs(train, "distractors", 12, seed=1, options=options)
        shapes = [d.shape for c in train + tests for d in c.factors.distractors]
        assert len(shapes) == 120 and family not in _families(shapes)
        assert len(_families(shapes)) >= 8


_SCENE_LOOKALIKES = {
    "faucet-open": {"cylinder", "hardware"},  # the faucet's head and base
    "button-press": {"cylinder"},  # the button
    "drawer-open": {"open_box"},  # the drawer
    "lever-pull": {"ellipsoid", "cylinder"},  # the ball handle and the rod base
    "door-open": {"hardware"},  # the door handle
    "basketball": {"ellipsoid", "torus"},  # the ball and the hoop
    "bin-picking": {"box", "open_box"},  # the block and the bin
}
"""What the review found next to each task's own fixture (a second faucet head, hoop, bin, ...)."""


@pytest.mark.parametrize("task", list(TASKS))
def test_distractors_never_look_like_anything_the_tasks_scene_shows(task, monkeypatch):
    from lerobot_factorworld.protocol import keepout

    monkeypatch.setattr(keepout, "keepout_boxes", lambda name: [])  # placement is not under test here: quick
    shown = set(scene_shape_families(task))
    assert _SCENE_LOOKALIKES.get(task, set()) <= shown
    options = SamplingOptions(n_distractors=5)
    train = sample_configs(task, 12, seed=0, factors=("distractors",), options=options)
    tests = shift_configs(train, "distractors", 12, seed=1, options=options)
    families = _families(d.shape for c in train + tests for d in c.factors.distractors)
    assert not families & shown
    assert len(families) >= 8  # the rule drops a few families, not the variety


def test_sampled_table_texture_avoids_the_fixture_objects_own_textures(monkeypatch):
    door = scene_assets("door-open").object_textures  # what the door shows while its texture is not varied
    assert door == ("metaworld:textures/metal1.png", "metaworld:textures/metal2.png")
    pool = (*door, "metaworld:textures/wood1.png", "proc:marble-000")
    monkeypatch.setattr(sampling, "asset_split_names", lambda kind, split, folder=None, mode="family": pool)
    drawn = sample_configs("door-open", 40, seed=0, factors=("table_texture",), options=IMAGES_ONLY)
    assert {c.factors.table_texture for c in drawn} == set(pool) - set(door)  # alone: half would be the door's metal
    both = sample_configs("door-open", 40, seed=0, factors=("object_texture", "table_texture"))
    assert all(c.factors.table_texture != c.factors.object_texture for c in both)
    # a repainted door frees its metal for the table, which then avoids the door's new texture
    repainted = [SceneConfig("door-open", FactorValues(object_texture="proc:marble-000"))]
    shifted = shift_configs(repainted, "table_texture", 40, seed=0, split="train", options=IMAGES_ONLY)
    assert {c.factors.table_texture for c in shifted} == set(pool) - {"proc:marble-000"}
    # a configuration written by hand is taken as given (the rules are sampling rules, docs/factors.md)
    same = SceneConfig("door-open", FactorValues(object_texture=door[0], table_texture=door[0]))
    assert same.factors.object_texture == same.factors.table_texture


def test_a_replaced_draw_is_uniform_over_the_allowed_names_and_takes_one_number():
    pool = sampling._Pool("shape", tuple(f"n{i}" for i in range(10)), {})
    excluded = {"n3", "n4", "n5"}  # a family's names are neighbours in the sorted pool

    def allowed(name: str) -> bool:
        return name not in excluded

    rng = np.random.default_rng(0)
    counts = Counter(sampling._draw(rng, pool, allowed, "shape") for _ in range(21000))
    assert set(counts) == set(pool.names) - excluded
    assert all(abs(c / 21000 - 1 / 7) < 0.012 for c in counts.values()), counts  # 5 sigma; `k mod m` gave 2/10
    a, b = np.random.default_rng(1), np.random.default_rng(1)
    draws = [sampling._draw(a, pool, allowed, "shape") for _ in range(50)]
    unruled = [pool.names[int(b.integers(10))] for _ in range(50)]
    assert a.random() == b.random()  # one draw each, whatever the rule did: later draws never shift
    assert [d for d, u in zip(draws, unruled) if u not in excluded] == [u for u in unruled if u not in excluded]
    again = np.random.default_rng(1)
    assert draws == [sampling._draw(again, pool, allowed, "shape") for _ in range(50)]  # same seed, same names


def test_sample_command_takes_sampling_options(tmp_path, capsys):
    from lerobot_factorworld import cli

    out = tmp_path / "envs.json"
    args = ["sample", "--task=door-open", "--n=20", "--factors=[table_texture]", f"--out={out}"]
    cli.main([*args, "--sampling.asset_split=variant"])
    variant = SamplingOptions(asset_split="variant")
    assert load_configs(out) == sample_configs("door-open", 20, 0, "train", ("table_texture",), variant)
    tables = _images(c.factors.table_texture for c in load_configs(out))
    assert tables <= set(split_names("texture", "train", mode="variant"))
    assert _families(tables) & _families(split_names("texture", "eval"))  # kinds the family split holds out
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_:
        cli.main([*args, "--sampling.asset_split=scene"])
    assert exit_.value.code == 2
    assert capsys.readouterr().err.splitlines() == [
        "error: unknown asset split 'scene'; valid asset splits: family, variant"
    ]


def test_distractors_avoid_the_family_of_the_objects_own_shape():
    options = SamplingOptions(n_distractors=5, asset_split="variant")
    train = sample_configs("pick-place", 30, seed=2, factors=("object_shape", "distractors"), options=options)

    def clashes(configs):
        return [
            c
            for c in configs
            if asset_family(c.factors.object_shape) in _families(d.shape for d in c.factors.distractors)
        ]

    assert not clashes(train)
    alone = sample_configs("pick-place", 30, seed=2, factors=("distractors",), options=options)
    assert [c.factors.object_shape for c in train] == [
        c.factors.object_shape for c in sample_configs("pick-place", 30, 2, "train", ("object_shape",), options)
    ]
    mixed = [t.with_factors(distractors=a.factors.distractors) for t, a in zip(train, alone)]
    assert len(clashes(mixed)) >= 3  # without the rule some would clash
    # a shifted shape avoids the inherited distractors' families and the other way round
    for shift in ("object_shape", "distractors"):
        tests = shift_configs(train, shift, 30, seed=3, split="train", options=options)
        assert not clashes(tests)
        kept = "distractors" if shift == "object_shape" else "object_shape"
        assert [getattr(c.factors, kept) for c in tests] == [getattr(c.factors, kept) for c in train]


def test_registry_and_values_import_one_way():
    """registry <- values <- sampling: no module imports one that imports it (not even inside a function)."""

    def imports(module) -> set[str]:
        tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
        return {node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}

    assert not {"values", "sampling"} & imports(registry)
    assert "sampling" not in imports(values)
    assert SceneObject is values.SceneObject is registry.SceneObject is lerobot_factorworld.SceneObject
    assert (
        validate_value("distractors", [SceneObject("proc:mug-001", 0.1, 0.1, 0.0, 0.08, "rgb:1,0,0")])[0].size == 0.08
    )
