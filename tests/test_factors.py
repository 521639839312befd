"""Factor registry, values and sampling: one source of truth, clear errors, seeded determinism."""

import json

import numpy as np
import pytest
from PIL import Image

from lerobot_factorworld import FACTORS, TASKS, FactorValues, SceneConfig, load_configs, save_configs
from lerobot_factorworld.assets import split_names
from lerobot_factorworld.factors.registry import (
    PAPER_STUDY_FACTORS,
    factor_range,
    support_matrix,
    support_matrix_markdown,
)
from lerobot_factorworld.factors.sampling import SamplingOptions, sample_configs, shift_configs
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
    assert len(TASKS) == 20


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
    assert {c.factors.table_texture for c in train} <= train_tex
    assert {c.factors.table_texture for c in tests} <= eval_tex
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
