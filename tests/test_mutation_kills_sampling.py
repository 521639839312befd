"""Sampling (protocol/sampling.py) where mutation testing found the suite silent (docs/testing.md): the public
one-factor draw had no in-process test, the seed derivation of ``_aside`` (which every rule-breaking draw uses, so
it decides scenes on every machine) was not pinned, and the distractors' placement was checked only for not
failing: their yaw range, their footprint against each other and the task's keep-out boxes, and the errors named
when the table or the shape pool leaves no room."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from lerobot_factorworld.factors.registry import DISTRACTOR_AREA, DISTRACTOR_SIZE
from lerobot_factorworld.protocol import keepout, sampling
from lerobot_factorworld.protocol.sampling import SamplingOptions, factor_rng, sample_factor, sample_factor_values

TASK = "door-open"


def test_one_factor_drawn_alone_is_the_value_the_grid_draws_from_the_same_stream():
    for name, split in itertools.product(("light", "table_texture", "camera_pos"), ("train", "eval")):
        alone = sample_factor(name, TASK, factor_rng(7, split, name), split)
        (grid,) = sample_factor_values(TASK, [name], n=1, seed=7, split=split)
        assert alone == getattr(grid, name), (name, split)
    # the split's own pool: a held-out (eval) texture is never a training one
    train = {sample_factor("table_texture", TASK, factor_rng(s, "train", "table_texture"), "train") for s in range(30)}
    held_out = {sample_factor("table_texture", TASK, factor_rng(s, "eval", "table_texture"), "eval") for s in range(30)}
    images = lambda names: {n for n in names if not n.startswith("rgb")}  # noqa: E731
    assert images(train) and images(held_out) and not images(train) & images(held_out)


def test_one_factor_follows_its_options_and_the_scene_it_joins():
    colours = [
        sample_factor("table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=1.0))
        for s in range(5)
    ]
    assert all(c.startswith("rgb") for c in colours)
    images = [
        sample_factor("table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0))
        for s in range(5)
    ]
    assert not any(i.startswith("rgb") for i in images)
    three = sample_factor("distractors", TASK, np.random.default_rng(0), options=SamplingOptions(n_distractors=3))
    assert len(three) == 3 and len(sample_factor("distractors", TASK, np.random.default_rng(0))) == 1  # default: 1
    # the rule against the scene: object texture never equals the table texture it is drawn beside
    for s in range(40):
        table = sample_factor(
            "table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0)
        )
        obj = sample_factor("object_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0), scene={"table_texture": table})  # fmt: skip
        assert obj != table
    with pytest.raises(ValueError, match="unknown split 'val'"):
        sample_factor("light", TASK, np.random.default_rng(0), split="val")


def test_aside_is_seeded_by_the_rng_state_and_leaves_the_rng_where_it_was():
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state
    first = int(sampling._aside(rng).integers(2**62))
    assert rng.bit_generator.state == before  # not advanced
    # pinned: the seed is the first 16 bytes, little-endian, of the SHA-256 of the state's JSON with sorted keys;
    # another derivation changes every rule-breaking draw, hence the scenes, on every machine
    assert first == 2965110437108376986
    assert int(sampling._aside(rng).integers(2**62)) == first  # the same state, the same generator
    rng.random()
    assert int(sampling._aside(rng).integers(2**62)) != first  # another state, another generator


def _distractor_scenes(n: int, count: int) -> list:
    options = SamplingOptions(n_distractors=count)
    return [sample_factor("distractors", TASK, np.random.default_rng(s), options=options) for s in range(n)]


def test_distractors_turn_all_the_way_round_and_keep_clear_of_each_other_and_the_task():
    scenes = _distractor_scenes(150, 5)
    yaws = [d.yaw for scene in scenes for d in scene]
    assert 0 <= min(yaws) < 0.2 and 2 * math.pi - 0.2 < max(yaws) < 2 * math.pi  # [0, 2 pi)
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    blocked = [tuple(b) for b in keepout.keepout_boxes(TASK)]
    edge = []
    for scene in scenes:
        boxes = [(d.x - d.size / 2, d.y - d.size / 2, d.x + d.size / 2, d.y + d.size / 2) for d in scene]
        for box, d in zip(boxes, scene):
            assert DISTRACTOR_SIZE[0] <= d.size <= DISTRACTOR_SIZE[1]
            assert xlo <= box[0] and box[2] <= xhi and ylo <= box[1] and box[3] <= yhi  # its whole footprint
            assert not any(sampling._overlap(box, b) for b in blocked)
            edge.append(min(box[0] - xlo, xhi - box[2], box[1] - ylo, yhi - box[3]))
        for a, b in itertools.combinations(boxes, 2):
            assert not sampling._overlap(a, b)
    assert min(edge) < 0.01  # the footprints reach the area's edge: the check above is not vacuous


def test_a_table_with_no_room_and_a_pool_with_no_shape_are_refused_naming_what_ran_out(monkeypatch):
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    with monkeypatch.context() as m:
        m.setattr(keepout, "keepout_boxes", lambda task: np.array([[xlo, ylo, xhi, yhi]]))
        with pytest.raises(RuntimeError) as err:
            sample_factor("distractors", TASK, np.random.default_rng(0), options=SamplingOptions(n_distractors=2))
        assert str(err.value) == (
            f"could not place 2 distractors on the free table area of {TASK} after {sampling.MAX_PLACEMENT_TRIES} "
            "tries; use fewer distractors (n_distractors)"
        )
    # every family a look-alike of the task's object: no distractor shape left
    monkeypatch.setattr(sampling, "scene_shape_families", lambda task, own: _every_family())
    with pytest.raises(ValueError, match=r"^no distractor shape in the \w+ pool obeys the rules between factors"):
        sample_factor("distractors", TASK, np.random.default_rng(0))


def _every_family() -> list[str]:
    pool = sampling._Pools("train", SamplingOptions()).shape
    return sorted({pool.family_of(name) for name in pool.names})


def test_aside_reads_the_whole_state_of_any_bit_generator_a_caller_passes():
    # sample_factor takes any np.random.Generator; only PCG64 (default_rng's) has an all-integer state. MT19937's
    # key, Philox's counter/key/buffer and SFC64's state are uint32/uint64 arrays, which the JSON encoder can only
    # write through ``default`` (as lists): without it _aside raises, and with a ``default`` that drops them the
    # arrays become ``null``, so every state at the same position would seed the same aside generator
    for make in (np.random.MT19937, np.random.Philox, np.random.SFC64):
        rng_a, rng_b = np.random.Generator(make(1)), np.random.Generator(make(2))
        assert type(rng_a.bit_generator.state["state"]) is dict  # the arrays sit in this nested dict
        before = rng_a.bit_generator.state["state"]
        draw_a = int(sampling._aside(rng_a).integers(2**62))
        assert all(np.array_equal(v, rng_a.bit_generator.state["state"][k]) for k, v in before.items())  # unmoved
        assert int(sampling._aside(rng_a).integers(2**62)) == draw_a  # the same state, the same generator
        # seeds 1 and 2 give the same position and other arrays: the arrays alone tell the two states apart
        assert int(sampling._aside(rng_b).integers(2**62)) != draw_a, make.__name__
    # through the public draw: a table texture forced to break its rule (the object wears the very texture the
    # unconstrained draw picks) is replaced through _aside, with an MT19937 generator as with PCG64
    images = SamplingOptions(rgb_fraction=0.0)
    for seed in range(3):
        free = sample_factor("table_texture", TASK, np.random.Generator(np.random.MT19937(seed)), options=images)
        rng = np.random.Generator(np.random.MT19937(seed))
        table = sample_factor("table_texture", TASK, rng, options=images, scene={"object_texture": free})
        assert table != free and table in sampling._Pools("train", images).texture.names


def _two_shape_families(folder: Path) -> SamplingOptions:
    """A shape folder of two families, crab/ and moth/, of six meshes each (sampling only lists the files, so a
    one-vertex .obj is enough), split by variant so that both families have files on each side."""
    for family in ("crab", "moth"):
        (folder / family).mkdir()
        for i in range(1, 7):
            (folder / family / f"{family}_{i}.obj").write_text("v 0 0 0\n")
    return SamplingOptions(shape_folder=str(folder), asset_split="variant", n_distractors=2)


def _folder_family(name: str) -> str:
    """The family a ``file:`` name of that folder belongs to: its subfolder."""
    return Path(name.removeprefix("file:")).parent.name


def test_a_shape_folder_family_is_its_top_level_subfolder_for_the_look_alike_rule(tmp_path):
    options = _two_shape_families(tmp_path)
    pool = sampling._Pools("train", options).shape
    moths = [n for n in pool.names if "/moth/" in n]
    assert len(moths) >= 2 and len(moths) < len(pool.names)
    assert pool.family_of(moths[0]) == "moth"  # the subfolder, not the file (asset_family without the folder)

    def families(scene):
        return [
            _folder_family(d.shape)
            for s in range(20)
            for d in sample_factor("distractors", "pick-place", np.random.default_rng(s), options=options, scene=scene)
        ]

    # no folder family is shown by pick-place's own scene: both are drawn (40 draws, about 4 in 7 of them moths)
    assert set(families({})) == {"crab", "moth"}
    # beside a moth object every other moth file is a look-alike: all 40 distractors are crabs
    assert families({"object_shape": moths[0]}) == ["crab"] * 40


# (x0, y0, x1, y1) boxes: open rectangles overlap iff both their x and their y intervals overlap
UNIT = (0.0, 0.0, 1.0, 1.0)
OVERLAP_CASES = [
    (UNIT, (0.5, 0.5, 2.0, 2.0), True),  # corner over corner
    (UNIT, UNIT, True),  # the same box
    (UNIT, (1.0, 0.0, 2.0, 1.0), False),  # touching at x = 1 from the right: no area in common
    ((1.0, 0.0, 2.0, 1.0), UNIT, False),  # the same, the other way round
    (UNIT, (0.0, 1.0, 1.0, 2.0), False),  # touching at y = 1 from above
    ((0.0, 1.0, 1.0, 2.0), UNIT, False),  # the same, the other way round
    ((5.0, 0.0, 6.0, 1.0), UNIT, False),  # far right, low y: only a's x0 (5) > b's x1 (1) separates them
    ((5.0, 0.0, 6.0, 1.0), (0.0, 0.0, 1.0, 10.0), False),  # far right of a tall box (b's y1 = 10 > a's x0)
    (UNIT, (5.0, 0.0, 6.0, 1.0), False),  # far left: only b's x0 (5) > a's x1 (1) separates them
    ((0.0, 0.0, 1.0, 10.0), (5.0, 0.0, 6.0, 1.0), False),  # a tall box far left of b (a's y1 = 10 > b's x0)
    ((0.0, 5.0, 1.0, 6.0), (0.0, 0.0, 1.0, 2.0), False),  # high above: only a's y0 (5) > b's y1 (2) separates
]


@pytest.mark.parametrize(("a", "b", "expected"), OVERLAP_CASES)
def test_boxes_overlap_only_where_they_share_area(a, b, expected):
    assert sampling._overlap(a, b) is expected


def test_boxes_overlap_exactly_when_both_intervals_overlap_on_a_grid():
    # every pair of boxes with corners on a 4 x 4 grid (touching edges included) against the interval rule
    corners = [(x0, y0, x1, y1) for x0, x1 in itertools.combinations(range(4), 2) for y0, y1 in itertools.combinations(range(4), 2)]  # fmt: skip
    for a, b in itertools.product(corners, repeat=2):
        expected = max(a[0], b[0]) < min(a[2], b[2]) and max(a[1], b[1]) < min(a[3], b[3])
        assert sampling._overlap(a, b) == expected, (a, b)


def test_a_distractor_shifted_to_held_out_files_avoids_the_family_of_an_object_inherited_from_training(tmp_path):
    # the look-alike rule across splits: an object shape drawn from the training side of a shape folder keeps
    # its family (its top-level subfolder) when a shift draws distractors from the held-out side. Before the
    # pool knew its folder, the inherited object's family was its own file name and 17 of 30 shifted
    # environments held a distractor of the object's family
    options = _two_shape_families(tmp_path)
    base = sampling.sample_configs("pick-place", 5, seed=0, factors=["object_shape"], options=options)
    objects = {_folder_family(c.factors.object_shape) for c in base}
    assert objects <= {"crab", "moth"} and objects  # the objects come from the folder
    for split in ("train", "eval"):
        shifted = sampling.shift_configs(base, "distractors", 30, split=split, options=options)
        for config in shifted:
            object_family = _folder_family(config.factors.object_shape)
            shown = {_folder_family(d.shape) for d in config.factors.distractors}
            assert object_family not in shown, (split, config.factors.object_shape, shown)
